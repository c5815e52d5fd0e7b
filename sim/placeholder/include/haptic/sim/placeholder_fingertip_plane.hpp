#pragma once

// PLACEHOLDER until the soft-hand simulation lands (issue "Soft hand simulation"): a rigid
// planar 3R finger whose fingertip point presses a horizontal plane. It produces real,
// geometrically consistent messages for both devices so the end-to-end path can be built
// and tested, but it models no tissue, no friction and no Bullet world.
//
// Frames: W (world/finger base): x along the extended finger, z up; the finger flexes in the
// x-z plane, a positive joint angle bends it downward. The plane is horizontal; the model
// places it so that the scripted press indents it by press_depth_m at full flexion (the
// caller puts the finger base in its world accordingly).
// D (thimble device base): rides on the distal phalanx, origin on the nail side at its
// middle, z_D pointing from nail toward pad (down when the finger is straight).

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "haptic/msgs/messages.hpp"

namespace haptic::sim {

struct PlaceholderFingerParameters {
    std::array<double, 3> phalanx_lengths_m{0.045, 0.025, 0.020};
    double press_depth_m{0.004};     // fingertip penetration at full press
    double contact_margin_m{0.005};  // constraints are sent once closer than this
    // Scripted press: joints flex from rest_rad by up to press_amplitude_rad and back.
    std::array<double, 3> rest_rad{0.10, 0.10, 0.05};
    std::array<double, 3> press_amplitude_rad{0.45, 0.35, 0.20};
    double press_period_s{2.0};
    // Thimble pad: a disc of samples at pad_depth_m below the nail-side origin.
    double pad_radius_m{0.008};
    double pad_depth_m{0.012};
    int pad_rings{3};  // samples: 1 centre + 8 per ring
};

class PlaceholderFingertipPlane {
  public:
    explicit PlaceholderFingertipPlane(const PlaceholderFingerParameters& parameters);

    // Advances the scripted finger to time t (seconds since start).
    void setTime(double t_s) noexcept;
    void setJointAngles(const Eigen::Vector3d& q_rad) noexcept { q_rad_ = q_rad; }

    [[nodiscard]] const Eigen::Vector3d& jointAngles() const noexcept { return q_rad_; }
    [[nodiscard]] Eigen::Vector3d fingertipPosition() const noexcept;
    // Signed distance of the fingertip point to the plane (negative = penetrating).
    [[nodiscard]] double fingertipDistance() const noexcept;
    // d(distance)/dq.
    [[nodiscard]] Eigen::Vector3d distanceGradient() const noexcept;

    // For the exoskeleton: the configuration projected out of the plane and the linearised
    // non-penetration constraint a^T q >= b, sent while the tip is within contact_margin_m.
    void fillConstraintSet(msgs::ConstraintSet& out) const noexcept;
    // For the thimble: pad samples in D with their signed distance and the plane normal in D.
    void fillContactSurface(msgs::ContactSurface& out) const noexcept;

    [[nodiscard]] std::size_t padSampleCount() const noexcept { return pad_samples_D_.size(); }
    // Height of the plane in W (the finger base frame).
    [[nodiscard]] double planeZ() const noexcept { return plane_z_m_; }

  private:
    [[nodiscard]] Eigen::Matrix3d rotationWorldFromDevice() const noexcept;
    [[nodiscard]] Eigen::Vector3d deviceOriginWorld() const noexcept;

    PlaceholderFingerParameters parameters_;
    Eigen::Vector3d q_rad_;
    double plane_z_m_{0.0};
    msgs::BoundedArray<Eigen::Vector3d, msgs::kMaxContactSamples> pad_samples_D_;
};

}  // namespace haptic::sim
