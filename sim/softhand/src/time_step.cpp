// Backward Euler with one Newton step, PCG, and the energy check (docs/algorithms.md §2.6).

#include <algorithm>
#include <cmath>
#include <limits>

#include "energy_terms.hpp"
#include "haptic/softhand/pcg.hpp"
#include "haptic/softhand/simulation.hpp"

namespace haptic::softhand {

namespace {

struct Layout {
    int nodes;
    int bodies;
    [[nodiscard]] int dofs() const { return 3 * nodes + 6 * bodies; }
    [[nodiscard]] int body(int b) const { return 3 * nodes + 6 * b; }
};

}  // namespace

namespace {

void integrate(const Simulation::Configuration& q, const Eigen::VectorXd& velocity, double h,
               Simulation::Configuration& out) {
    out.x = q.x;
    out.c = q.c;
    out.rotation = q.rotation;
    const int nodes = static_cast<int>(q.x.size());
    for (int i = 0; i < nodes; ++i) {
        out.x[i] += h * velocity.segment<3>(3 * i);
    }
    for (std::size_t b = 0; b < q.c.size(); ++b) {
        const int dof = 3 * nodes + 6 * static_cast<int>(b);
        out.c[b] += h * velocity.segment<3>(dof);
        out.rotation[b] = orthonormalized(expMap(h * velocity.segment<3>(dof + 3)) * q.rotation[b]);
    }
}

}  // namespace

// Mass matrix products, DoF mask and velocity vector, by a friend so src/ sees the layout.
struct StepAssembly {
    static void gatherState(const Simulation& sim, const std::vector<Simulation::Body>& bodies,
                            const std::vector<std::array<bool, 3>>& pinned,
                            const std::vector<Vec3>& v, Simulation::Workspace& w) {
        const Layout layout{sim.nodeCount(), sim.bodyCount()};
        const int n = layout.dofs();
        w.free_mask.assign(static_cast<std::size_t>(n), 1);
        w.velocity.resize(n);
        w.body_inertia.resize(bodies.size());
        for (int i = 0; i < layout.nodes; ++i) {
            for (int a = 0; a < 3; ++a) {
                w.free_mask[3 * i + a] = pinned[i][a] ? 0 : 1;
            }
            w.velocity.segment<3>(3 * i) = v[i];
        }
        for (int b = 0; b < layout.bodies; ++b) {
            const auto& body = bodies[b];
            const int dof = layout.body(b);
            w.body_inertia[b] = body.rotation * body.inertia_body * body.rotation.transpose();
            for (int k = 0; k < 6; ++k) {
                w.free_mask[dof + k] = body.kinematic ? 0 : 1;
            }
            w.velocity.segment<3>(dof) = body.kinematic ? Vec3::Zero() : body.v;
            w.velocity.segment<3>(dof + 3) = body.kinematic ? Vec3::Zero() : body.w;
        }
    }

    // out = M v (lumped node masses, 6x6 body blocks).
    static void massTimes(const std::vector<double>& node_mass,
                          const std::vector<Simulation::Body>& bodies,
                          const Simulation::Workspace& w, const Eigen::VectorXd& v,
                          Eigen::VectorXd& out) {
        const int nodes = static_cast<int>(node_mass.size());
        out.resize(v.size());
        for (int i = 0; i < nodes; ++i) {
            out.segment<3>(3 * i) = node_mass[i] * v.segment<3>(3 * i);
        }
        for (std::size_t b = 0; b < bodies.size(); ++b) {
            const int dof = 3 * nodes + 6 * static_cast<int>(b);
            out.segment<3>(dof) = bodies[b].mass * v.segment<3>(dof);
            out.segment<3>(dof + 3) = w.body_inertia[b] * v.segment<3>(dof + 3);
        }
    }

    // Adds c M to the diagonal blocks of `values`.
    static void addMass(const std::vector<double>& node_mass,
                        const std::vector<Simulation::Body>& bodies, Simulation::Workspace& w,
                        double c) {
        using RowBlock = Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>;
        const int nodes = static_cast<int>(node_mass.size());
        for (int i = 0; i < nodes; ++i) {
            RowBlock(w.system.data() + 9 * w.pattern.diagonal(i)).diagonal().array() +=
                c * node_mass[i];
        }
        for (std::size_t b = 0; b < bodies.size(); ++b) {
            const int row = nodes + 2 * static_cast<int>(b);
            RowBlock(w.system.data() + 9 * w.pattern.diagonal(row)).diagonal().array() +=
                c * bodies[b].mass;
            RowBlock(w.system.data() + 9 * w.pattern.diagonal(row + 1)) += c * w.body_inertia[b];
        }
    }
};

StepReport Simulation::step(double dt_s) {
    StepReport report = pending_;
    pending_ = StepReport{};
    report.substeps = 0;
    if (!(dt_s > 0.0) || !std::isfinite(dt_s) || dt_s > 1.0) {
        report.rejected_input = true;
        report.rejection_reason = "time step must be finite and in (0, 1] s";
        report.substeps = 0;
        report.energy_j = energyNow();
        return report;
    }
    advance(dt_s, 0, report);
    report.substepped = report.substeps > 1;
    report.active_contacts = static_cast<int>(contact_forces_.size());
    report.energy_j = energyNow();
    return report;
}

bool Simulation::advance(double h, int depth, StepReport& report) {
    const Layout layout{nodeCount(), bodyCount()};
    const int n = layout.dofs();
    Workspace& w = work_;
    // Nested substeps reuse the workspace: the caller only returns after them.
    currentConfiguration(w.start);
    const Configuration& q = w.start;
    StepAssembly::gatherState(*this, bodies_, pinned_, v_, w);
    const Eigen::VectorXd& velocity = w.velocity;

    // The Newton step starts from the inertial prediction q + h v, where the merit below is
    // evaluated first: linearising there makes the direction a descent direction of the
    // merit, and contacts about to happen this step are already in the set.
    integrate(q, velocity, h, w.predicted);
    detectContacts(w.predicted);

    const int block_rows = layout.nodes + 2 * layout.bodies;
    if (w.pattern.blockRows() != block_rows) {
        w.pattern.build(block_rows, {});
    }
    TermStats stats;
    double potential_predicted = 0.0;
    for (;;) {
        stats = TermStats{};
        Assembler assembler(w.pattern, w.hessian, w.tissue_hessian, w.gradient, w.missing);
        assembler.useElementBlocks(w.tet_slots, tets_.size());
        potential_predicted = EnergyTerms::potential(*this, w.predicted, &assembler, &stats);
        if (w.missing.empty()) {
            break;
        }
        // New blocks (first step, or a contact coupling a node to a new body): the pattern
        // grows and keeps them, so later steps assemble in place.
        std::vector<std::pair<int, int>> blocks = w.missing;
        w.pattern.appendBlocks(blocks);
        w.pattern.build(block_rows, std::move(blocks));
    }
    report.strain_limited_elements = stats.strain_limited_elements;
    report.inverted_elements = stats.inverted_elements;

    const double alpha = settings_.mass_damping_per_s;
    const double gamma = settings_.stiffness_damping_s;
    // Rayleigh damping D = alpha M + gamma H_tissue (tissue only) with H_tissue frozen at the
    // prediction for the whole step, so the merit below is one function across iterations.
    w.damping_hessian.swap(w.tissue_hessian);
    StepAssembly::massTimes(node_mass_, bodies_, w, velocity, w.mass_velocity);
    w.pattern.multiply(w.damping_hessian, velocity, w.tissue_trial);
    const double damping_start =
        alpha * velocity.dot(w.mass_velocity) + gamma * velocity.dot(w.tissue_trial);

    // Energy check. A step is accepted when it lowers the backward-Euler merit
    //   Phi(v+) = 1/2 dv^T M dv + U(q + h v+) + h/2 v+^T D v+   (whose minimiser is the step)
    // and does not raise the total energy 1/2 v^T M v + U(q). The exact backward-Euler step
    // satisfies both for convex energies; one Newton step on a non-convex or non-smooth one
    // (co-rotation, strain limits, friction switching between stick and slip, contacts
    // starting within the step) may not.
    struct Evaluation {
        double merit;
        double energy;
    };
    double trial_tissue = 0.0;  // tissue energy of the last evaluation
    const auto evaluate = [&](const Eigen::VectorXd& v_plus) {
        StepAssembly::massTimes(node_mass_, bodies_, w, v_plus, w.mass_trial);
        w.pattern.multiply(w.damping_hessian, v_plus, w.tissue_trial);
        const double damping =
            alpha * v_plus.dot(w.mass_trial) + gamma * v_plus.dot(w.tissue_trial);
        integrate(q, v_plus, h, w.trial);
        trial_tissue = EnergyTerms::tissue(*this, w.trial, nullptr, nullptr);
        const double potential = trial_tissue + EnergyTerms::external(*this, w.trial, nullptr) +
                                 EnergyTerms::skeleton(*this, w.trial, nullptr) +
                                 EnergyTerms::contact(*this, w.trial, nullptr);
        const double kinetic_change = (v_plus - velocity).dot(w.mass_trial - w.mass_velocity);
        return Evaluation{0.5 * kinetic_change + potential + 0.5 * h * damping,
                          0.5 * v_plus.dot(w.mass_trial) + potential};
    };
    const double energy_before = 0.5 * velocity.dot(w.mass_velocity) + potentialNow(q);
    // Phi(v) is the potential at the prediction, already summed by the assembly above.
    const double merit_start = potential_predicted + 0.5 * h * damping_start;
    const double merit_slack = 1e-12 * std::max(1.0, std::abs(merit_start));
    const double energy_slack = 1e-12 + 1e-9 * std::abs(energy_before);

    // Newton iterations on the merit. Most rejected full steps lower the merit but overshoot
    // where the linearisation was wrong (a node modelled as sliding that the step stops, a
    // node that touches within the step): they were halved and then substepped, each
    // substep a full step again. Relinearising at the better point instead (a damped Newton
    // iteration, with the same acceptance test) reaches the backward-Euler step in one or
    // two more solves; substeps stay the last resort.
    if (warm_start_.size() != n || !warm_start_.allFinite()) {
        warm_start_ = Eigen::VectorXd::Zero(n);
    }
    Eigen::VectorXd& v_plus = w.v_plus;
    Eigen::VectorXd& iterate = w.iterate;
    iterate = velocity;
    double merit_iterate = merit_start;
    bool accepted = false;
    int halvings_left = settings_.max_backtracks;
    // Not with inverted elements: the inversion-safe energy has spurious minima there, and
    // converged iterations settled into one (SofthandStability.InvertedElementsRecover kept
    // 3 elements inverted), where substeps from a fresh prediction get out.
    const int newton_iterations =
        stats.inverted_elements > 0 ? 1 : std::max(1, settings_.max_newton_iterations);
    for (int newton = 0; newton < newton_iterations && std::isfinite(merit_start); ++newton) {
        const bool last = newton + 1 == newton_iterations;
        if (newton > 0) {
            integrate(q, iterate, h, w.trial);
            Assembler assembler(w.pattern, w.hessian, w.tissue_hessian, w.gradient, w.missing,
                                /*keep_tissue_part=*/false);
            assembler.useElementBlocks(w.tet_slots, tets_.size());
            (void)EnergyTerms::potential(*this, w.trial, &assembler, nullptr);
            if (!w.missing.empty()) {
                break;  // a new contact block: the pattern would change under D; substep
            }
            ++report.newton_iterations;
        }
        buildSystem(iterate, h, w);
        w.delta = newton == 0 ? warm_start_ : Eigen::VectorXd::Zero(n);
        const PcgResult pcg = solvePcg(w.pattern, w.system, w.rhs, w.free_mask, w.preconditioner,
                                       settings_.pcg_max_iterations,
                                       settings_.pcg_relative_tolerance, w.delta, w.pcg);
        report.pcg_iterations += pcg.iterations;
        report.pcg_relative_residual = pcg.relative_residual;
        report.pcg_capped = report.pcg_capped || !pcg.converged;
        report.clamped = report.clamped || !pcg.converged;
        if (!w.delta.allFinite()) {
            break;
        }
        if (newton == 0) {
            // The next step starts PCG from the first full Newton direction (not from the
            // accepted, possibly halved or corrected step): with a small iteration cap the
            // scripted scenes track their targets markedly better that way.
            w.first_delta = w.delta;
        }
        double step_fraction = 1.0;
        double previous_excess = std::numeric_limits<double>::infinity();
        bool improved = false;
        for (;;) {
            v_plus = iterate + step_fraction * w.delta;
            const Evaluation value = evaluate(v_plus);
            const bool merit_lowered =
                std::isfinite(value.merit) && value.merit <= merit_start + merit_slack;
            const double excess = value.energy - energy_before;
            if (merit_lowered && excess <= energy_slack) {
                accepted = true;
                break;
            }
            // Not yet acceptable but better than the iterate: linearise again there.
            if (!last && std::isfinite(value.merit) && value.merit < merit_iterate) {
                iterate = v_plus;
                merit_iterate = value.merit;
                improved = true;
                break;
            }
            if (halvings_left-- <= 0) {
                break;
            }
            ++report.backtracks;
            // Only the energy rose, and a shorter step did not shrink the rise at least in
            // proportion: the rise is in the inertial prediction itself, which no shorter
            // Newton step removes; go straight to substeps instead of halving ten times.
            if (merit_lowered && !(excess < 0.75 * previous_excess)) {
                break;
            }
            previous_excess = merit_lowered ? excess : previous_excess;
            step_fraction *= 0.5;
        }
        if (accepted || !improved) {
            break;
        }
    }
    if (!accepted) {
        v_plus = velocity;
    }
    if (!accepted && depth < settings_.max_substep_depth) {
        const bool first = advance(0.5 * h, depth + 1, report);
        const bool second = advance(0.5 * h, depth + 1, report);
        return first && second;
    }
    if (!accepted) {
        // Out of substeps: stop rather than gain energy. Positions stay, velocities vanish.
        report.clamped = true;
        ++report.zeroed_steps;
        v_plus.setZero();
    }
    if (accepted) {
        warm_start_ = w.first_delta;
    } else {
        warm_start_.setZero();
    }

    // Speed clamp: a tracking teleport must not fling tissue across the scene.
    bool speed_clamped = false;
    const double v_max = settings_.max_speed_m_per_s;
    for (int i = 0; i < layout.nodes + layout.bodies; ++i) {
        const int dof = i < layout.nodes ? 3 * i : layout.body(i - layout.nodes);
        const double speed = v_plus.segment<3>(dof).norm();
        if (speed > v_max) {
            v_plus.segment<3>(dof) *= v_max / speed;
            report.clamped = true;
            speed_clamped = true;
        }
    }
    integrate(q, v_plus, h, w.trial);
    // The accepted evaluation was at these very positions unless the clamp moved them: its
    // tissue energy (the costly term) is that of the new state, for the report and the
    // next step's energy check.
    tissue_energy_valid_ = accepted && !speed_clamped;
    tissue_energy_ = trial_tissue;
    const Configuration& next = w.trial;
    for (int i = 0; i < layout.nodes; ++i) {
        x_[i] = next.x[i];
        v_[i] = v_plus.segment<3>(3 * i);
    }
    for (int b = 0; b < layout.bodies; ++b) {
        if (bodies_[b].kinematic) {
            continue;
        }
        bodies_[b].c = next.c[b];
        bodies_[b].rotation = next.rotation[b];
        bodies_[b].v = v_plus.segment<3>(layout.body(b));
        bodies_[b].w = v_plus.segment<3>(layout.body(b) + 3);
    }
    updateAnchors();
    ++report.substeps;
    return accepted;
}

void Simulation::buildSystem(const Eigen::VectorXd& iterate, double h, Workspace& w) {
    const double alpha = settings_.mass_damping_per_s;
    const double gamma = settings_.stiffness_damping_s;
    // System (1 + h alpha) M + h^2 H + h gamma H_tissue; right-hand side minus the merit's
    // gradient at v+ = iterate: M (iterate - v) + h (grad U + D iterate).
    w.system.resize(w.hessian.size());
    for (std::size_t k = 0; k < w.system.size(); ++k) {
        w.system[k] = (h * h) * w.hessian[k] + (h * gamma) * w.damping_hessian[k];
    }
    StepAssembly::addMass(node_mass_, bodies_, w, 1.0 + h * alpha);
    StepAssembly::massTimes(node_mass_, bodies_, w, iterate, w.mass_trial);
    w.pattern.multiply(w.damping_hessian, iterate, w.tissue_trial);
    w.rhs = -h * (w.gradient + alpha * w.mass_trial + gamma * w.tissue_trial);
    w.rhs -= w.mass_trial - w.mass_velocity;
    w.preconditioner.compute(w.pattern, w.system, nodeCount(), w.free_mask);
}

int Simulation::relax(double dt_s, int max_steps, double displacement_tolerance_m) {
    for (int s = 1; s <= max_steps; ++s) {
        for (auto& v : v_) {
            v.setZero();
        }
        for (auto& b : bodies_) {
            b.v.setZero();
            b.w.setZero();
        }
        const std::vector<Vec3> before = x_;
        std::vector<Vec3> body_before;
        for (const auto& b : bodies_) {
            body_before.push_back(b.c);
        }
        const StepReport report = step(dt_s);
        double largest = 0.0;
        for (int i = 0; i < nodeCount(); ++i) {
            largest = std::max(largest, (x_[i] - before[i]).norm());
        }
        for (int b = 0; b < bodyCount(); ++b) {
            largest = std::max(largest, (bodies_[b].c - body_before[b]).norm());
        }
        // A zeroed step (energy check out of substeps) moves nothing but has not converged.
        if (largest < displacement_tolerance_m && !report.clamped) {
            return s;
        }
    }
    return max_steps;
}

double Simulation::kineticEnergy() const noexcept {
    double kinetic = 0.0;
    for (int i = 0; i < nodeCount(); ++i) {
        kinetic += 0.5 * node_mass_[i] * v_[i].squaredNorm();
    }
    for (const auto& b : bodies_) {
        if (b.kinematic) {
            continue;
        }
        const Mat3 inertia = b.rotation * b.inertia_body * b.rotation.transpose();
        kinetic += 0.5 * b.mass * b.v.squaredNorm() + 0.5 * b.w.dot(inertia * b.w);
    }
    return kinetic;
}

double Simulation::totalEnergy() const {
    return kineticEnergy() +
           EnergyTerms::potential(*this, currentConfiguration(), nullptr, nullptr);
}

double Simulation::energyNow() {
    currentConfiguration(work_.start);
    return kineticEnergy() + potentialNow(work_.start);
}

double Simulation::potentialNow(const Configuration& q) {
    if (!tissue_energy_valid_) {
        tissue_energy_ = EnergyTerms::tissue(*this, q, nullptr, nullptr);
        tissue_energy_valid_ = true;
    }
    return tissue_energy_ + EnergyTerms::external(*this, q, nullptr) +
           EnergyTerms::skeleton(*this, q, nullptr) + EnergyTerms::contact(*this, q, nullptr);
}

}  // namespace haptic::softhand
