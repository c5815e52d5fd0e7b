#include "haptic/softhand/sparse_direct.hpp"

#include <algorithm>

namespace haptic::softhand {

void SparseDirectSolver::analyse(const BlockPattern& pattern) {
    const int n = 3 * pattern.blockRows();
    std::vector<Eigen::Triplet<double>> triplets;
    for (int row = 0; row < pattern.blockRows(); ++row) {
        for (int block = pattern.rowBegin(row); block < pattern.rowEnd(row); ++block) {
            const int col = pattern.column(block);
            for (int i = 0; i < 3; ++i) {
                for (int j = 0; j < 3; ++j) {
                    if (3 * col + j <= 3 * row + i) {
                        triplets.emplace_back(3 * row + i, 3 * col + j, 0.0);
                    }
                }
            }
        }
    }
    lower_.resize(n, n);
    lower_.setFromTriplets(triplets.begin(), triplets.end());
    lower_.makeCompressed();
    // Where each entry of each block lands in the compressed lower triangle, so that a step
    // only writes values: the triplets' sort and allocation were paid per solve before.
    slots_.assign(9 * static_cast<std::size_t>(pattern.blockCount()), -1);
    for (int row = 0; row < pattern.blockRows(); ++row) {
        for (int block = pattern.rowBegin(row); block < pattern.rowEnd(row); ++block) {
            const int col = pattern.column(block);
            for (int i = 0; i < 3; ++i) {
                for (int j = 0; j < 3; ++j) {
                    const int r = 3 * row + i;
                    const int c = 3 * col + j;
                    if (c > r) {
                        continue;  // the symmetric upper entry
                    }
                    const int* first = lower_.innerIndexPtr() + lower_.outerIndexPtr()[c];
                    const int* last = lower_.innerIndexPtr() + lower_.outerIndexPtr()[c + 1];
                    const int* at = std::lower_bound(first, last, r);
                    slots_[9 * static_cast<std::size_t>(block) + 3 * i + j] =
                        static_cast<int>(at - lower_.innerIndexPtr());
                }
            }
        }
    }
    if (!ldlt_) {
        ldlt_ = std::make_unique<Factorisation>();
    }
    ldlt_->analyzePattern(lower_);
    analysed_generation_ = pattern.generation();
}

void SparseDirectSolver::assemble(const BlockPattern& pattern, const std::vector<double>& values,
                                  const std::vector<char>& free_mask) {
    double* out = lower_.valuePtr();
    for (int row = 0; row < pattern.blockRows(); ++row) {
        for (int block = pattern.rowBegin(row); block < pattern.rowEnd(row); ++block) {
            const int col = pattern.column(block);
            if (col > row) {
                continue;  // upper triangle: every slot of the block is -1
            }
            const double* v = values.data() + 9 * static_cast<std::size_t>(block);
            const int* slot = slots_.data() + 9 * static_cast<std::size_t>(block);
            for (int i = 0; i < 3; ++i) {
                const int r = 3 * row + i;
                for (int j = 0; j < 3; ++j) {
                    if (slot[3 * i + j] < 0) {
                        continue;
                    }
                    const int c = 3 * col + j;
                    const bool free_entry = free_mask[static_cast<std::size_t>(r)] != 0 &&
                                            free_mask[static_cast<std::size_t>(c)] != 0;
                    // Pinned: identity; the zero stays an entry so the pattern does not change
                    // with the pinning and the symbolic analysis stays valid.
                    out[slot[3 * i + j]] = free_entry ? v[3 * i + j] : (r == c ? 1.0 : 0.0);
                }
            }
        }
    }
}

bool SparseDirectSolver::solve(const BlockPattern& pattern, const std::vector<double>& values,
                               const Eigen::VectorXd& b, const std::vector<char>& free_mask,
                               Eigen::VectorXd& x) {
    if (!ldlt_ || analysed_generation_ != pattern.generation() ||
        lower_.rows() != 3 * pattern.blockRows() ||
        slots_.size() != 9 * static_cast<std::size_t>(pattern.blockCount())) {
        analyse(pattern);
    }
    assemble(pattern, values, free_mask);
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
    solution_ = ldlt_->solve(masked_b_);
    if (ldlt_->info() != Eigen::Success || !solution_.allFinite()) {
        return false;
    }
    x = solution_;
    return true;
}

}  // namespace haptic::softhand
