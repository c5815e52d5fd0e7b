#pragma once

// K-metric projection (docs/algorithms.md §1.4, §6.5, §6.7):
//
//   y* = argmin_y 1/2 (y - y0)^T K (y - y0)   s.t.   c_j^T y >= d_j,  j = 1..N
//
// solved in its dual, min_{lambda >= 0} 1/2 lambda^T Q lambda - h^T lambda with
// Q = C^T K^-1 C and h = d - C^T y0, so that y = y0 + K^-1 C lambda. The dual is a bound-
// constrained QP; it is solved with a Lawson-Hanson active-set loop, plus the Goldfarb-Idnani
// swap for a violated constraint that is linearly dependent on the active ones (corners with
// more constraints than dimensions). The active set of the previous tick warm-starts it, so a
// resting contact costs one factorisation. Every loop is bounded by max_iterations; running
// out is reported, never thrown, and the returned point is the last iterate (finite, dual
// feasible).

#include <array>
#include <cstdint>

#include "haptic/kinesthetic/types.hpp"

namespace haptic::kinesthetic {

enum class SolveStatus : std::uint8_t {
    kOptimal,         // KKT conditions met to tolerance
    kIterationLimit,  // ran out of iterations; y is the last (partial) iterate
    kInfeasible,      // constraints contradict each other (or a zero normal with d > 0)
    kInvalidInput,    // NaN/Inf, K not SPD, sizes wrong; y = y0
};

[[nodiscard]] const char* toString(SolveStatus status) noexcept;

struct ActiveSet {
    std::array<std::int16_t, kMaxDofs> index{};
    int size{0};
    [[nodiscard]] bool contains(int j) const noexcept;
};

struct ProjectionResult {
    SolveStatus status{SolveStatus::kInvalidInput};
    int iterations{0};
    ActiveSet active;
    double max_violation{0.0};  // largest (d_j - c_j^T y) / |c_j| of the returned y, >= 0
};

class KMetricProjector {
  public:
    static constexpr int kDefaultMaxIterations = 16;
    explicit KMetricProjector(int max_iterations = kDefaultMaxIterations) noexcept;

    // C: n x N (one constraint normal per column), d: N. y is resized to n.
    ProjectionResult project(const ConfigMatrix& K, const ConfigVector& y0,
                             const ConstraintMatrix& C, const ConstraintVector& d,
                             const ActiveSet& warm_start, ConfigVector& y) noexcept;

    [[nodiscard]] int maxIterations() const noexcept { return max_iterations_; }

  private:
    int max_iterations_;
};

}  // namespace haptic::kinesthetic
