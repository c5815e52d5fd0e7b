#pragma once

// Contact-surface matching for the thimble (docs/algorithms.md §3.3-3.5): find the platform DoFs
// xi = (height, tilt_x, tilt_y) whose plate best reproduces the virtual contact surface,
//
//   E(xi) = sum_{i in C} w_i 2 psi(d(x_i)) + eta sum_{j not in C} w_j 2 psi(min(d(x_j), 0))
//           + lambda |S (xi - xi_prev)|^2,      subject to c_w(xi) >= 0,
//
// psi(d) = s^2 (exp(-d / s) - 1 + d / s) is the energy of the exponential pad law
// p(delta) = p0 (exp(delta / s) - 1) per unit stiffness weight w = A dp/d(delta) (taken at
// the virtual indentation), so dE/dxi is the mismatch between the generalised pad forces of
// the plate and of the virtual contact [DER]. psi(d) -> d^2 / 2 as s -> infinity (linear pad:
// the quadratic matched-point objective of docs/algorithms.md §3.3). Here d(y) = nu . (y - p) is
// the signed distance of y to the plate (positive on the finger side), applied with a smooth weight
// that fades to zero at the plate rim; S = diag(1, r_d, r_d) puts the tilts in metres at the rim.
// Contact samples (signed_distance < 0) are matched at their projection onto the virtual object,
// x_i = p_i
// - signed_distance_i n_i; non-contact samples are kept on the finger side of the plate.
//
// Solver: Gauss-Newton (curvature psi'', analytic Jacobians from
// ThimbleKinematics::constraintJacobian) with a 3-variable active-set QP on the linearised
// workspace constraints, then a backtracking line search that only accepts feasible poses with
// lower E. Warm started from the previous solution; iterations bounded by optimiser.max_iterations.
// solve() is noexcept, allocation-free and bounded: it runs on the 1 kHz path.

#include <cstdint>

#include "haptic/msgs/messages.hpp"
#include "haptic/tactile/thimble_kinematics.hpp"

namespace haptic::tactile {

struct OptimiserSettings {
    int max_iterations{20};
    int max_samples{64};             // optimiser.pad_samples; larger surfaces are rejected
    double non_contact_weight{1.0};  // eta
    double smoothness_weight{1e-6};  // lambda, relative to a total sample weight of 1
    double rim_blend_m{0.001};       // the rim weight falls from 1 to 0 over this width
    // s of the pad's exponential stiffening p(delta) = p0 (exp(delta / s) - 1):
    // optimiser.pad_stiffening_depth_m, which ships fitted to the soft-hand FEM fingertip
    // (fem_pad_fit.hpp). Infinity or <= 0: a linear pad, i.e. the quadratic objective.
    double pad_stiffening_depth_m{0.001};
    // Converged when the scaled step is below this: 1 um, far below what a hobby servo can
    // resolve (0.1 degree on a 10 mm crank is ~17 um).
    double step_tolerance_m{1e-6};
    double match_tolerance_m{3e-4};  // contact RMS residual above this sets poor_match
    double frame_limit_m{0.05};      // samples farther than this from the base origin are rejected
    double normal_tolerance{1e-2};   // | |n| - 1 | allowed for contact normals

    [[nodiscard]] static OptimiserSettings fromConfig(const config::ThimbleConfig& config);
};

enum class InputError : std::uint8_t {
    kNone,
    kTooManySamples,
    kNonFinitePosition,
    kNonFiniteDistance,
    kNonFiniteNormal,
    kNonFiniteWeight,
    kNegativeWeight,
    kNormalNotUnit,
    kOutOfFrame,
};

[[nodiscard]] const char* toString(InputError error) noexcept;

struct InputCheck {
    InputError error{InputError::kNone};
    int sample_index{-1};
    [[nodiscard]] bool ok() const noexcept { return error == InputError::kNone; }
};

// Checks every sample the optimiser would read; the first bad one is reported.
[[nodiscard]] InputCheck checkContactSurface(const msgs::ContactSurface& surface,
                                             const OptimiserSettings& settings) noexcept;

enum class SolveOutcome : std::uint8_t {
    kMatched,             // contact present: the optimised pose
    kRetractedNoContact,  // no sample in contact (or all weights zero): the retract pose
    kRejectedInput,       // bad input: the retract pose, reason in input
};

[[nodiscard]] const char* toString(SolveOutcome outcome) noexcept;

struct SolveReport {
    SolveOutcome outcome{SolveOutcome::kRetractedNoContact};
    InputCheck input;
    bool converged{false};
    int iterations{0};
    double objective{0.0};
    double contact_rms_m{0.0};            // weighted RMS of d over the matched contact points
    double non_contact_overlap_m{0.0};    // deepest plate intrusion past a non-contact sample
    std::uint32_t active_constraints{0};  // bit k = Constraint k within tolerance of its bound
    bool clamped{false};     // a workspace constraint is active: the contact is not reachable
    bool poor_match{false};  // contact_rms_m above match_tolerance_m (unreachable or contradictory)
};

struct TactileCommand {
    ServoAngles servo_rad{};
    PlatformDofs dofs;
    PlatformPose pose;
    SolveReport report;
};

class ContactSurfaceOptimiser {
  public:
    ContactSurfaceOptimiser(const ThimbleKinematics& kinematics, const OptimiserSettings& settings);

    [[nodiscard]] TactileCommand solve(const msgs::ContactSurface& surface) noexcept;

    // Next solve starts from the retract pose (e.g. after the device was re-enabled).
    void reset() noexcept {
        warm_start_ = kinematics_.retractPose();
        previous_matched_ = false;
    }
    [[nodiscard]] const PlatformDofs& warmStart() const noexcept { return warm_start_; }
    [[nodiscard]] const OptimiserSettings& settings() const noexcept { return settings_; }

  private:
    struct Target {
        Eigen::Vector3d point_m{Eigen::Vector3d::Zero()};
        double sqrt_weight{0.0};
        bool contact{false};
    };
    struct Evaluation {
        double objective{0.0};
        double contact_sq_sum{0.0};
        double contact_weight{0.0};
        double overlap_m{0.0};
    };

    // Distance to the plate and pad-energy derivatives of one sample at one pose; weight 0
    // when the sample does not enter E there.
    struct SampleState {
        double d{0.0};
        double weight{0.0};  // sqrt(w_i) times the rim weight
        double slope{0.0};
        double curvature{0.0};
    };
    using SampleStates = std::array<SampleState, msgs::kMaxContactSamples>;

    [[nodiscard]] Evaluation evaluate(const PlatformDofs& dofs, const PlatformPose& pose,
                                      SampleStates& states) const noexcept;
    [[nodiscard]] double rimWeight(double in_plane_radius_sq_m2) const noexcept;
    [[nodiscard]] TactileCommand finish(const PlatformDofs& dofs, SolveReport report) noexcept;
    [[nodiscard]] Eigen::Vector3d scaled(const PlatformDofs& dofs) const noexcept;
    [[nodiscard]] PlatformDofs unscaled(const Eigen::Vector3d& z) const noexcept;

    const ThimbleKinematics& kinematics_;
    OptimiserSettings settings_;
    std::array<Target, msgs::kMaxContactSamples> targets_{};
    std::array<SampleStates, 2> sample_states_{};
    int target_count_{0};
    double lambda_{0.0};
    double inverse_stiffening_depth_{0.0};
    PlatformDofs warm_start_;
    // The smoothness term only ties a solve to a previous matched pose; leaving the retract
    // pose should not be slowed down.
    bool previous_matched_{false};
};

}  // namespace haptic::tactile
