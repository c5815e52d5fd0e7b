#pragma once

// Preconditioned conjugate gradient with a block-Jacobi preconditioner (3x3 node blocks, 6x6
// body blocks) and Dirichlet filtering (Baraff-Witkin style): pinned DoFs stay at zero.
// Eigen's ConjugateGradient has no filter and no per-call report of the cap being hit, which
// the solver report needs, so the iteration is written out here, on the 3x3-block matrix of
// block_sparse.hpp, with every vector in a workspace that is sized once.

#include <Eigen/Core>
#include <atomic>
#include <vector>

#include "haptic/softhand/block_sparse.hpp"

namespace haptic::softhand {

struct PcgResult {
    int iterations{0};
    double relative_residual{0.0};
    bool converged{false};
};

class BlockJacobiPreconditioner {
  public:
    using Mat6 = Eigen::Matrix<double, 6, 6>;
    // The first `node_count` block rows are nodes (3x3 blocks); each body then spans two
    // block rows (linear, angular), inverted together as one 6x6 block. free_mask: 1 =
    // unknown, 0 = pinned (its row and column are replaced by the identity).
    void compute(const BlockPattern& pattern, const std::vector<double>& values, int node_count,
                 const std::vector<char>& free_mask);
    void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const;

  private:
    std::vector<Eigen::Matrix3d> node_inverses_;
    std::vector<Mat6> body_inverses_;
};

struct PcgWorkspace {
    Eigen::VectorXd mask, r, z, p, ap, best;
    void resize(Eigen::Index n);
};

// Solves A x = b on the free DoFs, starting from x (warm start); A is `values` on `pattern`.
// `stop`, when given and set, ends the iterations early (a cold solve not needed, time_step.cpp): x
// is then whatever iterate it had.
PcgResult solvePcg(const BlockPattern& pattern, const std::vector<double>& values,
                   const Eigen::VectorXd& b, const std::vector<char>& free_mask,
                   const BlockJacobiPreconditioner& pre, int max_iterations,
                   double relative_tolerance, Eigen::VectorXd& x, PcgWorkspace& work,
                   const std::atomic<bool>* stop = nullptr);

}  // namespace haptic::softhand
