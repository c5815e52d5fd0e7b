#pragma once

// The One Euro filter (Casiez, Roussel and Vogel, "1€ Filter: A Simple Speed-based Low-pass
// Filter for Noisy Input in Interactive Systems", CHI 2012) on tracked hand poses. A first-
// order low-pass whose cutoff rises with the filtered speed: at rest it removes a tracker's
// jitter, which would otherwise move the simulated contact, the device constraints and the
// reference force every frame; in motion it lags little. Per channel:
//   cutoff = min_cutoff + beta * |dx/dt|,  alpha = 1 / (1 + 1 / (2 pi cutoff dt))
// with dx/dt itself low-passed at derivative_cutoff. Each wrist position axis is a channel;
// with angle parameters, so is each of the 15 flexion angles, and the wrist orientation is
// slerped by the alpha of its low-passed angular velocity. docs/softhand.md, "Tracking filter".

#include <Eigen/Geometry>
#include <array>
#include <optional>

#include "haptic/softhand/tracking_input.hpp"

namespace haptic::softhand {

struct OneEuroParameters {
    double min_cutoff_hz{1.0};
    double beta{0.0};  // per unit of speed (s/rad for angles, s/m for positions)
    double derivative_cutoff_hz{1.0};
};

class OneEuroFilter {
  public:
    OneEuroFilter() = default;
    explicit OneEuroFilter(OneEuroParameters parameters) : parameters_(parameters) {}

    // The filtered value of a sample taken dt_s after the previous one. The first sample
    // (and the first after reset()) passes unchanged.
    double filter(double value, double dt_s);
    void reset() { initialised_ = false; }
    void setParameters(const OneEuroParameters& parameters) { parameters_ = parameters; }

  private:
    OneEuroParameters parameters_{};
    bool initialised_{false};
    double value_{0.0};
    double derivative_{0.0};
};

struct TrackingFilterSettings {
    // The 15 flexion angles, beta in s/rad; absent: they pass unfiltered, and so does the
    // wrist orientation, which uses the angles' parameters on its angular speed.
    std::optional<OneEuroParameters> angles{OneEuroParameters{}};
    OneEuroParameters position{};  // the wrist position, beta in s/m
};

class HandPoseFilter {
  public:
    explicit HandPoseFilter(const TrackingFilterSettings& settings);

    // The filtered pose of a tracker sample stamped t_s. A sample not after the previous one,
    // or more than `gap_s` after it, restarts the filter there (it passes unchanged).
    HandPoseInput filter(const HandPoseInput& sample, double t_s, double gap_s);
    void reset();

  private:
    std::array<OneEuroFilter, kHandPoseAngles> angles_;
    std::array<OneEuroFilter, 3> position_;
    std::optional<OneEuroParameters> orientation_;  // absent: angles and orientation pass
    Vec3 angular_velocity_{Vec3::Zero()};           // low-passed, of the wrist orientation (rad/s)
    std::optional<double> last_t_s_;
    Eigen::Quaterniond last_orientation_{Eigen::Quaterniond::Identity()};
};

}  // namespace haptic::softhand
