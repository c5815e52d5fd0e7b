// Backward Euler: Newton on the merit with an Armijo line search, PCG, and the energy guard
// (docs/algorithms.md §2.6).

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>

#include "energy_terms.hpp"
#include "haptic/softhand/helper_thread.hpp"
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

// Armijo's sufficient-decrease constant, and the halvings a line search along a PCG direction
// solved from zero may take at least (down to 1/64 of it, rather than no step). 16 moved the
// fingertip benchmark no differently and tripled the grasp scene's median step (2.8 against
// 1.2 ms), whose failed searches then took all of them.
constexpr double kArmijo = 1e-4;
constexpr int kColdHalvings = 6;
constexpr double kSignificantMove_m = 1e-5;

// Adds the assembly's missing blocks to the pattern within a step. The Rayleigh part of the
// system, frozen at the prediction, moves to the new pattern's slots (the new blocks are
// contact couplings, which carry no tissue damping). Allocates, but only when a contact
// couples a node to a body for the first time: the pattern keeps its blocks.
void growPattern(int block_rows, Simulation::Workspace& w) {
    const BlockPattern old = w.pattern;
    std::vector<std::pair<int, int>> blocks = w.missing;
    w.pattern.appendBlocks(blocks);
    w.pattern.build(block_rows, std::move(blocks));
    std::vector<double> damping(9 * static_cast<std::size_t>(w.pattern.blockCount()), 0.0);
    for (int row = 0; row < old.blockRows(); ++row) {
        for (int k = old.rowBegin(row); k < old.rowEnd(row); ++k) {
            const int slot = w.pattern.find(row, old.column(k));
            std::copy_n(w.damping_hessian.begin() + 9 * static_cast<std::ptrdiff_t>(k), 9,
                        damping.begin() + 9 * static_cast<std::ptrdiff_t>(slot));
        }
    }
    w.damping_hessian.swap(damping);
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
    const std::uint64_t helper_jobs_before = helper_ ? helper_->jobsRun() : 0;
    advance(dt_s, 0, report, std::numeric_limits<double>::quiet_NaN());
    // Every job is collected or taken back before advance() returns.
    report.helper_jobs = helper_ ? static_cast<int>(helper_->jobsRun() - helper_jobs_before) : 0;
    report.substepped = report.substeps > 1;
    report.active_contacts = static_cast<int>(contact_forces_.size());
    report.energy_j = energyNow();
    return report;
}

bool Simulation::advance(double h, int depth, StepReport& report, double energy_reference) {
    const Layout layout{nodeCount(), bodyCount()};
    const int n = layout.dofs();
    Workspace& w = work_;
    if (settings_.use_helper_thread && settings_.linear_solver == LinearSolver::kPcg) {
        if (!helper_) {
            helper_ = std::make_unique<HelperThread>();
        }
        // Between steps the helper sleeps on its timer until shortly before the next one is
        // due (a caller stepping at dt: handsim), then polls. A caller off that beat wakes it
        // here with an empty job, which a job started after the assembly below may still find
        // asleep (then the step takes the job back and does it itself). A substep runs inside
        // a step that already woke it.
        if (depth == 0) {
            helper_->wake();
            helper_->expectNextJobAt(
                std::chrono::steady_clock::now() +
                std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                    std::chrono::duration<double>(h)));
        }
    } else {
        helper_.reset();
    }
    // Nested substeps reuse the workspace: the caller only returns after them.
    currentConfiguration(w.start);
    const Configuration& q = w.start;
    StepAssembly::gatherState(*this, bodies_, pinned_, v_, w);
    const Eigen::VectorXd& velocity = w.velocity;

    // The Newton step starts from the inertial prediction q + h v, where the merit below is
    // evaluated first: linearising there makes the direction a descent direction of the
    // merit, and contacts about to happen this step are already in the set.
    integrate(q, velocity, h, w.predicted);
    // The energy guard's reference: the state as the last step left it, with the inputs set
    // since (targets, collider poses) and the contact set it ended with. Taken before the
    // contacts are detected at the prediction: a new contact's friction anchor is placed at
    // the predicted point, so at q its spring is already stretched by the node's travel
    // within the step, energy that no state ever held (at 1 kPa and 33 ms it let a step
    // gain joules while the guard saw a fall).
    // A first substep starts from its parent's state, whose contact set the parent already
    // replaced: it takes the parent's reference.
    const double energy_before =
        std::isnan(energy_reference) ? kineticEnergy() + potentialNow(q) : energy_reference;
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

    // The step minimises the backward-Euler merit
    //   Phi(v+) = 1/2 dv^T M dv + U(q + h v+) + h/2 v+^T D v+
    // by Newton iterations with an Armijo line search on Phi (docs/algorithms.md §2.6). The
    // system matrix is positive definite (co-rotated stiffness with R frozen, Gauss-Newton
    // residual terms), so a PCG direction started from zero descends; a warm-started one is
    // checked and replaced when it does not. Every accepted iterate lowers Phi, so the step
    // always advances to the best iterate found. The total energy 1/2 v^T M v + U(q) is a
    // guard, not an acceptance test: lowering Phi does not imply lowering it when U is
    // non-convex or the contact set changes within the step, and the only point certain to
    // pass it is v+ = 0, a frozen frame. When it rises, the step is first split into
    // substeps (where the limits allow), then its velocities are scaled down until the rise
    // is gone; positions keep the Newton result.
    struct Evaluation {
        double merit;
        double energy;
        double tissue;
    };
    // Reads the step's state only and writes the buffers it is given, so that the helper
    // thread can evaluate one point (into the w.ahead_* buffers) while this thread does
    // another.
    const auto evaluate_into = [&](const Eigen::VectorXd& v_trial, Eigen::VectorXd& mass_trial,
                                   Eigen::VectorXd& tissue_trial, Configuration& trial) {
        StepAssembly::massTimes(node_mass_, bodies_, w, v_trial, mass_trial);
        w.pattern.multiply(w.damping_hessian, v_trial, tissue_trial);
        const double damping = alpha * v_trial.dot(mass_trial) + gamma * v_trial.dot(tissue_trial);
        integrate(q, v_trial, h, trial);
        const double tissue = EnergyTerms::tissue(*this, trial, nullptr, nullptr);
        const double potential = tissue + EnergyTerms::external(*this, trial, nullptr) +
                                 EnergyTerms::skeleton(*this, trial, nullptr) +
                                 EnergyTerms::contact(*this, trial, nullptr);
        const double kinetic_change = (v_trial - velocity).dot(mass_trial - w.mass_velocity);
        return Evaluation{0.5 * kinetic_change + potential + 0.5 * h * damping,
                          0.5 * v_trial.dot(mass_trial) + potential, tissue};
    };
    const auto evaluate = [&](const Eigen::VectorXd& v_trial) {
        return evaluate_into(v_trial, w.mass_trial, w.tissue_trial, w.trial);
    };
    // Phi(v) is the potential at the prediction, already summed by the assembly above.
    const double merit_start = potential_predicted + 0.5 * h * damping_start;
    const double energy_slack = 1e-12 + 1e-9 * std::abs(energy_before);

    if (warm_start_.size() != n || !warm_start_.allFinite()) {
        warm_start_ = Eigen::VectorXd::Zero(n);
    }
    Eigen::VectorXd& v_plus = w.v_plus;
    Eigen::VectorXd& iterate = w.iterate;
    iterate = velocity;
    w.first_delta.setZero(n);
    // Not with inverted elements: the inversion-safe energy has spurious minima there, and
    // converged iterations settled into one (SofthandStability.InvertedElementsRecover kept
    // 3 elements inverted), where substeps from a fresh prediction get out.
    const int newton_iterations =
        stats.inverted_elements > 0 ? 1 : std::max(1, settings_.max_newton_iterations);
    // The helper thread's jobs. Each is withdrawn (taken back, or waited for) before anything
    // it reads changes: at the next Newton iteration's assembly, and after the loop.
    HelperThread* helper = helper_.get();
    if (helper != nullptr) {
        // Sized here so that the helper's jobs allocate nothing.
        w.cold_delta.setZero(n);
        w.cold_pcg.resize(n);
        w.ahead_v.resize(n);
        w.ahead_mass.resize(n);
        w.ahead_tissue.resize(n);
        if (w.ahead_trial.x.size() != q.x.size() || w.ahead_trial.c.size() != q.c.size()) {
            w.ahead_trial = q;
        }
    }
    struct ColdSolve {
        Workspace* w;
        int max_iterations;
        double relative_tolerance;
        PcgResult result;
        std::atomic<bool> stop{false};
    } cold{&w, settings_.pcg_max_iterations, settings_.pcg_relative_tolerance, {}, {}};
    const auto solve_cold = [](void* context) {
        auto& job = *static_cast<ColdSolve*>(context);
        Workspace& work = *job.w;
        work.cold_delta.setZero();
        job.result = solvePcg(work.pattern, work.system, work.rhs, work.free_mask,
                              work.preconditioner, job.max_iterations, job.relative_tolerance,
                              work.cold_delta, work.cold_pcg, &job.stop);
    };
    struct PointAhead {
        const decltype(evaluate_into)* evaluate;
        Workspace* w;
        Evaluation value;
    } ahead{&evaluate_into, &w, {}};
    const auto evaluate_ahead = [](void* context) {
        auto& job = *static_cast<PointAhead*>(context);
        Workspace& work = *job.w;
        job.value =
            (*job.evaluate)(work.ahead_v, work.ahead_mass, work.ahead_tissue, work.ahead_trial);
    };
    // Phi (and, once evaluated, E) at `iterate`; its merit is the line search's reference.
    bool evaluated_iterate = false;
    Evaluation iterate_value{merit_start, 0.0, 0.0};
    const bool direct = settings_.linear_solver == LinearSolver::kSparseLdlt;
    for (int newton = 0; newton < newton_iterations && std::isfinite(merit_start); ++newton) {
        if (newton > 0) {
            if (helper != nullptr) {
                (void)helper->withdraw();
            }
            integrate(q, iterate, h, w.trial);
            for (;;) {
                Assembler assembler(w.pattern, w.hessian, w.tissue_hessian, w.gradient, w.missing,
                                    /*keep_tissue_part=*/false);
                assembler.useElementBlocks(w.tet_slots, tets_.size());
                (void)EnergyTerms::potential(*this, w.trial, &assembler, nullptr);
                if (w.missing.empty()) {
                    break;
                }
                growPattern(block_rows, w);  // a contact couples a node to a new body
            }
            ++report.newton_iterations;
        }
        buildSystem(iterate, h, w);
        // The first iteration's PCG starts from the last step's direction. When that
        // direction does not descend, or its line search finds no lower Phi, the solve is
        // repeated from zero, whose every PCG iterate descends, and its line search may
        // halve further: the trap this closes was a capped warm-started direction 4x too
        // long that the next step warm-started from again, freezing the fingertip scene.
        // The direct solver has no warm start; its direction is exact, so it gets the same
        // halvings as a warm PCG solve (the extra cold halvings are PCG's trap remedy).
        bool warm = newton == 0 && !direct;
        // Under way on the helper, the cold solve that a failed warm one falls back to.
        enum class Cold { kNone, kRunning, kCollected } cold_state = Cold::kNone;
        if (warm && helper != nullptr) {
            cold.stop.store(false);
            helper->start(solve_cold, &cold);
            cold_state = Cold::kRunning;
        }
        double decrement = 0.0;
        double best_fraction = 0.0;
        bool sufficient = false;
        Evaluation best_value = iterate_value;
        for (;;) {
            if (warm) {
                w.delta = warm_start_;
            } else {
                w.delta.setZero(n);
            }
            if (direct && w.direct.solve(w.pattern, w.system, w.rhs, w.free_mask, w.delta)) {
                report.pcg_relative_residual = 0.0;
            } else {
                // The factorisation fails only on a system that is not positive definite to
                // roundoff; PCG from zero still returns a descent direction there (its
                // iterations in the report tell such a fallback).
                if (direct) {
                    w.preconditioner.compute(w.pattern, w.system, nodeCount(), w.free_mask);
                }
                PcgResult pcg;
                // The helper's cold solve, unless it had not begun it (then solved here).
                const bool cold_ready =
                    !warm && (cold_state == Cold::kCollected ||
                              (cold_state == Cold::kRunning && !helper->withdraw()));
                cold_state = warm ? cold_state : Cold::kNone;
                if (cold_ready) {
                    w.delta = w.cold_delta;
                    pcg = cold.result;
                    ++report.helper_results_used;
                } else {
                    pcg = solvePcg(w.pattern, w.system, w.rhs, w.free_mask, w.preconditioner,
                                   settings_.pcg_max_iterations, settings_.pcg_relative_tolerance,
                                   w.delta, w.pcg);
                }
                report.pcg_iterations += pcg.iterations;
                report.pcg_relative_residual = pcg.relative_residual;
                report.pcg_capped = report.pcg_capped || !pcg.converged;
                report.clamped = report.clamped || !pcg.converged;
            }
            decrement = w.rhs.dot(w.delta);  // -slope of Phi along delta
            const bool descends = w.delta.allFinite() && decrement > 0.0;
            // A direction that moves no DoF by more than this over the step is a correction
            // below what any output resolves: its line search failing is roundoff at a
            // minimum (seen in steady sliding), not a trap, and is not worth a second solve.
            const bool significant =
                descends && h * w.delta.lpNorm<Eigen::Infinity>() > kSignificantMove_m;
            if (descends) {
                // Armijo backtracking on Phi; when the halvings run out, the lowest Phi
                // seen, if it is below the iterate's.
                const int halvings = warm || direct || !significant
                                         ? settings_.max_backtracks
                                         : std::max(settings_.max_backtracks, kColdHalvings);
                double step_fraction = 1.0;
                best_value = iterate_value;
                // Once a point has failed, the helper evaluates the next halving while this
                // thread evaluates the current one; `ahead_pending`: its point is the current
                // one.
                bool ahead_pending = false;
                for (int halving = 0;; ++halving) {
                    Evaluation value;
                    if (ahead_pending && !helper->withdraw()) {
                        value = ahead.value;
                        ahead_pending = false;
                        ++report.helper_results_used;
                    } else {
                        ahead_pending = false;  // taken back before it began: evaluated here
                        // Free once the cold solve is done (collected here, kept for later).
                        const bool helper_free =
                            helper != nullptr && (cold_state != Cold::kRunning || helper->done());
                        // From the second point on: the first usually passes, and a point
                        // ahead that the helper has begun is waited for when withdrawn.
                        if (helper_free && halving > 0 && halving < halvings) {
                            if (cold_state == Cold::kRunning) {
                                helper->wait();  // done: its result stays for a restart
                                cold_state = Cold::kCollected;
                            }
                            w.ahead_v = iterate + (0.5 * step_fraction) * w.delta;
                            helper->start(evaluate_ahead, &ahead);
                            ahead_pending = true;
                        }
                        v_plus = iterate + step_fraction * w.delta;
                        value = evaluate(v_plus);
                    }
                    if (std::isfinite(value.merit) && value.merit < best_value.merit) {
                        best_value = value;
                        best_fraction = step_fraction;
                    }
                    if (std::isfinite(value.merit) &&
                        value.merit <= iterate_value.merit - kArmijo * step_fraction * decrement) {
                        sufficient = true;
                        break;  // a point still being evaluated ahead is withdrawn later
                    }
                    if (halving >= halvings) {
                        break;
                    }
                    ++report.backtracks;
                    step_fraction *= 0.5;
                }
            }
            if (best_fraction > 0.0 || !warm || (descends && !significant)) {
                break;
            }
            warm = false;
            ++report.restarted_solves;
        }
        if (cold_state == Cold::kRunning) {
            cold.stop.store(true);  // the warm direction served: end the cold solve early
        }
        if (newton == 0) {
            // The next step starts PCG from this step's first Newton direction (not from
            // the accepted, possibly shortened step): with a small iteration cap the
            // scripted scenes track their targets markedly better that way.
            w.first_delta = w.delta;
        }
        if (best_fraction == 0.0) {
            break;  // no lower Phi along a descent direction: at a minimum to precision
        }
        iterate += best_fraction * w.delta;
        iterate_value = best_value;
        evaluated_iterate = true;
        // Done when this iteration moved no DoF by more than the tolerance over the step
        // and the energy guard passes. An iterate that still raises the energy gets the
        // iterations left before the guard's remedy.
        const double moved_m = h * best_fraction * w.delta.lpNorm<Eigen::Infinity>();
        const bool energy_ok = best_value.energy - energy_before <= energy_slack;
        if (!sufficient || (energy_ok && moved_m <= settings_.newton_tolerance_m)) {
            break;
        }
    }
    if (helper != nullptr) {
        (void)helper->withdraw();  // before the state its jobs read changes
    }
    if (!evaluated_iterate) {
        iterate_value = evaluate(iterate);
    }
    v_plus = iterate;
    const double excess = iterate_value.energy - energy_before;
    const bool energy_rose = !(excess <= energy_slack);
    const bool finite = std::isfinite(iterate_value.energy) && iterate.allFinite();
    if (energy_rose && depth < settings_.max_substep_depth) {
        const bool first = advance(0.5 * h, depth + 1, report, energy_before);
        const bool second = advance(0.5 * h, depth + 1, report);
        return first && second;
    }
    // Not as one conditional expression: its two sides' common type is a new VectorXd, whose
    // copy allocated on every step.
    if (w.first_delta.size() == n && w.first_delta.allFinite()) {
        warm_start_ = w.first_delta;
    } else {
        warm_start_.setZero(n);
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
    if (!finite) {
        // Nothing finite to advance to (a non-finite input got past the checks): hold the
        // positions and stop. The one case that freezes a step; counted apart.
        ++report.zeroed_steps;
        report.clamped = true;
        v_plus.setZero();
    }
    integrate(q, v_plus, h, w.trial);
    if (energy_rose && finite) {
        // Out of substeps: the positions keep the Newton result and the velocities are
        // scaled so that the kinetic energy is what the energy before the step leaves above
        // the new potential (zero when the new potential alone exceeds it; from rest the
        // next step cannot rise, since Phi(v+) <= Phi(0) bounds its potential by this one).
        report.clamped = true;
        ++report.rescaled_steps;
        StepAssembly::massTimes(node_mass_, bodies_, w, iterate, w.mass_trial);
        const double kinetic = 0.5 * iterate.dot(w.mass_trial);
        const double potential_after = iterate_value.energy - kinetic;
        const double allowed = std::max(0.0, energy_before - potential_after);
        const double scale = kinetic > 0.0 && std::isfinite(allowed / kinetic)
                                 ? std::sqrt(std::min(1.0, allowed / kinetic))
                                 : 0.0;
        v_plus *= scale;
    }
    // The evaluation at the iterate was at these very positions unless the clamp moved
    // them: its tissue energy (the costly term) is that of the new state, for the report
    // and the next step's energy guard.
    tissue_energy_valid_ = finite && !speed_clamped;
    tissue_energy_ = iterate_value.tissue;
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
    return !energy_rose;
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
    if (settings_.linear_solver == LinearSolver::kPcg) {
        w.preconditioner.compute(w.pattern, w.system, nodeCount(), w.free_mask);
    }
}

}  // namespace haptic::softhand
