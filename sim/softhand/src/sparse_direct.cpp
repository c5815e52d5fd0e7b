#include "haptic/softhand/sparse_direct.hpp"

#include <utility>

namespace haptic::softhand {

void SparseDirectSolver::assemble(const BlockPattern& pattern, const std::vector<double>& values,
                                  const std::vector<char>& free_mask) {
    const int n = 3 * pattern.blockRows();
    triplets_.clear();
    for (int row = 0; row < pattern.blockRows(); ++row) {
        for (int block = pattern.rowBegin(row); block < pattern.rowEnd(row); ++block) {
            const int col = pattern.column(block);
            if (col > row) {
                continue;  // the symmetric upper block
            }
            const double* v = values.data() + 9 * static_cast<std::size_t>(block);
            for (int i = 0; i < 3; ++i) {
                const int r = 3 * row + i;
                for (int j = 0; j < 3; ++j) {
                    const int c = 3 * col + j;
                    if (c > r) {
                        continue;
                    }
                    const bool free_entry = free_mask[static_cast<std::size_t>(r)] != 0 &&
                                            free_mask[static_cast<std::size_t>(c)] != 0;
                    // Pinned: identity; the zero stays an entry so the pattern does not change
                    // with the pinning and the symbolic analysis stays valid.
                    const double value = free_entry ? v[3 * i + j] : (r == c ? 1.0 : 0.0);
                    triplets_.emplace_back(r, c, value);
                }
            }
        }
    }
    lower_.resize(n, n);
    lower_.setFromTriplets(triplets_.begin(), triplets_.end());
}

bool SparseDirectSolver::solve(const BlockPattern& pattern, const std::vector<double>& values,
                               const Eigen::VectorXd& b, const std::vector<char>& free_mask,
                               Eigen::VectorXd& x) {
    assemble(pattern, values, free_mask);
    if (!ldlt_ || analysed_generation_ != pattern.generation() || ldlt_->rows() != lower_.rows()) {
        if (!ldlt_) {
            ldlt_ = std::make_unique<Factorisation>();
        }
        ldlt_->analyzePattern(lower_);
        analysed_generation_ = pattern.generation();
    }
    ldlt_->factorize(lower_);
    if (ldlt_->info() != Eigen::Success || (ldlt_->vectorD().array() <= 0.0).any()) {
        return false;
    }
    masked_b_ = b;
    for (Eigen::Index i = 0; i < b.size(); ++i) {
        if (free_mask[static_cast<std::size_t>(i)] == 0) {
            masked_b_(i) = 0.0;
        }
    }
    Eigen::VectorXd solution = ldlt_->solve(masked_b_);
    if (ldlt_->info() != Eigen::Success || !solution.allFinite()) {
        return false;
    }
    x = std::move(solution);
    return true;
}

}  // namespace haptic::softhand
