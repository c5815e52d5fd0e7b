#pragma once

// The virtual user's finger pad under a thimble (docs/drivers.md, "Virtual user"): what the
// user feels from where the plate is. The pad is the user's distal phalanx as the scene's hand
// shapes it (the skin the virtual user measures its finger's penetration with): radius R about
// the phalanx's axis from its flat proximal end to the centre of its round tip, `half_length`
// either side of the phalanx's centre (the finger frame's origin; the device sits on the finger
// by the thimble file's T_finger_device, as in handsim, so the user's pad is where the
// simulated one is). Half-length 0 is a sphere about the centre. The plate is the flat disc of
// the platform pose the measured servo angles give (forward kinematics). The file's
// contact_height_m is hapticd's belief about where the pad begins, a calibration; the user's
// pad does not read it.
//
// The indentation delta is how far the deepest point of the pad's surface that lies over the
// plate's disc reaches past the plate's plane: on the side of the phalanx facing the plate
// along its length, or on its round tip. The force, normal to the plate, sums two contacts:
// - the side, a cylinder on a flat: a line contact, each length dt of the side's line over the
//   disc loaded by P'(delta(t)) dt. In 2D Hertz theory a cylinder's approach has no absolute
//   value (the half-space's displacement is logarithmic); with the datum at depth R it is
//   delta = 2 P' / (pi E*) (ln(4 R / b) - 1/2), b = sqrt(4 P' R / (pi E*)) the contact's
//   half-width, i.e. delta = P' / (pi E*) (ln(4 pi E* R / P') - 1), solved for P'. delta(t) is
//   linear along the line when the plate is pitched;
// - the tip, Hertz's sphere law F = 4/3 E* sqrt(R) delta^(3/2) at its point nearest the plate,
//   times the share of its contact circle that lies beyond the side (1/2 for a level plate,
//   all of it for a sphere: half-length 0).
// Both with the same E* and R. Until 2026-11-29 the whole pad felt the sphere law at its
// deepest point, 3.6 times softer than the FEM fingertip at 1.5 mm along the side; the line
// contact is within 10 % of the FEM from 1.5 to 2 mm and softer below (-46 % at 0.25 mm).
// Friction is not modelled (the plate does not slide on the pad in the thimble's motion: it
// presses and tilts).
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
    // `half_length_m`: half the distal phalanx's length (HandModel's BoneInfo::length_m / 2).
    UserPad(const config::ThimbleConfig& thimble, const config::UserPadConfig& pad,
            double half_length_m);
    ~UserPad();
    UserPad(UserPad&&) noexcept;
    UserPad& operator=(UserPad&&) noexcept;

    // The contact with the plate where these servo angles put it. The forward kinematics
    // starts from the last pose found, so calls along a trajectory converge in few steps.
    [[nodiscard]] FeltPadContact feel(const std::array<double, 3>& servo_rad);

    // Hertz's sphere law alone: the force at an indentation (0 for delta <= 0).
    [[nodiscard]] double forceAt(double indentation_m) const noexcept;
    // The line contact's load per length of the side (N/m) at an indentation (0 for <= 0).
    [[nodiscard]] double lineLoadAt(double indentation_m) const noexcept;
    // The phalanx's centre (the finger frame's origin) in the device frame.
    [[nodiscard]] const Eigen::Vector3d& centreDeviceM() const noexcept { return centre_; }
    // Its axis in the device frame, from the flat proximal end to the tip's centre (unit).
    [[nodiscard]] const Eigen::Vector3d& axisDevice() const noexcept { return axis_; }
    // The height at which a level plate first touches the pad under its centre (device z of the
    // pad's surface there; the axis level, as the shipped mount has it).
    [[nodiscard]] double firstContactHeightM() const noexcept {
        return centre_.z() + pad_.radius_m;
    }

  private:
    std::unique_ptr<tactile::ThimbleKinematics> kinematics_;
    config::UserPadConfig pad_;
    double plate_radius_m_{0.0};
    Eigen::Vector3d centre_{Eigen::Vector3d::Zero()};
    Eigen::Vector3d axis_{Eigen::Vector3d::UnitX()};
    double half_length_m_{0.0};
    std::array<double, 3> last_dofs_{};  // height, tilt_x, tilt_y of the last pose found
    bool have_last_{false};
};

}  // namespace haptic::emu
