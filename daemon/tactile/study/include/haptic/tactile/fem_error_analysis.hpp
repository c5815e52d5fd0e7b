#pragma once

// The thimble's error analysis against the soft-hand FEM (docs/algorithms.md §3.7, issue #21):
// each virtual object presses the FEM fingertip, whose bone is held, and that contact is the
// reference; the contact surface handsim would send for it (softhand::TactileOutput) goes to
// the optimiser (cold, and warm from the same press at two thirds of the depth) and to the two
// baselines; each method's servo angles go through forward kinematics, and the plate at that
// pose presses a fresh FEM fingertip. The optimiser's own pad model never judges it: both
// contacts are the FEM's. Not for the RT path (builds a model per press).

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "haptic/config/device.hpp"
#include "haptic/msgs/messages.hpp"
#include "haptic/softhand/collider.hpp"
#include "haptic/softhand/hand_builder.hpp"
#include "haptic/tactile/contact_optimiser.hpp"
#include "haptic/tactile/thimble_kinematics.hpp"

namespace haptic::tactile {

// Net contact on the fingertip, in the device base frame D. The moment is about the lowest
// point of the undeformed pad, so that a force along the pad normal through it has none.
struct FemContact {
    Eigen::Vector3d force_on_finger_n{Eigen::Vector3d::Zero()};
    Eigen::Vector3d moment_nm{Eigen::Vector3d::Zero()};
    int nodes_in_contact{0};
};

struct FemPress {
    FemContact contact;
    msgs::ContactSurface surface;  // what handsim sends for this contact
    int relax_steps{0};  // quasi-static steps taken (FemFingertip::kMaxRelaxSteps: not at rest)
};

// An object in D: its shape in its own frame, the frame's rotation in D, and where it sits
// across the pad (x, y in D); its height is found so that it reaches the indentation.
struct FemCase {
    std::string name;
    softhand::ColliderShape shape;
    Eigen::Matrix3d rotation{Eigen::Matrix3d::Identity()};
    Eigen::Vector2d across_m{Eigen::Vector2d::Zero()};
    double indentation_m{0.0015};  // deepest undeformed pad node inside the object
};

class FemFingertip {
  public:
    static constexpr int kMaxRelaxSteps = 400;

    // The fingertip model of the thimble scene at `resolution`, with the thimble's
    // finger_calibration.T_finger_device. Gravity off: the press is a device-frame experiment.
    FemFingertip(const config::ThimbleConfig& thimble, int resolution, int samples);

    // Presses the held fingertip with `shape` at `position`/`rotation` in D until at rest.
    [[nodiscard]] FemPress press(const softhand::ColliderShape& shape,
                                 const Eigen::Vector3d& position_d,
                                 const Eigen::Matrix3d& rotation_d) const;
    // The plate at a platform pose: a box of 2 plate radii across whose face is the plate.
    [[nodiscard]] FemPress pressPlate(const PlatformPose& pose, double plate_radius_m) const;
    // The case's object, its height chosen so that the deepest undeformed pad node lies
    // `indentation_m` inside it.
    [[nodiscard]] Eigen::Vector3d placement(const FemCase& c, double indentation_m) const;

    [[nodiscard]] const Eigen::Vector3d& padPoint() const { return pad_point_d_; }
    [[nodiscard]] int resolution() const { return resolution_; }

  private:
    [[nodiscard]] softhand::HandModel build() const;

    config::HandConfig hand_;
    softhand::SolverSettings solver_;
    config::Transform finger_from_device_;
    int resolution_;
    int samples_;
    std::vector<Eigen::Vector3d> pad_rest_d_;  // undeformed pad-side skin nodes in D
    Eigen::Vector3d pad_point_d_{Eigen::Vector3d::Zero()};
};

struct FemMethodResult {
    bool valid{false};            // false: no pose, or the servos cannot reach it
    double force_error{0.0};      // |F_d - F_v| / |F_v|
    double magnitude_error{0.0};  // (|F_d| - |F_v|) / |F_v|, signed
    double moment_error_mm{0.0};  // |M_d - M_v| / |F_v|: the centre of pressure's offset
    FemContact device;
};

struct FemCaseResult {
    std::string name;
    FemContact reference;
    SolveReport cold_report;
    SolveReport warm_report;
    FemMethodResult cold;
    FemMethodResult warm;
    FemMethodResult plane_fit;
    FemMethodResult force_normal;
};

// Planes tilted 0/10/20/30 degrees across the finger and 5 along it, spheres of 5/10/20 mm under
// the pad, a 10 mm sphere off-centre (4 mm towards the tip, 3 mm to the side), and a
// 90-degree edge across the finger; each `indentation_m` into the undeformed pad.
[[nodiscard]] std::vector<FemCase> femStandardCases(double indentation_m);

// Force of the flat, untilted plate `indentation_m` into the pad over that depth (N/m): the
// force-normal baseline's finger stiffness, its most favourable single value for these cases.
[[nodiscard]] double femSecantStiffness(const FemFingertip& finger, double indentation_m,
                                        double plate_radius_m);

[[nodiscard]] std::vector<FemCaseResult> runFemErrorAnalysis(const ThimbleKinematics& kinematics,
                                                             const OptimiserSettings& settings,
                                                             const FemFingertip& finger,
                                                             const std::vector<FemCase>& cases,
                                                             double finger_stiffness_n_per_m);

}  // namespace haptic::tactile
