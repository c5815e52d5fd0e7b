#include "haptic/softhand/block_sparse.hpp"

#include <algorithm>

namespace haptic::softhand {

void BlockPattern::build(int block_rows, std::vector<std::pair<int, int>> blocks) {
    for (int r = 0; r < block_rows; ++r) {
        blocks.emplace_back(r, r);
    }
    std::sort(blocks.begin(), blocks.end());
    blocks.erase(std::unique(blocks.begin(), blocks.end()), blocks.end());
    block_rows_ = block_rows;
    ++generation_;
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
    using Block = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>;
    y.resize(3 * static_cast<Eigen::Index>(block_rows_));
    for (int r = 0; r < block_rows_; ++r) {
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (int k = row_start_[r]; k < row_start_[r + 1]; ++k) {
            sum.noalias() += Block(values.data() + 9 * k) * x.segment<3>(3 * columns_[k]);
        }
        y.segment<3>(3 * r) = sum;
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
