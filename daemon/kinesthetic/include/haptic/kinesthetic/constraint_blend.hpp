#pragma once

// First-order hold of the sim's constraints between its frames. The sim publishes at 60-200 Hz
// and hapticd renders at 1 kHz; a constraint that moves by a little from one frame to the next
// (the tracker's noise, the soft finger settling) would step the force at the sim's rate, which
// the finger feels as a buzz. So a constraint set that keeps its structure (the same number of
// constraints, each normal within kSameNormalCosine of its predecessor, each contact on the same
// joints) is approached linearly,
// from what was rendered when it arrived, over the interval at which frames have been arriving.
// A set that changes structure (a contact appears or goes) is rendered at once: a new contact is
// never delayed. The cost is up to one sim frame of extra latency on a contact that moves.
// A row's contact (msgs::ContactKinematics: gap, normal, axes, levers, reference angles) is
// blended with it; the interpolated normal and axes are normalised where they are used
// (contact_gap.hpp).
//
// RT: noexcept, no allocation, O(number of constraints) per tick.

#include <span>

#include "haptic/msgs/messages.hpp"

namespace haptic::kinesthetic {

class ConstraintBlend {
  public:
    using Constraints = msgs::BoundedArray<msgs::LinearConstraint, msgs::kMaxConstraints>;

    // Normals closer than this (cosine) are the same contact moving.
    static constexpr double kSameNormalCosine = 0.9;
    // The ramp never lasts longer than this, whatever the arrivals suggest.
    static constexpr int kMaxRampTicks = 50;

    // Once per tick with the newest constraints (unchanged between frames); returns those to
    // render this tick, valid until the next call.
    std::span<const msgs::LinearConstraint> update(
        std::span<const msgs::LinearConstraint> newest) noexcept;
    // Forget the ramp: the next constraints are rendered as they come.
    void reset() noexcept;

    // Ticks over which a changed set is approached (the mean interval between new sets).
    [[nodiscard]] int rampTicks() const noexcept { return ramp_ticks_; }

  private:
    [[nodiscard]] bool sameStructure(std::span<const msgs::LinearConstraint> newest) const noexcept;

    Constraints target_{};
    Constraints from_{};
    Constraints blended_{};
    bool has_target_{false};
    int ticks_since_arrival_{0};
    double mean_interval_ticks_{0.0};  // 0 until two sets have arrived
    int ramp_ticks_{1};
    int ramp_step_{0};
};

}  // namespace haptic::kinesthetic
