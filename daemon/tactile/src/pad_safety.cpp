#include "haptic/tactile/pad_safety.hpp"

#include <array>
#include <cmath>

namespace haptic::tactile {

double plateRimWeight(double in_plane_radius_sq_m2, double plate_radius_m,
                      double rim_blend_m) noexcept {
    // Squared radii: most samples are well inside or outside, no square root needed.
    const double outer = plate_radius_m;
    const double inner = outer - rim_blend_m;
    if (in_plane_radius_sq_m2 <= inner * inner) {
        return 1.0;
    }
    if (in_plane_radius_sq_m2 >= outer * outer) {
        return 0.0;
    }
    const double t = (outer - std::sqrt(in_plane_radius_sq_m2)) / rim_blend_m;
    return t * t * (3.0 - 2.0 * t);  // smoothstep
}

double padForceN(const PlatformPose& pose, const msgs::ContactSurface& surface,
                 double plate_radius_m, double rim_blend_m,
                 double min_total_weight_n_per_m) noexcept {
    const Eigen::Vector3d normal = pose.plateNormal();
    double total_weight = 0.0;
    for (const msgs::ContactSample& sample : surface.samples) {
        total_weight += sample.weight > 0.0 ? sample.weight : 0.0;
    }
    // Softer in total than the floor: every patch stiffened by one factor (a pad with no
    // stiffness at all gets the floor shared evenly).
    const bool even = !(total_weight > 0.0) && min_total_weight_n_per_m > 0.0;
    const double scale = total_weight > 0.0 && total_weight < min_total_weight_n_per_m
                             ? min_total_weight_n_per_m / total_weight
                             : 1.0;
    const double even_weight =
        even ? min_total_weight_n_per_m / static_cast<double>(surface.samples.size()) : 0.0;
    double force_n = 0.0;
    for (const msgs::ContactSample& sample : surface.samples) {
        const Eigen::Vector3d rel =
            Eigen::Vector3d(sample.p_device_m[0], sample.p_device_m[1], sample.p_device_m[2]) -
            pose.position_m;
        const double d = normal.dot(rel);  // positive: the patch is still on the finger side
        const double weight = even ? even_weight : sample.weight * scale;
        if (!(d < 0.0) || !(weight > 0.0)) {
            continue;
        }
        force_n +=
            weight * -d * plateRimWeight(rel.squaredNorm() - d * d, plate_radius_m, rim_blend_m);
    }
    return force_n;
}

PadSafetySettings PadSafetySettings::fromConfig(const config::DeviceConfig& device,
                                                double period_s) {
    PadSafetySettings settings;
    settings.max_force_n = device.safety.max_force_n;
    settings.max_force_rate_n_per_s = device.safety.max_force_rate_n_per_s;
    settings.max_approach_speed_m_per_s = device.safety.max_velocity_m_per_s;
    settings.period_s = period_s;
    settings.plate_radius_m = device.thimble().plate_radius_m;
    settings.min_pad_stiffness_n_per_m = device.safety.min_pad_stiffness_n_per_m;
    return settings;
}

std::uint8_t PadSafetyLimiter::allows(const PlatformPose& pose, const msgs::ContactSurface* surface,
                                      double& force_n) const noexcept {
    std::uint8_t violated = 0;
    force_n = modelForceN(pose, surface);
    if (!(force_n <= settings_.max_force_n)) {
        violated |= static_cast<std::uint8_t>(PadFlag::kForce);
    }
    if (!has_previous_) {
        return violated;
    }
    if (force_n > previous_force_n_ &&
        !(force_n <= previous_force_n_ + settings_.max_force_rate_n_per_s * settings_.period_s)) {
        violated |= static_cast<std::uint8_t>(PadFlag::kForceRate);
    }
    // The centre and four rim points: a tilt can bring the rim towards the pad while the
    // centre stays where it was.
    const double r = settings_.plate_radius_m;
    const std::array<Eigen::Vector3d, 5> points{
        Eigen::Vector3d::Zero(), Eigen::Vector3d(r, 0.0, 0.0), Eigen::Vector3d(-r, 0.0, 0.0),
        Eigen::Vector3d(0.0, r, 0.0), Eigen::Vector3d(0.0, -r, 0.0)};
    const Eigen::Vector3d towards_finger = previous_pose_.plateNormal();
    double approach_m = 0.0;
    for (const Eigen::Vector3d& point : points) {
        const Eigen::Vector3d now = pose.position_m + pose.rotation * point;
        const Eigen::Vector3d before = previous_pose_.position_m + previous_pose_.rotation * point;
        const double step = towards_finger.dot(now - before);
        if (std::isnan(step) || step > approach_m) {
            approach_m = step;  // a NaN stays and breaks the limit below
        }
    }
    if (!(approach_m <= settings_.max_approach_speed_m_per_s * settings_.period_s)) {
        violated |= static_cast<std::uint8_t>(PadFlag::kApproachSpeed);
    }
    return violated;
}

}  // namespace haptic::tactile
