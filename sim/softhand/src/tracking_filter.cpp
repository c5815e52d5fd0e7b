#include "haptic/softhand/tracking_filter.hpp"

#include <cmath>
#include <numbers>

namespace haptic::softhand {
namespace {

// The exponential smoothing factor of a first-order low-pass at cutoff_hz sampled every dt_s.
double smoothing(double cutoff_hz, double dt_s) {
    const double tau_s = 1.0 / (2.0 * std::numbers::pi * cutoff_hz);
    return 1.0 / (1.0 + tau_s / dt_s);
}

}  // namespace

double OneEuroFilter::filter(double value, double dt_s) {
    if (!initialised_) {
        initialised_ = true;
        value_ = value;
        derivative_ = 0.0;
        return value;
    }
    const double raw_derivative = (value - value_) / dt_s;
    derivative_ +=
        smoothing(parameters_.derivative_cutoff_hz, dt_s) * (raw_derivative - derivative_);
    const double cutoff_hz = parameters_.min_cutoff_hz + parameters_.beta * std::abs(derivative_);
    value_ += smoothing(cutoff_hz, dt_s) * (value - value_);
    return value_;
}

HandPoseFilter::HandPoseFilter(const TrackingFilterSettings& settings)
    : orientation_(settings.angles) {
    for (auto& filter : angles_) {
        filter.setParameters(settings.angles.value_or(OneEuroParameters{}));
    }
    for (auto& filter : position_) {
        filter.setParameters(settings.position);
    }
}

void HandPoseFilter::reset() {
    for (auto& filter : angles_) {
        filter.reset();
    }
    for (auto& filter : position_) {
        filter.reset();
    }
    last_t_s_.reset();
}

HandPoseInput HandPoseFilter::filter(const HandPoseInput& sample, double t_s, double gap_s) {
    const Eigen::Quaterniond orientation(sample.wrist.rotation);
    if (!last_t_s_ || t_s <= *last_t_s_ || t_s - *last_t_s_ > gap_s) {
        reset();
        last_t_s_ = t_s;
        angular_velocity_.setZero();
        last_orientation_ = orientation.normalized();
        for (std::size_t i = 0; i < angles_.size(); ++i) {
            (void)angles_[i].filter(sample.flexion_rad[i], 1.0);
        }
        for (int axis = 0; axis < 3; ++axis) {
            (void)position_[static_cast<std::size_t>(axis)].filter(sample.wrist.position_m[axis],
                                                                   1.0);
        }
        return sample;
    }
    const double dt_s = t_s - *last_t_s_;
    last_t_s_ = t_s;
    HandPoseInput out = sample;
    for (int axis = 0; axis < 3; ++axis) {
        out.wrist.position_m[axis] =
            position_[static_cast<std::size_t>(axis)].filter(sample.wrist.position_m[axis], dt_s);
    }
    if (!orientation_) {
        return out;
    }
    for (std::size_t i = 0; i < angles_.size(); ++i) {
        out.flexion_rad[i] = angles_[i].filter(sample.flexion_rad[i], dt_s);
    }
    // The orientation as one channel: the rotation from the last filtered orientation to the
    // sample, per second, low-passed as a vector (so that a tracker's jitter averages out, as
    // a signed derivative does), sets the cutoff by its length.
    const Eigen::AngleAxisd step(last_orientation_.conjugate() * orientation);
    const Vec3 rate = step.axis() * (step.angle() / dt_s);
    angular_velocity_ +=
        smoothing(orientation_->derivative_cutoff_hz, dt_s) * (rate - angular_velocity_);
    const double cutoff_hz =
        orientation_->min_cutoff_hz + orientation_->beta * angular_velocity_.norm();
    last_orientation_ =
        last_orientation_.slerp(smoothing(cutoff_hz, dt_s), orientation).normalized();
    out.wrist.rotation = last_orientation_.toRotationMatrix();
    return out;
}

}  // namespace haptic::softhand
