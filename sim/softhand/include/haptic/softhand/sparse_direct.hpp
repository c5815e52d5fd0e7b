#pragma once

// The Newton system solved by a sparse direct factorisation (Eigen's SimplicialLDLT) instead
// of the capped PCG: exact to roundoff whatever the conditioning, at the price of a
// factorisation per Newton iteration. The symbolic analysis (fill-reducing ordering) is kept
// while the block pattern's generation is unchanged, so a step pays only the numeric
// factorisation. Pinned DoFs get an identity row and column, as in solvePcg.

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

#include "haptic/softhand/block_sparse.hpp"

namespace haptic::softhand {

class SparseDirectSolver {
  public:
    SparseDirectSolver() = default;
    // The factorisation is a cache of the last system: a copy starts without one (Eigen's
    // solvers cannot be copied or moved, so it is held by pointer).
    SparseDirectSolver(const SparseDirectSolver&) {}
    SparseDirectSolver& operator=(const SparseDirectSolver& other) {
        if (this != &other) {
            ldlt_.reset();
            analysed_generation_ = -1;
        }
        return *this;
    }
    SparseDirectSolver(SparseDirectSolver&&) noexcept = default;
    SparseDirectSolver& operator=(SparseDirectSolver&&) noexcept = default;
    ~SparseDirectSolver() = default;

    // Solves A x = b on the free DoFs (x = 0 on pinned ones); A is `values` on `pattern`.
    // False when the factorisation fails (A not positive definite to roundoff), x untouched.
    bool solve(const BlockPattern& pattern, const std::vector<double>& values,
               const Eigen::VectorXd& b, const std::vector<char>& free_mask, Eigen::VectorXd& x);

  private:
    // The lower triangle's structure, each block entry's place in it, and the ordering.
    void analyse(const BlockPattern& pattern);
    void assemble(const BlockPattern& pattern, const std::vector<double>& values,
                  const std::vector<char>& free_mask);

    Eigen::SparseMatrix<double> lower_;  // the lower triangle, pattern fixed per generation
    // Per block of the pattern, 9 entries (row-major): the index into lower_'s values, -1 for
    // an entry above the diagonal.
    std::vector<int> slots_;
    using Factorisation = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower>;
    std::unique_ptr<Factorisation> ldlt_;
    int analysed_generation_{-1};
    Eigen::VectorXd masked_b_;
    Eigen::VectorXd solution_;
};

}  // namespace haptic::softhand
