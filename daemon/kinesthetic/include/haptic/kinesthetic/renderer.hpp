#pragma once

// Kinesthetic rendering for (under)actuated devices, docs/algorithms.md §5 and §6, selectable at
// run time. One call to tick() per 1 kHz cycle: device configuration q, its rate, and up to
// kMaxConstraintCount linear constraints c_j^T q >= d_j in configuration space (what the
// simulation publishes in msgs::ConstraintSet). Output: actuator forces u (before the port
// safety stage, see port_safety.hpp) and diagnostics.
//
// Metric: configuration space with W = I, so P_a = B (B^T B)^-1 B^T is the orthogonal projector
// on the actuated directions range(B(q)), recomputed every tick (§6.7). Stiffnesses are in the
// units of q (N/m for the point device, N m/rad for the exoskeleton's joint space).
//
//   standard             K = k_a I proxy, u = least-squares B^+ K (q_p - q). Exact on a
//                        fully actuated device; on an underactuated one it is the same
//                        computation as naive (it is the reference the others are judged by).
//   naive                §5.2: isotropic proxy, rendered force = its projection on range(B).
//   nullspace            §5.3: the naive proxy's contact forces mu_j (tau_c = sum_j mu_j a_j over
//                        its active rows) moved among those contacts keeping their resultant
//                        (sum_j mu_j n_j, n_j the contacts' Cartesian normals) and total, each by
//                        at most its own mu_j: the bounded minimiser of |P_u tau|^2 plus
//                        penalties on moves that keep the resultant only nearly; then
//                        u = B^+ tau. Needs the rows' contacts (msgs::ContactKinematics); with
//                        one contact, rows without contacts, or normals that fix every force it
//                        is naive (docs/algorithms.md §5.3).
//   subspace             §5.4: q_p = q + B alpha / k_a. With one actuator and constraints that
//                        carry their contact (msgs::ContactKinematics): each violated contact's
//                        g(chi(q + B alpha / k_a)) = 0 solved along the actuated direction
//                        (bracketed, then safeguarded Newton; <= 40 evaluations per contact),
//                        within the force limit and the actuator's stroke; the largest push
//                        needed; every contact checked at the result. Otherwise alpha = argmin 1/2
//                        alpha^T (B^T B / k_a) alpha over the linear rows (exact QP). u = alpha.
//                        rho -> infinity.
//   linearized_subspace  §5.5: one Kaczmarz sweep over the violated constraints, each corrected
//                        along its actuated direction; rows that carry their contact are first
//                        linearised at the current q (so this is subspace's linearisation).
//                        For one actuator it is the max-over-constraints rule of §5.5.
//   anisotropic          §6.5: K = k_a (P_a + rho P_u), K-metric proxy, u = B^+ K (q_p - q),
//                        rho from the closed form, the numeric search or a manual override.
//
// Actuator-space damping -b_v ell_dot is added while in contact. Contract of tick(): noexcept,
// no allocation, no locks, bounded iterations; bad input gives u = 0 and a fault reason.

#include <cstdint>
#include <span>

#include "haptic/config/device.hpp"
#include "haptic/kinesthetic/device_model.hpp"
#include "haptic/kinesthetic/kmetric_projection.hpp"
#include "haptic/msgs/messages.hpp"

namespace haptic::kinesthetic {

using RenderingMethod = config::RenderingMethod;

enum class RhoMode : std::uint8_t { kClosedForm, kNumericSearch, kManual };

struct RenderParameters {
    RenderingMethod method{RenderingMethod::kAnisotropic};
    double tracking_stiffness{1000.0};  // k_a
    double user_stiffness{300.0};       // k_u, isotropic estimate (closed-form rho*)
    // Anisotropic user stiffness for the numeric search (n x n, SPD); empty = k_u I.
    ConfigMatrix user_stiffness_matrix{};
    RhoMode rho_mode{RhoMode::kClosedForm};
    double rho_override{1.0};      // used when rho_mode == kManual
    double actuator_damping{0.0};  // b_v, in actuator units (N s/m)
    int max_iterations{KMetricProjector::kDefaultMaxIterations};
    int rho_search_iterations{48};
    // eps, relative to the mean squared joint torque of a unit redistribution
    double nullspace_regularisation{1e-9};
};

enum class RenderFault : std::uint8_t {
    kNone,
    kNonFiniteState,        // q or q_dot has NaN/Inf or the wrong size
    kInvalidConstraints,    // NaN/Inf, wrong size or more than kMaxConstraintCount
    kSolverIterationLimit,  // proxy QP hit its bound; output is from the last iterate
    kInfeasibleConstraints,
    kNotRenderable,  // the needed force has no actuated component (or B is singular)
};

[[nodiscard]] const char* toString(RenderFault fault) noexcept;

struct RenderOutput {
    ActuatorVector actuator_force;  // u (m); zero on fault
    ConfigVector proxy;             // q_p
    ConfigVector coupling_force;    // K (q_p - q): what a fully actuated device would apply
    ConfigVector rendered_force;    // B u: what this device applies (damping included)
    double rho{1.0};                // anisotropy used this tick
    SolveStatus solve_status{SolveStatus::kOptimal};
    RenderFault fault{RenderFault::kNone};
    int iterations{0};
    int active_constraints{0};
    bool in_contact{false};
    // subspace on contacts: a contact out of reach within the force limit or the actuator's
    // stroke; the limit is rendered (not a fault).
    bool limited{false};
};

class KinestheticRenderer {
  public:
    // Throws std::invalid_argument with the reason if the parameters are invalid for the device.
    KinestheticRenderer(const DeviceModel& device, const RenderParameters& parameters);

    // Not RT: validates and swaps parameters; returns the reason (nullptr if accepted).
    const char* setParameters(const RenderParameters& parameters) noexcept;
    // RT-safe method switch (haptic/command set-method); resets the warm start.
    void setMethod(RenderingMethod method) noexcept;
    // RT: k_a for the next ticks (a device's stiffness clamp lowers it as its linkage
    // stiffens); false, and nothing changes, unless finite and > 0.
    bool setTrackingStiffness(double k_a) noexcept;
    // RT: k_u for the next ticks (the online estimate, UserStiffnessEstimator); false, and
    // nothing changes, unless finite and > 0.
    bool setUserStiffness(double k_u) noexcept;

    void tick(const ConfigVector& q, const ConfigVector& q_dot, const ConstraintMatrix& C,
              const ConstraintVector& d, RenderOutput& out) noexcept;
    // Same with the constraints as the simulation publishes them.
    void tick(const ConfigVector& q, const ConfigVector& q_dot,
              std::span<const msgs::LinearConstraint> constraints, RenderOutput& out) noexcept;

    void reset() noexcept { warm_start_ = ActiveSet{}; }

    [[nodiscard]] const RenderParameters& parameters() const noexcept { return parameters_; }
    [[nodiscard]] const DeviceModel& device() const noexcept { return device_; }

    // Reason why the parameters are invalid for the device, nullptr if they are fine.
    [[nodiscard]] static const char* validate(const DeviceModel& device,
                                              const RenderParameters& parameters) noexcept;

  private:
    void renderProxy(double rho, const ConfigVector& q, const ConstraintMatrix& C,
                     const ConstraintVector& d, RenderOutput& out) noexcept;
    void renderSubspace(const ConfigVector& q, const ConstraintMatrix& C, const ConstraintVector& d,
                        RenderOutput& out) noexcept;
    // §5.4 on the contacts themselves (contacts_), one actuator.
    void renderNonlinearSubspace(const ConfigVector& q, RenderOutput& out) noexcept;
    void renderLinearizedSubspace(const ConfigVector& q, const ConstraintMatrix& C,
                                  const ConstraintVector& d, RenderOutput& out) noexcept;
    void redistributeInNullspace(const ConstraintMatrix& C, RenderOutput& out) noexcept;
    double chooseRho(const ConstraintMatrix& C, const ConstraintVector& d,
                     const ConfigVector& q) noexcept;
    void clearOutput(const ConfigVector& q, RenderFault fault, RenderOutput& out) noexcept;

    const DeviceModel& device_;
    RenderParameters parameters_;
    KMetricProjector projector_;
    KMetricProjector move_projector_;  // nullspace: its moves within their bounds
    ActiveSet warm_start_;
    // Per-tick scratch, sized in the constructor.
    ActuationMatrix B_;
    BoundedMatrix<kMaxActuators, kMaxActuators> gram_;  // B^T B
    ConfigMatrix P_a_;
    ConstraintMatrix C_scratch_;
    ConstraintVector d_scratch_;
    // The rows of the current tick when they all carry a usable contact (else empty).
    std::span<const msgs::LinearConstraint> contacts_;
};

}  // namespace haptic::kinesthetic
