#pragma once

// Kinematics of the 3-RRS fingertip thimble (docs/algorithms.md §3.6, DER): closed-form inverse
// kinematics per leg, the parasitic-motion solve, forward kinematics by Newton and the
// workspace constraints c_w(xi) >= 0.
//
// Frames and units: device base frame, origin at the static body centre (nail side), z from
// the nail towards the pad; metres and radians. The platform carries a flat round plate; its
// normal towards the finger is -R z (it presses the pad by moving towards smaller z).
//
// Platform DoFs xi = (height, tilt_x, tilt_y): height is the z of the platform centre; the
// tilt vector (tilt_x, tilt_y, 0) is the axis-angle of the tilt, so its length is exactly the
// angle between the plate normal and z. The remaining (p_x, p_y, yaw) are the parasitic
// motion fixed by the three leg-plane constraints.
//
// Everything here is noexcept, allocation-free and bounded: the 1 kHz loop may call it.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>

#include "haptic/config/device.hpp"

namespace haptic::tactile {

struct PlatformDofs {
    double height_m{0.0};
    double tilt_x_rad{0.0};
    double tilt_y_rad{0.0};
};

struct PlatformPose {
    Eigen::Vector3d position_m{Eigen::Vector3d::Zero()};  // platform (plate) centre
    Eigen::Matrix3d rotation{Eigen::Matrix3d::Identity()};
    double yaw_rad{0.0};  // parasitic rotation about the platform normal

    // Unit plate normal pointing from the plate into the finger.
    [[nodiscard]] Eigen::Vector3d plateNormal() const { return -rotation.col(2); }
};

using ServoAngles = std::array<double, 3>;

// Why a pose is not reachable. The first violated check is reported, with the leg when the
// check is per leg.
enum class KinematicsError : std::uint8_t {
    kNone,
    kNonFinite,
    kParasiticNotConverged,
    kLegUnreachable,
    kTiltLimit,
    kIndentationLimit,
    kServoBelowMin,
    kServoAboveMax,
    kReachMargin,
    kJointCone,
    kForwardNotConverged,
};

[[nodiscard]] const char* toString(KinematicsError error) noexcept;

// Workspace constraints, each scaled to be dimensionless (angles in rad, lengths divided by
// the plate radius) and feasible when >= 0. The index is the bit in active-constraint masks.
enum class Constraint : std::uint8_t {
    kTilt = 0,
    kIndentation = 1,
    kServoMin0 = 2,  // +leg
    kServoMax0 = 5,  // +leg
    kReach0 = 8,     // +leg
    kCone0 = 11,     // +leg
};
inline constexpr int kConstraintCount = 14;
using ConstraintValues = std::array<double, kConstraintCount>;
// d c_w / d(height, tilt_x, tilt_y), per constraint row.
using ConstraintJacobian = Eigen::Matrix<double, kConstraintCount, 3>;

// Derivatives of the plate pose over (height, tilt_x, tilt_y), parasitic motion included.
struct PoseJacobian {
    Eigen::Matrix3d position_m;  // column k: d position_m / d xi_k
    Eigen::Matrix3d normal;      // column k: d plateNormal() / d xi_k
};

[[nodiscard]] const char* constraintName(int index) noexcept;

struct InverseResult {
    KinematicsError error{KinematicsError::kNone};
    int leg{-1};  // leg of the failed per-leg check, -1 otherwise
    ServoAngles servo_rad{};
    PlatformPose pose;
    [[nodiscard]] bool ok() const noexcept { return error == KinematicsError::kNone; }
};

struct ForwardResult {
    KinematicsError error{KinematicsError::kNone};
    PlatformDofs dofs;
    PlatformPose pose;
    int iterations{0};
    double residual_rad{0.0};  // max |IK(dofs) - measured|
    [[nodiscard]] bool ok() const noexcept { return error == KinematicsError::kNone; }
};

// Reachable height range at zero tilt, found by a scan and bisection over the constraints.
struct WorkspaceSummary {
    double min_height_m{0.0};
    double max_height_m{0.0};
};

// The largest tilt reachable in every direction (72 directions), maximised over heights.
struct TiltReach {
    double best_height_m{0.0};
    double max_tilt_rad{0.0};
};

class ThimbleKinematics {
  public:
    // Leg reachability margin: keep every elbow at least this far from straight or folded,
    // away from the singular configurations.
    static constexpr double kElbowMarginRad = 5.0 * 3.14159265358979323846 / 180.0;

    explicit ThimbleKinematics(const config::ThimbleConfig& config);

    // Platform pose of xi with the parasitic motion solved (Newton from yaw = 0; 2-4
    // iterations). Fails only on non-finite input or no convergence.
    // `guess` (a nearby pose) starts Newton from its parasitic motion instead of zero.
    [[nodiscard]] KinematicsError platformPose(const PlatformDofs& dofs, PlatformPose& pose,
                                               const PlatformPose* guess = nullptr) const noexcept;

    // Closed-form IK on the assembly branch theta = phi - acos(kappa / rho) (elbow outward).
    // With check_workspace the pose must also satisfy every workspace constraint.
    [[nodiscard]] InverseResult inverse(const PlatformDofs& dofs,
                                        bool check_workspace = true) const noexcept;

    // Newton on xi such that IK(xi) = measured, from `guess` (the last estimate; the centre
    // of the workspace if none), then, if that fails, from the centre and from the retract
    // pose. Converges to |residual| < 1e-13 rad or reports an error.
    [[nodiscard]] ForwardResult forward(const ServoAngles& measured_rad,
                                        const PlatformDofs& guess) const noexcept;
    [[nodiscard]] ForwardResult forward(const ServoAngles& measured_rad) const noexcept {
        return forward(measured_rad, centre_);
    }

    // c_w(xi); returns false if the legs cannot even be assembled (values then undefined).
    [[nodiscard]] bool constraints(const PlatformDofs& dofs, ConstraintValues& values,
                                   PlatformPose* pose = nullptr,
                                   const PlatformPose* guess = nullptr) const noexcept;
    [[nodiscard]] static bool feasible(const ConstraintValues& values) noexcept;
    // Analytic d c_w / d xi at `pose` = platformPose(dofs) (implicit-function derivative of the
    // parasitic motion, then the leg chain); costs about one constraints() call. False if a
    // leg cannot be assembled there.
    [[nodiscard]] bool constraintJacobian(const PlatformDofs& dofs, const PlatformPose& pose,
                                          ConstraintJacobian& jacobian,
                                          PoseJacobian& pose_jacobian) const noexcept;

    // The pose farthest from the pad (zero tilt, largest reachable height): the no-contact pose.
    [[nodiscard]] const PlatformDofs& retractPose() const noexcept { return retract_; }
    // Zero tilt, mid height: the default Newton start.
    [[nodiscard]] const PlatformDofs& centrePose() const noexcept { return centre_; }
    [[nodiscard]] const WorkspaceSummary& workspace() const noexcept { return summary_; }
    // Thousands of IK evaluations: for tools and tests, not for the loop.
    [[nodiscard]] TiltReach tiltReach() const noexcept;
    [[nodiscard]] const config::ThimbleConfig& config() const noexcept { return config_; }
    [[nodiscard]] double minHeightM() const noexcept { return min_height_m_; }

    // Moves xi into the workspace: clamps the tilt and the indentation limit, then bisects
    // towards the zero-tilt pose at the clamped height (or the retract pose) until feasible.
    [[nodiscard]] PlatformDofs projectToWorkspace(const PlatformDofs& dofs) const noexcept;

  private:
    // One Newton solve from `guess` (forward() tries up to three starts).
    [[nodiscard]] ForwardResult forwardFrom(const ServoAngles& measured_rad,
                                            const PlatformDofs& guess) const noexcept;
    struct LegSolution {
        double servo_rad{0.0};
        double reach_ratio{0.0};  // |kappa| / rho, <= 1 when the leg closes
        Eigen::Vector3d joint_m{Eigen::Vector3d::Zero()};  // spherical joint S_i
        Eigen::Vector3d elbow_m{Eigen::Vector3d::Zero()};  // A_i
    };
    using LegSolutions = std::array<LegSolution, 3>;
    [[nodiscard]] bool solveLeg(int leg, const PlatformPose& pose, LegSolution& out) const noexcept;
    // All three legs; false at the first that does not close, whose index goes to
    // `unreachable_leg` when given.
    [[nodiscard]] bool solveLegs(const PlatformPose& pose, LegSolutions& out,
                                 int* unreachable_leg = nullptr) const noexcept;
    [[nodiscard]] bool rawServoAngles(const PlatformDofs& dofs, ServoAngles& out) const noexcept;
    [[nodiscard]] bool isFeasible(const PlatformDofs& dofs) const noexcept;
    void computeWorkspace();

    config::ThimbleConfig config_;
    std::array<Eigen::Vector3d, 3> radial_{};        // e_i
    std::array<Eigen::Vector3d, 3> servo_axis_{};    // a_i = z x e_i
    std::array<Eigen::Vector3d, 3> base_joint_{};    // B_i
    std::array<Eigen::Vector3d, 3> platform_arm_{};  // s_i, platform frame
    double min_height_m_{0.0};
    PlatformDofs retract_;
    PlatformDofs centre_;
    WorkspaceSummary summary_;
};

// Rotation with axis-angle (tilt_x, tilt_y, 0), smooth through zero.
[[nodiscard]] Eigen::Matrix3d tiltRotation(double tilt_x_rad, double tilt_y_rad) noexcept;

// The tilt whose plate normal (towards the finger) is `normal`; `normal` need not be unit.
[[nodiscard]] std::array<double, 2> tiltForNormal(const Eigen::Vector3d& normal) noexcept;

// The warm-start pose of the contact optimiser and of the plane-fit baseline: xi whose plate
// plane passes through point_m with the given normal towards the finger (not projected into the
// workspace; fixed-point on the height, the parasitic shift included).
[[nodiscard]] PlatformDofs poseForPlane(const ThimbleKinematics& kinematics,
                                        const Eigen::Vector3d& normal_into_finger,
                                        const Eigen::Vector3d& point_m) noexcept;

}  // namespace haptic::tactile
