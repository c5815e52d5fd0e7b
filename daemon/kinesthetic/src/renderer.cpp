#include "haptic/kinesthetic/renderer.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "haptic/kinesthetic/anisotropic.hpp"
#include "haptic/kinesthetic/contact_gap.hpp"

namespace haptic::kinesthetic {

namespace {

// Below this share of a constraint normal in range(B) the actuators cannot push it out.
constexpr double kActuatedShareEpsilon = 1e-9;
// The nonlinear subspace root: evaluations of g at most per contact (bracketing takes at most
// half), and how close to the surface is on it.
constexpr int kMaxRootIterations = 40;
constexpr double kRootToleranceM = 1e-9;  // 1 nm: far below any encoder

struct ActuatedRoot {
    double alpha{0.0};
    int evaluations{0};
    bool reached{true};  // false: no surface crossing within the bound
};

// The alpha between 0 and `bound` (either sign) nearest 0 with g(q + direction alpha) = 0,
// given g(0) = g0 < 0 and g's slope along `direction` pointing towards `bound`. From the
// linear estimate, Newton steps that lead outwards (or doublings where Newton does not) until
// g >= 0 brackets the crossing (g is not monotone over a long way: the point moves on arcs),
// then a safeguarded Newton iteration in the bracket (a step that leaves it is a bisection).
// Returns the bracket's feasible end, so the proxy is never left inside this contact. At most
// kMaxRootIterations evaluations of g.
ActuatedRoot solveAlongActuator(const msgs::ContactKinematics& contact, const ConfigVector& q,
                                const ConfigVector& direction, double bound, double g0,
                                double slope) noexcept {
    ActuatedRoot root;
    ConfigVector gradient;
    const double reach = std::abs(bound);
    double inside = 0.0;  // g < 0 here
    double outside = std::numeric_limits<double>::quiet_NaN();
    double alpha = std::copysign(std::min(std::abs(g0 / slope), reach), bound);
    while (root.evaluations < kMaxRootIterations) {
        ++root.evaluations;
        const ConfigVector q_p = q + direction * alpha;
        const double g = contactGap(contact, q_p, &gradient);
        const double along = gradient.dot(direction);
        if (g >= 0.0) {
            outside = alpha;
            if (g <= kRootToleranceM) {
                break;
            }
        } else {
            inside = alpha;
        }
        const double newton = along != 0.0 ? alpha - g / along : std::nan("");
        if (std::isnan(outside)) {
            // Not bracketed yet: further out, by Newton if it leads out, else doubling.
            if (std::abs(alpha) >= reach) {
                break;
            }
            const bool outwards = std::abs(newton) > std::abs(alpha) && newton * bound > 0.0;
            alpha = std::copysign(
                std::min(outwards ? std::abs(newton) : 2.0 * std::abs(alpha), reach), bound);
            continue;
        }
        if (std::abs(outside - inside) <= 1e-15 * (1.0 + reach)) {
            break;
        }
        const bool in_bracket = (newton - inside) * (newton - outside) < 0.0;
        alpha = in_bracket ? newton : 0.5 * (inside + outside);
    }
    if (std::isnan(outside)) {
        root.alpha = inside;  // the bound: out of reach within it
        root.reached = false;
        return root;
    }
    root.alpha = outside;
    return root;
}

bool isSymmetricPositiveDefinite(const ConfigMatrix& M) noexcept {
    if (!M.allFinite() ||
        (M - M.transpose()).cwiseAbs().maxCoeff() > 1e-9 * (1.0 + M.cwiseAbs().maxCoeff())) {
        return false;
    }
    const Eigen::LDLT<ConfigMatrix> ldlt(M);
    return ldlt.info() == Eigen::Success && ldlt.vectorD().minCoeff() > 0.0;
}

RenderFault faultOf(SolveStatus status) noexcept {
    switch (status) {
        case SolveStatus::kOptimal:
            return RenderFault::kNone;
        case SolveStatus::kIterationLimit:
            return RenderFault::kSolverIterationLimit;
        case SolveStatus::kInfeasible:
            return RenderFault::kInfeasibleConstraints;
        case SolveStatus::kInvalidInput:
            return RenderFault::kInvalidConstraints;
    }
    return RenderFault::kInvalidConstraints;
}

}  // namespace

const char* toString(RenderFault fault) noexcept {
    switch (fault) {
        case RenderFault::kNone:
            return "none";
        case RenderFault::kNonFiniteState:
            return "device state has NaN/Inf or the wrong size";
        case RenderFault::kInvalidConstraints:
            return "constraints have NaN/Inf, the wrong size or too many entries";
        case RenderFault::kSolverIterationLimit:
            return "proxy solver hit its iteration bound";
        case RenderFault::kInfeasibleConstraints:
            return "constraints are infeasible";
        case RenderFault::kNotRenderable:
            return "required force has no actuated component";
    }
    return "unknown";
}

const char* KinestheticRenderer::validate(const DeviceModel& device,
                                          const RenderParameters& p) noexcept {
    const int n = device.dofs();
    if (n < 1 || n > kMaxDofs || device.actuators() < 1 || device.actuators() > kMaxActuators ||
        device.actuators() > n) {
        return "device dimensions exceed the renderer's capacity";
    }
    if (!(p.tracking_stiffness > 0.0) || !std::isfinite(p.tracking_stiffness)) {
        return "tracking_stiffness (k_a) must be finite and > 0";
    }
    if (!(p.user_stiffness > 0.0) || !std::isfinite(p.user_stiffness)) {
        return "user_stiffness (k_u) must be finite and > 0";
    }
    if (p.user_stiffness_matrix.size() != 0 &&
        (p.user_stiffness_matrix.rows() != n || p.user_stiffness_matrix.cols() != n ||
         !isSymmetricPositiveDefinite(p.user_stiffness_matrix))) {
        return "user_stiffness_matrix must be empty or a symmetric positive definite n x n";
    }
    if (p.rho_mode == RhoMode::kManual &&
        (!(p.rho_override > 0.0) || !std::isfinite(p.rho_override))) {
        return "rho_override must be finite and > 0";
    }
    if (!(p.actuator_damping >= 0.0) || !std::isfinite(p.actuator_damping)) {
        return "actuator_damping must be finite and >= 0";
    }
    if (p.max_iterations < 1 || p.max_iterations > 1000) {
        return "max_iterations must be in [1, 1000]";
    }
    if (p.rho_search_iterations < 1 || p.rho_search_iterations > 200) {
        return "rho_search_iterations must be in [1, 200]";
    }
    if (!(p.nullspace_regularisation >= 0.0) || !std::isfinite(p.nullspace_regularisation)) {
        return "nullspace_regularisation must be finite and >= 0";
    }
    return nullptr;
}

KinestheticRenderer::KinestheticRenderer(const DeviceModel& device,
                                         const RenderParameters& parameters)
    : device_(device), parameters_(parameters), projector_(parameters.max_iterations) {
    if (const char* reason = validate(device, parameters)) {
        throw std::invalid_argument(std::string("KinestheticRenderer: ") + reason);
    }
}

const char* KinestheticRenderer::setParameters(const RenderParameters& parameters) noexcept {
    if (const char* reason = validate(device_, parameters)) {
        return reason;
    }
    parameters_ = parameters;
    projector_ = KMetricProjector(parameters.max_iterations);
    reset();
    return nullptr;
}

bool KinestheticRenderer::setTrackingStiffness(double k_a) noexcept {
    if (!(k_a > 0.0) || !std::isfinite(k_a)) {
        return false;
    }
    parameters_.tracking_stiffness = k_a;
    return true;
}

bool KinestheticRenderer::setUserStiffness(double k_u) noexcept {
    if (!(k_u > 0.0) || !std::isfinite(k_u)) {
        return false;
    }
    parameters_.user_stiffness = k_u;
    return true;
}

void KinestheticRenderer::setMethod(RenderingMethod method) noexcept {
    parameters_.method = method;
    reset();
}

void KinestheticRenderer::clearOutput(const ConfigVector& q, RenderFault fault,
                                      RenderOutput& out) noexcept {
    const int n = device_.dofs();
    out.actuator_force.setZero(device_.actuators());
    if (q.size() == n && q.allFinite()) {
        out.proxy = q;
    } else {
        out.proxy.setZero(n);
    }
    out.coupling_force.setZero(n);
    out.rendered_force.setZero(n);
    out.fault = fault;
    out.iterations = 0;
    out.active_constraints = 0;
    out.in_contact = false;
    out.limited = false;
    out.solve_status = SolveStatus::kInvalidInput;
    reset();
}

void KinestheticRenderer::tick(const ConfigVector& q, const ConfigVector& q_dot,
                               std::span<const msgs::LinearConstraint> constraints,
                               RenderOutput& out) noexcept {
    const int n = device_.dofs();
    if (constraints.size() > static_cast<std::size_t>(kMaxConstraintCount)) {
        clearOutput(q, RenderFault::kInvalidConstraints, out);
        return;
    }
    const int count = static_cast<int>(constraints.size());
    C_scratch_.resize(n, count);
    d_scratch_.resize(count);
    const bool state_ok = q.size() == n && q.allFinite();
    bool all_contacts = count > 0;
    ConfigVector gradient;
    for (int j = 0; j < count; ++j) {
        const auto& constraint = constraints[static_cast<std::size_t>(j)];
        const bool usable = state_ok && usableContact(constraint.contact, n);
        all_contacts = all_contacts && usable;
        if (usable && parameters_.method == RenderingMethod::kLinearizedSubspace) {
            // The contact's linearisation at this q, not at the sim's q_ref.
            const double g = contactGap(constraint.contact, q, &gradient);
            C_scratch_.col(j) = gradient;
            d_scratch_[j] = gradient.dot(q) - g;
            continue;
        }
        for (int i = 0; i < n; ++i) {
            C_scratch_(i, j) = constraint.a[static_cast<std::size_t>(i)];
        }
        d_scratch_[j] = constraint.b;
    }
    contacts_ = all_contacts ? constraints : std::span<const msgs::LinearConstraint>{};
    tick(q, q_dot, C_scratch_, d_scratch_, out);
    contacts_ = {};
}

void KinestheticRenderer::tick(const ConfigVector& q, const ConfigVector& q_dot,
                               const ConstraintMatrix& C, const ConstraintVector& d,
                               RenderOutput& out) noexcept {
    const int n = device_.dofs();
    if (q.size() != n || q_dot.size() != n || !q.allFinite() || !q_dot.allFinite()) {
        clearOutput(q, RenderFault::kNonFiniteState, out);
        return;
    }
    if ((C.cols() > 0 && C.rows() != n) || d.size() != C.cols() || !C.allFinite() ||
        !d.allFinite()) {
        clearOutput(q, RenderFault::kInvalidConstraints, out);
        return;
    }
    device_.actuationMatrix(q, B_);
    gram_.noalias() = B_.transpose() * B_;
    const Eigen::LDLT<BoundedMatrix<kMaxActuators, kMaxActuators>> gram_ldlt(gram_);
    if (!B_.allFinite() || gram_ldlt.info() != Eigen::Success ||
        !(gram_ldlt.vectorD().minCoeff() > 1e-14 * (1.0 + gram_.diagonal().maxCoeff()))) {
        clearOutput(q, RenderFault::kNotRenderable, out);
        return;
    }
    P_a_.noalias() = B_ * gram_ldlt.solve(B_.transpose());

    out.fault = RenderFault::kNone;
    out.solve_status = SolveStatus::kOptimal;
    out.iterations = 0;
    out.rho = 1.0;
    out.limited = false;
    switch (parameters_.method) {
        case RenderingMethod::kStandard:
        case RenderingMethod::kNaive:
            renderProxy(1.0, q, C, d, out);
            break;
        case RenderingMethod::kNullspace:
            renderProxy(1.0, q, C, d, out);
            redistributeInNullspace(C, out);
            break;
        case RenderingMethod::kAnisotropic:
            renderProxy(chooseRho(C, d, q), q, C, d, out);
            break;
        case RenderingMethod::kSubspace:
            renderSubspace(q, C, d, out);
            break;
        case RenderingMethod::kLinearizedSubspace:
            renderLinearizedSubspace(q, C, d, out);
            break;
    }
    if (parameters_.method != RenderingMethod::kSubspace &&
        parameters_.method != RenderingMethod::kLinearizedSubspace) {
        out.actuator_force = gram_ldlt.solve(B_.transpose() * out.coupling_force);
    }
    if (out.in_contact && parameters_.actuator_damping > 0.0) {
        out.actuator_force.noalias() -= parameters_.actuator_damping * (B_.transpose() * q_dot);
    }
    if (!out.actuator_force.allFinite()) {
        clearOutput(q, RenderFault::kNotRenderable, out);
        return;
    }
    out.rendered_force.noalias() = B_ * out.actuator_force;
}

double KinestheticRenderer::chooseRho(const ConstraintMatrix& C, const ConstraintVector& d,
                                      const ConfigVector& q) noexcept {
    const double k_a = parameters_.tracking_stiffness;
    switch (parameters_.rho_mode) {
        case RhoMode::kManual:
            return std::clamp(parameters_.rho_override, kMinRho, kMaxRho);
        case RhoMode::kClosedForm:
            return optimalRhoIsotropic(k_a, parameters_.user_stiffness);
        case RhoMode::kNumericSearch:
            break;
    }
    // The search is defined for one plane: use the most penetrated constraint.
    int deepest = -1;
    double depth = 0.0;
    for (int j = 0; j < C.cols(); ++j) {
        const double norm = C.col(j).norm();
        if (norm > 0.0) {
            const double penetration = (d[j] - C.col(j).dot(q)) / norm;
            if (penetration > depth) {
                depth = penetration;
                deepest = j;
            }
        }
    }
    if (deepest < 0) {
        return optimalRhoIsotropic(k_a, parameters_.user_stiffness);
    }
    const int n = device_.dofs();
    ConfigMatrix K_u;
    if (parameters_.user_stiffness_matrix.size() == 0) {
        K_u = parameters_.user_stiffness * ConfigMatrix::Identity(n, n);
    } else {
        K_u = parameters_.user_stiffness_matrix;
    }
    const ConfigVector normal = C.col(deepest);
    const RhoSearchResult search =
        searchOptimalRho(P_a_, k_a, K_u, normal, parameters_.rho_search_iterations);
    return search.valid ? search.rho : optimalRhoIsotropic(k_a, parameters_.user_stiffness);
}

void KinestheticRenderer::renderProxy(double rho, const ConfigVector& q, const ConstraintMatrix& C,
                                      const ConstraintVector& d, RenderOutput& out) noexcept {
    const int n = device_.dofs();
    const double k_a = parameters_.tracking_stiffness;
    out.rho = rho;
    const ConfigMatrix K = k_a * (P_a_ + rho * (ConfigMatrix::Identity(n, n) - P_a_));
    const ProjectionResult result = projector_.project(K, q, C, d, warm_start_, out.proxy);
    warm_start_ = result.active;
    out.solve_status = result.status;
    out.fault = faultOf(result.status);
    out.iterations = result.iterations;
    out.active_constraints = result.active.size;
    out.in_contact = result.active.size > 0;
    out.coupling_force.noalias() = K * (out.proxy - q);
}

void KinestheticRenderer::redistributeInNullspace(const ConstraintMatrix& C,
                                                  RenderOutput& out) noexcept {
    // §5.3: the proxy fixes the contact forces' resultant; the force is moved among the
    // active contacts, keeping the resultant and the total, to the split the actuators render
    // best. Only the rows' own contacts say where each force acts (its Cartesian normal);
    // without them, or with one contact, there is nothing to move and this is naive.
    const int k = warm_start_.size;  // the proxy's active rows, as its solve left them
    if (!out.in_contact || contacts_.empty() || k < 2) {
        return;
    }
    const int n = device_.dofs();
    BoundedMatrix<kMaxDofs, kMaxDofs> A(n, k);  // active rows' gradients, one a column
    // Per contact: its Cartesian normal and a 1. A change in the kernel of these columns moves
    // force between contacts: the resultant and the sum of the magnitudes stay. (Without the
    // sum, opposed normals would let it squeeze the finger harder without limit.)
    BoundedMatrix<4, kMaxDofs> moves(4, k);
    for (int j = 0; j < k; ++j) {
        const auto row = static_cast<std::size_t>(warm_start_.index[static_cast<std::size_t>(j)]);
        A.col(j) = C.col(static_cast<Eigen::Index>(row));
        const auto& normal = contacts_[row].contact.normal;
        moves.col(j) << Eigen::Vector3d(normal[0], normal[1], normal[2]).normalized(), 1.0;
    }
    // Contact force magnitudes mu >= 0 with tau_c = A mu (the proxy's KKT condition).
    const BoundedMatrix<kMaxDofs, kMaxDofs> gram = A.transpose() * A;
    const Eigen::LDLT<BoundedMatrix<kMaxDofs, kMaxDofs>> gram_ldlt(gram);
    if (gram_ldlt.info() != Eigen::Success ||
        !(gram_ldlt.vectorD().minCoeff() > 1e-12 * (1.0 + gram.diagonal().maxCoeff()))) {
        return;  // dependent active rows: the split among them is not defined
    }
    const BoundedVector<kMaxDofs> mu =
        gram_ldlt.solve(A.transpose() * out.coupling_force).cwiseMax(0.0);
    const ConfigMatrix P_u = ConfigMatrix::Identity(n, n) - P_a_;
    const BoundedMatrix<kMaxDofs, kMaxDofs> curvature = A.transpose() * P_u * A;
    const double scale = curvature.trace() / k;  // of |P_u A dmu|^2 per |dmu|^2
    if (!(scale > 0.0)) {
        return;  // every contact's torque is renderable: nothing to gain
    }
    // The moves: eigenvectors v_i of the columns' Gram matrix with eigenvalue l_i below
    // kMoveTolerance (l_i = 0: resultant and total kept exactly). Each is penalised by
    // scale * l_i / (kMoveTolerance - l_i), so a direction that keeps them only nearly counts
    // less, and none as its eigenvalue reaches the tolerance: normals turning apart (a contact
    // reaching an edge) end the redistribution continuously.
    constexpr double kMoveTolerance = 1e-3;  // |resultant and total change|^2 per |dmu|^2
    const BoundedMatrix<kMaxDofs, kMaxDofs> move_gram = moves.transpose() * moves;
    const Eigen::SelfAdjointEigenSolver<BoundedMatrix<kMaxDofs, kMaxDofs>> eigen(move_gram);
    if (eigen.info() != Eigen::Success) {
        return;
    }
    BoundedMatrix<kMaxDofs, kMaxDofs> V(k, k);
    BoundedVector<kMaxDofs> penalty(k);
    int m = 0;
    for (int i = 0; i < k; ++i) {
        const double l = std::max(eigen.eigenvalues()[i], 0.0);
        if (l < kMoveTolerance) {
            V.col(m) = eigen.eigenvectors().col(i);
            penalty[m] = scale * l / (kMoveTolerance - l);
            ++m;
        }
    }
    if (m == 0) {
        return;  // the resultant and the total fix every magnitude
    }
    // dmu = V c minimising |P_u (tau_c + A V c)|^2 + sum_i penalty_i c_i^2 + eps scale |c|^2:
    // its unconstrained minimiser c0, then the minimiser within |dmu_j| <= mu_j (no contact's
    // force changes by more than itself: none goes below 0, and one that has just become
    // active moves nothing), as the K-metric projection of c0 in the objective's own metric
    // onto those bounds (the same active-set solver as the proxy's). The bounded minimiser of a
    // strictly convex objective moves continuously with its data: no force step when a contact
    // becomes active or leaves.
    ConfigMatrix H = V.leftCols(m).transpose() * curvature * V.leftCols(m);
    H.diagonal() += penalty.head(m) + BoundedVector<kMaxDofs>::Constant(
                                          m, parameters_.nullspace_regularisation * scale);
    const Eigen::LDLT<ConfigMatrix> ldlt(H);
    if (ldlt.info() != Eigen::Success) {
        return;
    }
    const ConfigVector c0 =
        ldlt.solve(-(V.leftCols(m).transpose() * (A.transpose() * (P_u * out.coupling_force))));
    static_assert(2 * kMaxDofs <= kMaxConstraintCount, "two bounds per active row");
    ConstraintMatrix bounds(m, 2 * k);
    ConstraintVector limits(2 * k);
    for (int j = 0; j < k; ++j) {
        bounds.col(j) = V.row(j).head(m).transpose();       // dmu_j >= -mu_j
        bounds.col(k + j) = -V.row(j).head(m).transpose();  // -dmu_j >= -mu_j
        limits[j] = -mu[j];
        limits[k + j] = -mu[j];
    }
    ConfigVector c;
    const ProjectionResult bounded = move_projector_.project(H, c0, bounds, limits, {}, c);
    if (bounded.status != SolveStatus::kOptimal || !c.allFinite()) {
        return;  // naive rather than a move the bounds were not checked for
    }
    out.coupling_force.noalias() += A * (V.leftCols(m) * c);
}

void KinestheticRenderer::renderNonlinearSubspace(const ConfigVector& q,
                                                  RenderOutput& out) noexcept {
    const double k_a = parameters_.tracking_stiffness;
    out.rho = kMaxRho;
    const ConfigVector direction = B_.col(0) / k_a;  // q_p(alpha) = q + direction alpha
    // alpha within the force limit, and the proxy within the actuator's stroke (the
    // stroke's room on either side of the current stroke, none beyond a limit).
    const ActuatorLimits limits = device_.actuatorLimits(0);
    ActuatorVector ell;
    device_.actuatorCoordinates(q, ell);
    const double gram = gram_(0, 0);
    const double stroke_up = std::max(0.0, (limits.stroke_max - ell[0]) * k_a / gram);
    const double stroke_down = std::min(0.0, (limits.stroke_min - ell[0]) * k_a / gram);
    const double alpha_max = std::min(limits.max_force_n, stroke_up);
    const double alpha_min = std::max(-limits.max_force_n, stroke_down);
    double push_up = 0.0;
    double push_down = 0.0;
    bool out_of_reach = false;
    int active = 0;
    int evaluations = 0;
    ConfigVector gradient;
    for (const msgs::LinearConstraint& row : contacts_) {
        const double g0 = contactGap(row.contact, q, &gradient);
        if (!std::isfinite(g0) || !gradient.allFinite()) {
            clearOutput(q, RenderFault::kInvalidConstraints, out);
            return;
        }
        if (g0 >= 0.0) {
            continue;
        }
        ++active;
        const double slope = gradient.dot(direction);
        if (std::abs(slope) * k_a <= kActuatedShareEpsilon * std::sqrt(gram) * gradient.norm()) {
            out.fault = RenderFault::kNotRenderable;  // no actuated share: cannot push it out
            continue;
        }
        const ActuatedRoot root = solveAlongActuator(
            row.contact, q, direction, slope > 0.0 ? alpha_max : alpha_min, g0, slope);
        evaluations += root.evaluations;
        out_of_reach = out_of_reach || !root.reached;
        if (root.alpha > 0.0) {
            push_up = std::max(push_up, root.alpha);
        } else {
            push_down = std::min(push_down, root.alpha);
        }
    }
    double alpha = push_up > 0.0 ? push_up : push_down;
    bool infeasible = push_up > 0.0 && push_down < 0.0;  // contacts on both sides
    if (infeasible) {
        alpha = push_up >= -push_down ? push_up : push_down;  // the larger push wins
    }
    // Every contact at the chosen alpha: one that was clear may have been pushed into. (Out
    // of reach, the unreached contact is inside by design: reported as limited instead.)
    if (alpha != 0.0 && !out_of_reach) {
        const ConfigVector q_p = q + direction * alpha;
        for (const msgs::LinearConstraint& row : contacts_) {
            infeasible = infeasible || contactGap(row.contact, q_p) < -kRootToleranceM;
        }
    }
    if (infeasible) {
        out.fault = RenderFault::kInfeasibleConstraints;
        out.solve_status = SolveStatus::kInfeasible;
    }
    // Out of reach within the force limit or the stroke: the limit is rendered; the proxy
    // stays inside. Not a fault (the device does what it can), but reported.
    out.limited = out_of_reach;
    out.actuator_force.resize(1);
    out.actuator_force[0] = alpha;
    out.iterations = evaluations;
    out.active_constraints = active;
    out.in_contact = active > 0;
    out.proxy = q + direction * alpha;
    out.coupling_force.noalias() = B_ * out.actuator_force;
}

void KinestheticRenderer::renderSubspace(const ConfigVector& q, const ConstraintMatrix& C,
                                         const ConstraintVector& d, RenderOutput& out) noexcept {
    if (device_.actuators() == 1 && !contacts_.empty()) {
        renderNonlinearSubspace(q, out);
        return;
    }
    const int m = device_.actuators();
    const int count = static_cast<int>(C.cols());
    const double k_a = parameters_.tracking_stiffness;
    out.rho = kMaxRho;
    ConfigMatrix K_alpha = gram_ / k_a;
    ConstraintMatrix C_alpha(m, count);
    C_alpha.noalias() = B_.transpose() * C / k_a;
    const double b_norm = std::sqrt(gram_.trace());
    bool unrenderable = false;
    for (int j = 0; j < count; ++j) {
        // A normal (almost) outside range(B) cannot be pushed out by the actuators (§5.4).
        if (C_alpha.col(j).norm() * k_a <= kActuatedShareEpsilon * b_norm * C.col(j).norm()) {
            C_alpha.col(j).setZero();
        }
    }
    ConstraintVector d_alpha(count);
    d_alpha.noalias() = d - C.transpose() * q;
    ConfigVector alpha;
    const ConfigVector zero = ConfigVector::Zero(m);
    const ProjectionResult result =
        projector_.project(K_alpha, zero, C_alpha, d_alpha, warm_start_, alpha);
    warm_start_ = result.active;
    out.solve_status = result.status;
    out.fault = faultOf(result.status);
    unrenderable = result.status == SolveStatus::kInfeasible;
    out.iterations = result.iterations;
    out.active_constraints = result.active.size;
    out.in_contact = result.active.size > 0;
    out.actuator_force.resize(m);
    for (int i = 0; i < m; ++i) {
        const double limit = device_.actuatorLimits(i).max_force_n;
        out.actuator_force[i] = std::clamp(alpha[i], -limit, limit);
    }
    if (unrenderable) {
        out.fault = RenderFault::kNotRenderable;
    }
    out.proxy = q + B_ * out.actuator_force / k_a;
    out.coupling_force.noalias() = B_ * out.actuator_force;
}

void KinestheticRenderer::renderLinearizedSubspace(const ConfigVector& q, const ConstraintMatrix& C,
                                                   const ConstraintVector& d,
                                                   RenderOutput& out) noexcept {
    const int m = device_.actuators();
    const double k_a = parameters_.tracking_stiffness;
    out.rho = kMaxRho;
    const Eigen::LDLT<BoundedMatrix<kMaxActuators, kMaxActuators>> gram_ldlt(gram_);
    const double b_norm = std::sqrt(gram_.trace());
    ActuatorVector alpha = ActuatorVector::Zero(m);
    ConfigVector q_p = q;
    int corrected = 0;
    for (int j = 0; j < C.cols(); ++j) {
        const double gap = C.col(j).dot(q_p) - d[j];
        if (gap >= 0.0) {
            continue;
        }
        ActuatorVector w = ActuatorVector::Zero(m);
        w.noalias() = B_.transpose() * C.col(j);
        if (w.norm() <= kActuatedShareEpsilon * b_norm * C.col(j).norm()) {
            out.fault = RenderFault::kNotRenderable;
            continue;
        }
        // Minimum-norm (in B^T B) alpha that brings q + B alpha / k_a onto constraint j.
        const ActuatorVector direction = gram_ldlt.solve(w);
        alpha.noalias() += (-gap * k_a / w.dot(direction)) * direction;
        q_p = q + B_ * alpha / k_a;
        ++corrected;
    }
    out.iterations = 1;
    out.active_constraints = corrected;
    out.in_contact = corrected > 0;
    out.actuator_force.resize(m);
    for (int i = 0; i < m; ++i) {
        const double limit = device_.actuatorLimits(i).max_force_n;
        out.actuator_force[i] = std::clamp(alpha[i], -limit, limit);
    }
    out.proxy = q + B_ * out.actuator_force / k_a;
    out.coupling_force.noalias() = B_ * out.actuator_force;
}

}  // namespace haptic::kinesthetic
