#pragma once

// Internal: the potential energy terms of docs/algorithms.md §2.4, each able to return its energy
// alone (energy check) or also add its gradient and Gauss-Newton Hessian (Newton step).

#include <array>
#include <span>
#include <vector>

#include "haptic/softhand/block_sparse.hpp"
#include "haptic/softhand/simulation.hpp"

namespace haptic::softhand {

// Gradient and PSD Hessian blocks of the potential over the stacked DoFs: 3 per node, then
// 6 per body (linear, angular). Blocks go straight into the values of a pattern kept between
// steps; a block the pattern lacks (a contact that couples a node to a new body) is listed in
// `missing`, and the caller grows the pattern and assembles again.
class Assembler {
  public:
    // `keep_tissue_part` false leaves `tissue_hessian` alone: only the step's first
    // linearisation needs it (Rayleigh damping is frozen there for the whole step).
    Assembler(const BlockPattern& pattern, std::vector<double>& hessian,
              std::vector<double>& tissue_hessian, Eigen::VectorXd& gradient,
              std::vector<std::pair<int, int>>& missing, bool keep_tissue_part = true)
        : gradient(gradient),
          pattern_(pattern),
          hessian_(hessian),
          tissue_hessian_(tissue_hessian),
          missing_(missing),
          keep_tissue_part_(keep_tissue_part) {
        const auto values = static_cast<std::size_t>(9 * pattern.blockCount());
        hessian_.assign(values, 0.0);
        if (keep_tissue_part_) {
            tissue_hessian_.assign(values, 0.0);
        }
        gradient.setZero(3 * static_cast<Eigen::Index>(pattern.blockRows()));
        missing_.clear();
    }

    void addBlock(int row, int col, const Mat3& block) {
        const int k = pattern_.find(row / 3, col / 3);
        if (k < 0) {
            missing_.emplace_back(row / 3, col / 3);
            return;
        }
        using RowBlock = Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>;
        RowBlock(hessian_.data() + 9 * k) += block;
        if (collecting_tissue) {
            RowBlock(tissue_hessian_.data() + 9 * k) += block;
        }
    }
    void addGradient(int dof, const Vec3& g) { gradient.segment<3>(dof) += g; }
    [[nodiscard]] bool keepsTissuePart() const { return keep_tissue_part_; }

    // Adds `block` at pattern index k, or its transpose (the mirrored block of a symmetric
    // term, so each pair is computed once).
    void addBlockAt(int k, const Mat3& block) {
        RowBlock(hessian_.data() + 9 * k) += block;
        if (collecting_tissue) {
            RowBlock(tissue_hessian_.data() + 9 * k) += block;
        }
    }
    void addTransposedBlockAt(int k, const Mat3& block) {
        RowBlock(hessian_.data() + 9 * k) += block.transpose();
        if (collecting_tissue) {
            RowBlock(tissue_hessian_.data() + 9 * k) += block.transpose();
        }
    }

    // Caches element block indices in `cache` (kept by the caller between steps) for
    // elementSlots(); without a cache every element looks its blocks up.
    void useElementBlocks(ElementBlockSlots& cache, std::size_t elements) {
        if (cache.generation != pattern_.generation() || cache.slots.size() != elements) {
            std::array<int, 16> unknown;
            unknown.fill(ElementBlockSlots::kUnknown);
            cache.slots.assign(elements, unknown);
            cache.generation = pattern_.generation();
        }
        element_blocks_ = &cache;
    }
    // The 16 block indices of element e over `nodes`, or nullptr when there is no cache or a
    // block is missing from the pattern (the caller then adds blocks one by one, and the
    // missing ones are listed for the next pattern).
    [[nodiscard]] const std::array<int, 16>* elementSlots(std::size_t e,
                                                          const std::array<int, 4>& nodes) {
        if (element_blocks_ == nullptr) {
            return nullptr;
        }
        std::array<int, 16>& slots = element_blocks_->slots[e];
        if (slots[0] == ElementBlockSlots::kUnknown) {
            for (int i = 0; i < 4; ++i) {
                for (int j = 0; j < 4; ++j) {
                    const int k = pattern_.find(nodes[i], nodes[j]);
                    if (k < 0) {
                        slots.fill(ElementBlockSlots::kUnknown);
                        return nullptr;
                    }
                    slots[4 * i + j] = k;
                }
            }
        }
        return &slots;
    }

    Eigen::VectorXd& gradient;
    // Tissue blocks are also kept apart: Rayleigh stiffness damping applies to them only.
    // Damping the contact and friction springs would turn Coulomb sliding into viscous creep.
    bool collecting_tissue{false};

  private:
    using RowBlock = Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>;

    const BlockPattern& pattern_;
    ElementBlockSlots* element_blocks_{nullptr};
    std::vector<double>& hessian_;
    std::vector<double>& tissue_hessian_;
    std::vector<std::pair<int, int>>& missing_;
    bool keep_tissue_part_;
};

// One Jacobian block d(residual)/d(dof .. dof+2).
struct JacobianBlock {
    int dof;
    Mat3 jacobian;
};

// Adds J_i^T g to the gradient and J_i^T H J_j to the Hessian for a term whose gradient and
// Hessian with respect to a 3-vector are g and H.
void addLinearizedTerm(Assembler* assembler, const Vec3& gradient, const Mat3& hessian,
                       std::span<const JacobianBlock> blocks);

// E = 1/2 e^T W e with e linearised as e + sum J_i dz_i. Returns E; adds J^T W e and J^T W J.
double addResidualTerm(Assembler* assembler, const Mat3& weight, const Vec3& residual,
                       std::span<const JacobianBlock> blocks);

struct TermStats {
    int strain_limited_elements{0};
    int inverted_elements{0};
};

struct EnergyTerms {
    using Sim = Simulation;
    static int nodeDof(int node) { return 3 * node; }
    static int bodyDof(const Sim& sim, int body) { return 3 * sim.nodeCount() + 6 * body; }

    // Co-rotational FEM plus strain-limit penalty (§2.4.2-2.4.3). With an assembler the
    // co-rotation is frozen at q for the Newton step.
    static double tissue(const Sim& sim, const Sim::Configuration& q, Assembler* assembler,
                         TermStats* stats);
    // Gravity and applied node forces.
    static double external(const Sim& sim, const Sim::Configuration& q, Assembler* assembler);
    // Bone-tissue coupling (§2.4.4), joints (§2.4.1), tracking springs (§2.3).
    static double skeleton(const Sim& sim, const Sim::Configuration& q, Assembler* assembler);
    // Normal penalty and anchored friction for the detected contacts (§2.4.6-2.4.7). Energy
    // evaluation uses the true signed distance at q, so a step that digs deeper is caught.
    static double contact(const Sim& sim, const Sim::Configuration& q, Assembler* assembler);

    static double potential(const Sim& sim, const Sim::Configuration& q, Assembler* assembler,
                            TermStats* stats) {
        return tissue(sim, q, assembler, stats) + external(sim, q, assembler) +
               skeleton(sim, q, assembler) + contact(sim, q, assembler);
    }
};

// The Jacobian blocks of one term (at most two bodies of two blocks each), without allocation.
class JacobianBlocks {
  public:
    void clear() { count_ = 0; }
    void push_back(const JacobianBlock& block) { items_[count_++] = block; }
    operator std::span<const JacobianBlock>() const { return {items_.data(), count_}; }

  private:
    std::array<JacobianBlock, 4> items_{};
    std::size_t count_{0};
};

// 3x3 Jacobian blocks of a body-fixed point with world lever arm r: [I, -[r]x] (§1.1).
inline void appendBodyPoint(JacobianBlocks& out, int body_dof, const Vec3& lever, double sign) {
    out.push_back({body_dof, sign * Mat3::Identity()});
    out.push_back({body_dof + 3, -sign * skew(lever)});
}

}  // namespace haptic::softhand
