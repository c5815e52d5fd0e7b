#include "haptic/softhand/block_sparse.hpp"

#include <algorithm>
#include <atomic>

namespace haptic::softhand {

void BlockPattern::build(int block_rows, std::vector<std::pair<int, int>> blocks) {
    for (int r = 0; r < block_rows; ++r) {
        blocks.emplace_back(r, r);
    }
    std::sort(blocks.begin(), blocks.end());
    blocks.erase(std::unique(blocks.begin(), blocks.end()), blocks.end());
    block_rows_ = block_rows;
    // Drawn from one counter for every pattern: a cache keyed on the generation (the sparse
    // direct solver's analysis) cannot take another pattern's first build for its own.
    static std::atomic<int> last_generation{0};
    generation_ = ++last_generation;
    row_start_.assign(static_cast<std::size_t>(block_rows) + 1, 0);
    columns_.clear();
    columns_.reserve(blocks.size());
    for (const auto& [row, col] : blocks) {
        ++row_start_[static_cast<std::size_t>(row) + 1];
        columns_.push_back(col);
    }
    for (int r = 0; r < block_rows; ++r) {
        row_start_[r + 1] += row_start_[r];
    }
    diagonal_.resize(static_cast<std::size_t>(block_rows));
    for (int r = 0; r < block_rows; ++r) {
        diagonal_[r] = find(r, r);
    }
}

int BlockPattern::find(int row, int col) const {
    const auto begin = columns_.begin() + row_start_[row];
    const auto end = columns_.begin() + row_start_[row + 1];
    const auto it = std::lower_bound(begin, end, col);
    return it != end && *it == col ? static_cast<int>(it - columns_.begin()) : -1;
}

void BlockPattern::multiply(const std::vector<double>& values, const Eigen::VectorXd& x,
                            Eigen::VectorXd& y) const {
    // Written out: through Eigen's mapped 3x3 blocks this product was a quarter of the soft
    // hand step, and the scalar form measured faster.
    y.resize(3 * static_cast<Eigen::Index>(block_rows_));
    const double* in = x.data();
    double* out = y.data();
    for (int r = 0; r < block_rows_; ++r) {
        double s0 = 0.0;
        double s1 = 0.0;
        double s2 = 0.0;
        for (int k = row_start_[r]; k < row_start_[r + 1]; ++k) {
            const double* b = values.data() + 9 * static_cast<std::size_t>(k);
            const double* v = in + 3 * static_cast<std::size_t>(columns_[k]);
            s0 += b[0] * v[0] + b[1] * v[1] + b[2] * v[2];
            s1 += b[3] * v[0] + b[4] * v[1] + b[5] * v[2];
            s2 += b[6] * v[0] + b[7] * v[1] + b[8] * v[2];
        }
        out[3 * r] = s0;
        out[3 * r + 1] = s1;
        out[3 * r + 2] = s2;
    }
}

void BlockPattern::appendBlocks(std::vector<std::pair<int, int>>& out) const {
    for (int r = 0; r < block_rows_; ++r) {
        for (int k = row_start_[r]; k < row_start_[r + 1]; ++k) {
            out.emplace_back(r, columns_[k]);
        }
    }
}

}  // namespace haptic::softhand
