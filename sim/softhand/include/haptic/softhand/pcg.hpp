#pragma once

// Preconditioned conjugate gradient with a block-Jacobi preconditioner (3x3 node blocks, 6x6
// body blocks) and Dirichlet filtering (Baraff-Witkin style): pinned DoFs stay at zero.
// Eigen's ConjugateGradient has no filter and no per-call report of the cap being hit, which
// the solver report needs, so the iteration is written out here on Eigen's sparse types.

#include <Eigen/Core>
#include <Eigen/Sparse>
#include <utility>
#include <vector>

namespace haptic::softhand {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

struct PcgResult {
    int iterations{0};
    double relative_residual{0.0};
    bool converged{false};
};

class BlockJacobiPreconditioner {
  public:
    // blocks: (first dof, size) covering every DoF once; free_mask: 1 = unknown, 0 = pinned.
    void compute(const SparseMatrix& a, const std::vector<std::pair<int, int>>& blocks,
                 const std::vector<char>& free_mask);
    void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const;

  private:
    std::vector<std::pair<int, int>> blocks_;
    std::vector<Eigen::MatrixXd> inverses_;
};

// Solves a x = b on the free DoFs, starting from x (warm start).
PcgResult solvePcg(const SparseMatrix& a, const Eigen::VectorXd& b,
                   const std::vector<char>& free_mask, const BlockJacobiPreconditioner& pre,
                   int max_iterations, double relative_tolerance, Eigen::VectorXd& x);

}  // namespace haptic::softhand
