#include "haptic/emu/user_pad.hpp"

#include <algorithm>
#include <cmath>

#include "haptic/softhand/bullet_coupling.hpp"
#include "haptic/tactile/thimble_kinematics.hpp"

namespace haptic::emu {

UserPad::UserPad(const config::ThimbleConfig& thimble, const config::UserPadConfig& pad)
    : kinematics_(std::make_unique<tactile::ThimbleKinematics>(thimble)),
      pad_(pad),
      plate_radius_m_(thimble.plate_radius_m) {
    // The sphere's centre is the distal phalanx's: the finger frame's origin, where the device
    // sits by T_finger_device (p_finger = R p_device + t), so at -R^T t in the device frame.
    const config::Transform& mount = thimble.finger_calibration.T_finger_device;
    const Eigen::Matrix3d rotation = softhand::rotationFromRpy(mount.rpy_rad);
    centre_ =
        -rotation.transpose() *
        Eigen::Vector3d(mount.translation_m[0], mount.translation_m[1], mount.translation_m[2]);
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
    // The sphere's centre lies on the finger's side of the plate's plane at this distance.
    const double centre_distance = (centre_ - plate_centre).dot(normal);
    const Eigen::Vector3d point = centre_ - centre_distance * normal;
    out.point_device_m = point;
    if ((point - plate_centre).norm() > plate_radius_m_) {
        return out;  // past the rim: the disc does not reach under the pad
    }
    out.indentation_m = std::max(0.0, pad_.radius_m - centre_distance);
    out.force_device_n = forceAt(out.indentation_m) * normal;
    out.moment_device_nm = point.cross(out.force_device_n);
    return out;
}

}  // namespace haptic::emu
