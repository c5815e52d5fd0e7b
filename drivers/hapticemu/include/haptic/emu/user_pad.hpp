#pragma once

// The virtual user's finger pad under a thimble (docs/drivers.md, "Virtual user"): what the
// user feels from where the plate is. The pad is a Hertz sphere of radius R about the distal
// phalanx's centre (the finger frame's origin; the device sits on the finger by the thimble
// file's T_finger_device, as in handsim, so the user's pad is where the simulated one is);
// the plate is the flat disc of the platform pose the measured servo angles give (forward
// kinematics). The file's contact_height_m is hapticd's belief about where the pad begins,
// a calibration; the user's pad does not read it. Indented by delta along the plate normal,
// the pad feels F = 4/3 E* sqrt(R) delta^(3/2), normal to the plate, at the point of the plate
// nearest the sphere's centre. The plate's rim is not modelled: a sphere whose nearest plate
// point lies outside the disc feels nothing. Friction is not modelled either (the plate does
// not slide on the pad in the thimble's motion: it presses and tilts).
//
// This is the user's pad, independent of the tactile optimiser's model (an exponential pad
// law over the contact surface's samples): the felt force judges the rendering.

#include <Eigen/Core>
#include <array>
#include <memory>

#include "haptic/config/device.hpp"
#include "haptic/config/virtual_user.hpp"

namespace haptic::tactile {
class ThimbleKinematics;
}

namespace haptic::emu {

struct FeltPadContact {
    bool pose_known{false};  // the forward kinematics converged for the angles given
    double indentation_m{0.0};
    Eigen::Vector3d force_device_n{Eigen::Vector3d::Zero()};    // on the pad, device frame
    Eigen::Vector3d moment_device_nm{Eigen::Vector3d::Zero()};  // about the device origin
    Eigen::Vector3d point_device_m{Eigen::Vector3d::Zero()};    // where the plate presses
};

class UserPad {
  public:
    UserPad(const config::ThimbleConfig& thimble, const config::UserPadConfig& pad);
    ~UserPad();
    UserPad(UserPad&&) noexcept;
    UserPad& operator=(UserPad&&) noexcept;

    // The contact with the plate where these servo angles put it. The forward kinematics
    // starts from the last pose found, so calls along a trajectory converge in few steps.
    [[nodiscard]] FeltPadContact feel(const std::array<double, 3>& servo_rad);

    // Hertz's law alone: the force at an indentation (0 for delta <= 0).
    [[nodiscard]] double forceAt(double indentation_m) const noexcept;
    [[nodiscard]] const Eigen::Vector3d& sphereCentreDeviceM() const noexcept { return centre_; }
    // The height at which a level plate first touches the pad (device z of its outermost point).
    [[nodiscard]] double firstContactHeightM() const noexcept {
        return centre_.z() + pad_.radius_m;
    }

  private:
    std::unique_ptr<tactile::ThimbleKinematics> kinematics_;
    config::UserPadConfig pad_;
    double plate_radius_m_{0.0};
    Eigen::Vector3d centre_{Eigen::Vector3d::Zero()};
    std::array<double, 3> last_dofs_{};  // height, tilt_x, tilt_y of the last pose found
    bool have_last_{false};
};

}  // namespace haptic::emu
