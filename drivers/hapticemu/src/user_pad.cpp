#include "haptic/emu/user_pad.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "haptic/softhand/bullet_coupling.hpp"
#include "haptic/tactile/thimble_kinematics.hpp"

namespace haptic::emu {

namespace {

// Slices of the side's line contact (midpoint rule along the part over the disc).
constexpr int kSideSlices = 32;

}  // namespace

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

double UserPad::lineLoadAt(double indentation_m) const noexcept {
    if (!(indentation_m > 0.0)) {
        return 0.0;
    }
    // delta(P') = P' / (pi E*) (ln(4 pi E* R / P') - 1) rises with P' up to P' = 4 pi E* R / e^2,
    // where delta = P' / (pi E*): the law's reach (4.3 mm for the shipped pad). Below it, P' is
    // found by bisection on log P'; beyond it, the load grows on that point's secant.
    const double e_star = pad_.effective_modulus_pa;
    const double scale = 4.0 * std::numbers::pi * e_star * pad_.radius_m;
    const double peak_load = scale * std::exp(-2.0);
    const double peak_depth = peak_load / (std::numbers::pi * e_star);
    if (indentation_m >= peak_depth) {
        return peak_load * indentation_m / peak_depth;
    }
    const auto depthOf = [&](double load) {
        return load / (std::numbers::pi * e_star) * (std::log(scale / load) - 1.0);
    };
    double low = std::log(peak_load) - 60.0;
    double high = std::log(peak_load);
    for (int i = 0; i < 60; ++i) {
        const double mid = 0.5 * (low + high);
        (depthOf(std::exp(mid)) < indentation_m ? low : high) = mid;
    }
    return std::exp(0.5 * (low + high));
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
    // The force and its moment, summed over the contact's parts: the plate's point under each
    // part of the pad, loaded along the plate's normal.
    double force = 0.0;
    Eigen::Vector3d loaded_points = Eigen::Vector3d::Zero();  // sum of load x plate point
    const auto press = [&](const Eigen::Vector3d& pad_point, double load_n) {
        if (load_n > 0.0) {
            force += load_n;
            loaded_points += load_n * (pad_point - height(pad_point) * normal);
        }
    };
    const double along = normal.dot(axis_);
    // The tip: its sphere's point nearest the plate, pressed by Hertz's sphere law. Where the
    // phalanx has a side, only the part of the tip's contact circle (radius sqrt(R delta))
    // beyond the junction with the side belongs to the tip: the side's line contact carries
    // the rest. That share runs from 0 (the plate pitched up towards the tip) through 1/2
    // (level) to 1 (pitched down onto the tip).
    const Eigen::Vector3d tip_point = centre_ + half_length_m_ * axis_ - pad_.radius_m * normal;
    if (overDisc(tip_point)) {
        consider(tip_point);
        const double tip_depth = -height(tip_point);
        double share = 1.0;
        if (half_length_m_ > 0.0 && tip_depth > 0.0) {
            const double a = std::sqrt(pad_.radius_m * tip_depth);
            // The contact circle's centre lies -(R - delta) along beyond the junction along
            // the axis, so -(R - delta) along / sqrt(1 - along^2) in the plate's plane; the
            // side's part is the circle's segment behind the chord at that distance.
            const double in_plane = std::sqrt(std::max(1.0 - along * along, 1e-12));
            const double x = std::clamp(-(pad_.radius_m - tip_depth) * along / in_plane, -a, a);
            const double behind = a * a * std::acos(x / a) - x * std::sqrt(a * a - x * x);
            share = 1.0 - behind / (std::numbers::pi * a * a);
        }
        press(tip_point, share * forceAt(tip_depth));
    }
    // The side: the line of the phalanx's surface nearest the plate, p(t) = base + t axis for t
    // in [-half, half] (the proximal end is flat: its rim ends the line). Its part over the disc
    // is an interval of t, and its height is linear in t: the deepest is at an end. It is
    // pressed as a line contact (a cylinder on a flat), integrated along the interval.
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
            // Midpoint rule over the part of the interval past the plate (the indentation is
            // linear in t, so that part is an interval too): slices start where it does, so a
            // pad indented anywhere is loaded.
            const double h_low = height(first);
            const double h_high = height(last);
            double from = low;
            double to = high;
            if (h_low >= 0.0 && h_high >= 0.0) {
                to = from;  // nowhere past the plate
            } else if (h_low >= 0.0) {
                from = low + (high - low) * h_low / (h_low - h_high);
            } else if (h_high >= 0.0) {
                to = low + (high - low) * h_low / (h_low - h_high);
            }
            const double slice = (to - from) / kSideSlices;
            for (int i = 0; slice > 0.0 && i < kSideSlices; ++i) {
                const Eigen::Vector3d p = base + (from + (i + 0.5) * slice) * axis_;
                press(p, slice * lineLoadAt(-height(p)));
            }
        }
    }
    if (!std::isfinite(deepest)) {
        return out;  // no part of the pad lies over the disc
    }
    out.indentation_m = std::max(0.0, -deepest);
    // Every load is along the normal: the centre of pressure carries the moment.
    out.point_device_m =
        force > 0.0 ? Eigen::Vector3d(loaded_points / force) : deepest_point - deepest * normal;
    out.force_device_n = force * normal;
    out.moment_device_nm = out.point_device_m.cross(out.force_device_n);
    return out;
}

}  // namespace haptic::emu
