#pragma once

// The thimble's safety limits (the device file's `safety:` block), enforced on the plate pose
// hapticd sends, whatever the optimiser chose (docs/tactile.md, "Pad safety"):
//   - max_force_n: the force the pad model predicts for the plate stays at or below it;
//   - max_force_rate_n_per_s: that force rises at most this fast (it may always fall: a
//     release is the safe direction);
//   - max_velocity_m_per_s: no point of the plate (its centre and four rim points) approaches
//     the finger along the plate normal faster than this (it may always withdraw).
// The pad model is the one the contact surface carries: its samples are the undeformed pad in
// the device frame and each weight is its patch's stiffness (N/m: area times the pad's
// stiffness per area, or the sim's contact secant where that is stiffer, never less); a sample
// the plate passes by delta presses back with w delta, faded out over the plate's rim as in the
// optimiser. A linear pad. The
// weights come from the sim, so the device file sets a floor on their total
// (safety.min_pad_stiffness_n_per_m): a pad model softer than that is stiffened to it.
//
// Rate and speed are judged against the reference: the pose last sent (commanded()). Each
// tick, limit() searches the line from the retract pose (gain 0) to the caller's pose (its
// gain) for the largest gain whose pose keeps all three limits, by bisection (kBisections
// steps) from last tick's gain when that still keeps them, otherwise from the retract pose;
// allows() judges any other pose, e.g. the one a servo rate limit actually sends.
// noexcept, allocation-free, bounded: it runs on the 1 kHz path.

#include <cstdint>

#include "haptic/config/device.hpp"
#include "haptic/msgs/messages.hpp"
#include "haptic/tactile/thimble_kinematics.hpp"

namespace haptic::tactile {

// Share of a pad patch at in-plane distance sqrt(in_plane_radius_sq_m2) from the plate centre
// that the plate presses: 1 inside, a smoothstep to 0 over `rim_blend_m` at the rim.
[[nodiscard]] double plateRimWeight(double in_plane_radius_sq_m2, double plate_radius_m,
                                    double rim_blend_m) noexcept;

// The net force (N, along the plate normal) the pad model predicts for the plate at `pose`.
// A surface whose weights sum to less than `min_total_weight_n_per_m` is judged as if each
// were scaled up to that total (safety.min_pad_stiffness_n_per_m).
[[nodiscard]] double padForceN(const PlatformPose& pose, const msgs::ContactSurface& surface,
                               double plate_radius_m, double rim_blend_m,
                               double min_total_weight_n_per_m = 0.0) noexcept;

struct PadSafetySettings {
    double max_force_n{1.5};
    double max_force_rate_n_per_s{100.0};
    double max_approach_speed_m_per_s{0.1};
    double period_s{1e-3};
    double plate_radius_m{0.008};
    double rim_blend_m{0.001};              // as the optimiser's
    double min_pad_stiffness_n_per_m{0.0};  // floor of the surface's total weight

    [[nodiscard]] static PadSafetySettings fromConfig(const config::DeviceConfig& device,
                                                      double period_s);
};

// Which limit held the plate back this tick (bits of PadLimit::flags).
enum class PadFlag : std::uint8_t {
    kForce = 1U << 0U,
    kForceRate = 1U << 1U,
    kApproachSpeed = 1U << 2U,
    // The servos' own step (each servo rate-limited on its own, off the judged line) broke a
    // limit and was shortened.
    kServoStep = 1U << 3U,
};

struct PadLimit {
    double gain{0.0};
    double pad_force_n{0.0};  // the pad model's force at the returned gain
    std::uint8_t flags{0};    // PadFlag bits: what lowered the gain
    PlatformPose pose{};      // the pose at the returned gain
    bool has_pose{false};     // false only when not even the retract pose had one
};

class PadSafetyLimiter {
  public:
    // Resolution 1/65536 of the searched interval: on the shipped stroke (8 mm) 0.12 um, so
    // even a pad of 45 kN/m rises by about 5.5 mN per step, below a 0.02 N per tick rate limit.
    static constexpr int kBisections = 16;

    explicit PadSafetyLimiter(const PadSafetySettings& settings) noexcept : settings_(settings) {}

    // `pose_at(gain, pose)` writes the platform pose at that gain of the blend and returns
    // false when it has none (treated as beyond the limits; gain 0, the retract pose, is
    // always taken). `surface` may be null (no pad known: no force).
    template <class PoseAt>
    [[nodiscard]] PadLimit limit(double gain, const msgs::ContactSurface* surface,
                                 PoseAt&& pose_at) noexcept {
        PadLimit result;
        PlatformPose pose;
        if (gain > 0.0 && pose_at(gain, pose)) {
            const std::uint8_t violated = allows(pose, surface, result.pad_force_n);
            if (violated == 0) {
                result.gain = gain;
                return found(result, pose);
            }
            result.flags = violated;
        }
        // Bisection on [low, gain], `low` keeping the limits: last tick's gain when it still
        // does (so a stiff pad's force can creep up by less than one step of [0, gain]),
        // otherwise 0, the retract pose.
        double low = 0.0;
        double high = gain;
        PlatformPose low_pose;
        double low_force = 0.0;
        const double resume = previous_gain_ < gain ? previous_gain_ : 0.0;
        if (resume > 0.0 && pose_at(resume, low_pose) &&
            allows(low_pose, surface, low_force) == 0) {
            low = resume;
        }
        const bool has_low = low > 0.0 || pose_at(0.0, low_pose);
        if (low == 0.0) {
            low_force = has_low ? modelForceN(low_pose, surface) : 0.0;
        }
        for (int i = 0; i < kBisections && gain > 0.0; ++i) {
            const double mid = 0.5 * (low + high);
            double force = 0.0;
            if (pose_at(mid, pose) && allows(pose, surface, force) == 0) {
                low = mid;
                low_pose = pose;
                low_force = force;
            } else {
                high = mid;
            }
        }
        result.gain = low;
        result.pad_force_n = low_force;
        if (!has_low) {
            previous_gain_ = 0.0;
            return result;
        }
        return found(result, low_pose);
    }

    // The servo step actually sent: the servos are rate-limited each on its own, so the angles
    // sent leave the line limit() judged, and may have no plate pose at all.
    struct ServoStep {
        ServoAngles servo_rad{};
        ForwardResult forward{};  // of servo_rad; not ok(): no pose known for it
        bool shortened{false};    // cut back from the step asked, or held where it was
    };

    // Judges the step from `previous` (the angles sent last tick, themselves judged) to `step`.
    // `forward(angles, result)` fills the forward kinematics of servo angles (result.ok()
    // false: none). `retracting`: the step heads for the retract pose (limit() chose gain 0:
    // FAULT, a disable, a stale device, or no other pose keeps the limits); it is sent as it is,
    // since the retract is always allowed and nothing may hold it up. Otherwise a step whose
    // pose keeps the limits is sent whole, else the longest fraction of it whose pose is known
    // and keeps them, by bisection (kBisections). When no fraction does:
    //  - a step whose pose is known and whose pad force rises by at most the rate limit over
    //    `previous` goes on whole: the finger itself pushed into the plate, so that even the
    //    previous angles break a limit now, and the servos move towards the pose limit()
    //    chose, which keeps them (limit() lowers its gain each tick until it reaches the
    //    retract);
    //  - a step that would press harder than that, or has no known pose, is not sent (fail
    //    closed: a pose that cannot be judged may press anywhere): the servos hold at
    //    `previous`.
    template <class Forward>
    [[nodiscard]] ServoStep judgeStep(const ServoAngles& previous, const ServoAngles& step,
                                      const msgs::ContactSurface* surface, bool retracting,
                                      Forward&& forward) const noexcept {
        ServoStep result{step, {}, false};
        forward(step, result.forward);
        if (retracting) {
            return result;
        }
        double force_n = 0.0;
        if (result.forward.ok() && allows(result.forward.pose, surface, force_n) == 0) {
            return result;
        }
        double low = 0.0;
        double high = 1.0;
        ForwardResult fraction;
        for (int i = 0; i < kBisections; ++i) {
            const double mid = 0.5 * (low + high);
            ServoAngles angles;
            for (std::size_t k = 0; k < angles.size(); ++k) {
                angles[k] = previous[k] + mid * (step[k] - previous[k]);
            }
            forward(angles, fraction);
            if (fraction.ok() && allows(fraction.pose, surface, force_n) == 0) {
                low = mid;
                result.servo_rad = angles;
                result.forward = fraction;
                result.shortened = true;
            } else {
                high = mid;
            }
        }
        if (!result.shortened) {
            ForwardResult at_previous;
            forward(previous, at_previous);
            if (!result.forward.ok() || !at_previous.ok() ||
                !(modelForceN(result.forward.pose, surface) <=
                  modelForceN(at_previous.pose, surface) +
                      settings_.max_force_rate_n_per_s * settings_.period_s)) {
                result.servo_rad = previous;
                result.forward = at_previous;
                result.shortened = true;
            }
        }
        return result;
    }

    // Which limits `pose` would break against the reference (PadFlag bits, 0: none); `force_n`
    // gets the pad model's force there.
    [[nodiscard]] std::uint8_t allows(const PlatformPose& pose, const msgs::ContactSurface* surface,
                                      double& force_n) const noexcept;

    // The pose the servos were actually sent (the forward kinematics of their targets): the
    // reference for the next tick's rate and speed limits. Returns the pad model's force.
    double commanded(const PlatformPose& pose, const msgs::ContactSurface* surface) noexcept {
        previous_pose_ = pose;
        previous_force_n_ = modelForceN(pose, surface);
        has_previous_ = true;
        return previous_force_n_;
    }

    [[nodiscard]] const PadSafetySettings& settings() const noexcept { return settings_; }

  private:
    // The pad model's force for the plate at `pose` (0 with no surface), with the settings' plate
    // and the floor under the model's stiffness.
    [[nodiscard]] double modelForceN(const PlatformPose& pose,
                                     const msgs::ContactSurface* surface) const noexcept {
        return surface == nullptr
                   ? 0.0
                   : padForceN(pose, *surface, settings_.plate_radius_m, settings_.rim_blend_m,
                               settings_.min_pad_stiffness_n_per_m);
    }

    PadLimit found(PadLimit result, const PlatformPose& pose) noexcept {
        previous_gain_ = result.gain;
        result.pose = pose;
        result.has_pose = true;
        return result;
    }

    PadSafetySettings settings_;
    PlatformPose previous_pose_{};
    double previous_force_n_{0.0};
    double previous_gain_{0.0};
    bool has_previous_{false};
};

}  // namespace haptic::tactile
