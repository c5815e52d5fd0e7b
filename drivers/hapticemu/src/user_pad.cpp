#include "haptic/emu/user_pad.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "haptic/softhand/bullet_coupling.hpp"
#include "haptic/tactile/thimble_kinematics.hpp"

namespace haptic::emu {

UserPad::UserPad(const config::ThimbleConfig& thimble, const config::UserPadConfig& pad,
                 double half_length_m)
    : kinematics_(std::make_unique<tactile::ThimbleKinematics>(thimble)),
      pad_(pad),
      plate_radius_m_(thimble.plate_radius_m),
      half_length_m_(half_length_m) {
    if (!(half_length_m >= 0.0) || !std::isfinite(half_length_m)) {
        throw std::invalid_argument("user pad: the phalanx's half-length must be >= 0, not " +
                                    std::to_string(half_length_m));
    }
    // The phalanx's centre is the finger frame's origin, where the device sits by
    // T_finger_device (p_finger = R p_device + t), so at -R^T t in the device frame; its axis
    // is the finger frame's x (towards the tip), R^T x there.
    const config::Transform& mount = thimble.finger_calibration.T_finger_device;
    const Eigen::Matrix3d rotation = softhand::rotationFromRpy(mount.rpy_rad);
    centre_ =
        -rotation.transpose() *
        Eigen::Vector3d(mount.translation_m[0], mount.translation_m[1], mount.translation_m[2]);
    axis_ = rotation.transpose() * Eigen::Vector3d::UnitX();
}

UserPad::~UserPad() = default;
UserPad::UserPad(UserPad&&) noexcept = default;
UserPad& UserPad::operator=(UserPad&&) noexcept = default;

double UserPad::forceAt(double indentation_m) const noexcept {
    if (!(indentation_m > 0.0)) {
        return 0.0;
    }
    return 4.0 / 3.0 * pad_.effective_modulus_pa * std::sqrt(pad_.radius_m) *
           std::pow(indentation_m, 1.5);
}

FeltPadContact UserPad::feel(const std::array<double, 3>& servo_rad) {
    FeltPadContact out;
    const tactile::ForwardResult forward =
        have_last_
            ? kinematics_->forward(
                  servo_rad, tactile::PlatformDofs{last_dofs_[0], last_dofs_[1], last_dofs_[2]})
            : kinematics_->forward(servo_rad);
    if (!forward.ok()) {
        have_last_ = false;  // start the next solve from the workspace's centre
        return out;
    }
    have_last_ = true;
    last_dofs_ = {forward.dofs.height_m, forward.dofs.tilt_x_rad, forward.dofs.tilt_y_rad};
    out.pose_known = true;
    const Eigen::Vector3d normal = forward.pose.plateNormal();  // from the plate into the finger
    const Eigen::Vector3d& plate_centre = forward.pose.position_m;
    // How far a point lies on the finger's side of the plate's plane (negative: past it), and
    // whether it lies over the disc.
    const auto height = [&](const Eigen::Vector3d& p) { return (p - plate_centre).dot(normal); };
    const auto overDisc = [&](const Eigen::Vector3d& p) {
        const Eigen::Vector3d offset = p - plate_centre;
        return (offset - offset.dot(normal) * normal).squaredNorm() <=
               plate_radius_m_ * plate_radius_m_;
    };
    double deepest = std::numeric_limits<double>::infinity();  // the lowest height found
    Eigen::Vector3d deepest_point = centre_;
    const auto consider = [&](const Eigen::Vector3d& p) {
        if (height(p) < deepest) {
            deepest = height(p);
            deepest_point = p;
        }
    };
    // The tip: its sphere's point nearest the plate.
    const Eigen::Vector3d tip_point = centre_ + half_length_m_ * axis_ - pad_.radius_m * normal;
    if (overDisc(tip_point)) {
        consider(tip_point);
    }
    // The side: the line of the phalanx's surface nearest the plate, p(t) = base + t axis for t
    // in [-half, half] (the proximal end is flat: its rim ends the line). Its part over the disc
    // is an interval of t, and its height is linear in t: the deepest is at an end.
    const double along = normal.dot(axis_);
    const Eigen::Vector3d across = normal - along * axis_;
    if (across.squaredNorm() > 1e-24) {
        const Eigen::Vector3d base = centre_ - pad_.radius_m * across.normalized();
        // |u0 + t du|^2 <= r^2, u the in-plane offset from the plate's centre.
        const Eigen::Vector3d u0 =
            (base - plate_centre) - (base - plate_centre).dot(normal) * normal;
        const Eigen::Vector3d du = axis_ - along * normal;
        const double a = du.squaredNorm();
        const double b = u0.dot(du);
        const double c = u0.squaredNorm() - plate_radius_m_ * plate_radius_m_;
        // a = |across|^2 > 0 here: the axis is not along the normal.
        double low = -half_length_m_;
        double high = half_length_m_;
        bool over = false;
        const double discriminant = b * b - a * c;
        if (discriminant >= 0.0) {
            low = std::max(low, (-b - std::sqrt(discriminant)) / a);
            high = std::min(high, (-b + std::sqrt(discriminant)) / a);
            over = low <= high;
        }
        if (over) {
            const Eigen::Vector3d first = base + low * axis_;
            const Eigen::Vector3d last = base + high * axis_;
            // A plate level with the axis meets the side along the whole interval: it presses at
            // the interval's middle (ties with the tip's point go to the side, which is longer).
            if (std::abs(height(first) - height(last)) <= 1e-9 && height(first) <= deepest + 1e-9) {
                deepest = std::min(deepest, height(first));
                deepest_point = 0.5 * (first + last);
            } else {
                consider(first);
                consider(last);
            }
        }
    }
    if (!std::isfinite(deepest)) {
        return out;  // no part of the pad lies over the disc
    }
    // The plate's point under the pad's deepest.
    const Eigen::Vector3d point = deepest_point - deepest * normal;
    out.point_device_m = point;
    out.indentation_m = std::max(0.0, -deepest);
    out.force_device_n = forceAt(out.indentation_m) * normal;
    out.moment_device_nm = point.cross(out.force_device_n);
    return out;
}

}  // namespace haptic::emu
