#pragma once

// Symmetric-pattern sparse matrix of dense 3x3 blocks (block CSR). The soft hand's DoFs come
// in groups of three (node position, body linear, body angular), so every Hessian term is a
// 3x3 block: assembling into a pattern kept between steps replaces rebuilding and sorting
// scalar triplets every step, and the block product is faster than a scalar CSR product.

#include <Eigen/Core>
#include <array>
#include <utility>
#include <vector>

namespace haptic::softhand {

class BlockPattern {
  public:
    // Pattern over `block_rows` block rows with the given (row, col) blocks plus every
    // diagonal block. Duplicates are allowed.
    void build(int block_rows, std::vector<std::pair<int, int>> blocks);

    [[nodiscard]] int blockRows() const { return block_rows_; }
    [[nodiscard]] int blockCount() const { return static_cast<int>(columns_.size()); }
    // Changes on every build(), unique over all patterns: block indices looked up before it are
    // stale after it.
    [[nodiscard]] int generation() const { return generation_; }
    // Index of block (row, col), or -1 when it is not in the pattern.
    [[nodiscard]] int find(int row, int col) const;
    [[nodiscard]] int diagonal(int row) const { return diagonal_[row]; }
    [[nodiscard]] int rowBegin(int row) const { return row_start_[row]; }
    [[nodiscard]] int rowEnd(int row) const { return row_start_[row + 1]; }
    [[nodiscard]] int column(int block) const { return columns_[block]; }

    // y = A x for the block values `values` (9 per block, row-major).
    void multiply(const std::vector<double>& values, const Eigen::VectorXd& x,
                  Eigen::VectorXd& y) const;
    // Appends every block (row, col) of the pattern to `out`.
    void appendBlocks(std::vector<std::pair<int, int>>& out) const;

  private:
    int block_rows_{0};
    int generation_{0};
    std::vector<int> row_start_{0};
    std::vector<int> columns_;
    std::vector<int> diagonal_;
};

// Pattern indices of each tet's 4x4 node blocks (row-major, entry 4 i + j), looked up once
// per pattern generation: the tissue term assembles every element every step, and a binary
// search per block was a twentieth of the whole-hand step.
struct ElementBlockSlots {
    static constexpr int kUnknown = -1;
    std::vector<std::array<int, 16>> slots;
    int generation{-1};
};

}  // namespace haptic::softhand
