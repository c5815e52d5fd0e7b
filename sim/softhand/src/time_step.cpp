// Backward Euler with one Newton step, PCG, and the energy check (ALGORITHMS.md §2.6).

#include <algorithm>
#include <cmath>

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

// Mass matrix, DoF mask and velocity vector, built by a friend so src/ can see the layout.
struct StepAssembly {
    static void build(const Simulation& sim, const std::vector<Simulation::Body>& bodies,
                      const std::vector<std::array<bool, 3>>& pinned,
                      const std::vector<double>& node_mass, const std::vector<Vec3>& v,
                      SparseMatrix& mass, std::vector<char>& free_mask, Eigen::VectorXd& velocity,
                      std::vector<std::pair<int, int>>& blocks) {
        const Layout layout{sim.nodeCount(), sim.bodyCount()};
        const int n = layout.dofs();
        std::vector<Eigen::Triplet<double>> triplets;
        free_mask.assign(static_cast<std::size_t>(n), 1);
        velocity.resize(n);
        blocks.clear();
        for (int i = 0; i < layout.nodes; ++i) {
            for (int a = 0; a < 3; ++a) {
                triplets.emplace_back(3 * i + a, 3 * i + a, node_mass[i]);
                free_mask[3 * i + a] = pinned[i][a] ? 0 : 1;
            }
            velocity.segment<3>(3 * i) = v[i];
            blocks.emplace_back(3 * i, 3);
        }
        for (int b = 0; b < layout.bodies; ++b) {
            const auto& body = bodies[b];
            const int dof = layout.body(b);
            const Mat3 inertia = body.rotation * body.inertia_body * body.rotation.transpose();
            for (int r = 0; r < 3; ++r) {
                triplets.emplace_back(dof + r, dof + r, body.mass);
                for (int c = 0; c < 3; ++c) {
                    triplets.emplace_back(dof + 3 + r, dof + 3 + c, inertia(r, c));
                }
            }
            for (int k = 0; k < 6; ++k) {
                free_mask[dof + k] = body.kinematic ? 0 : 1;
            }
            velocity.segment<3>(dof) = body.kinematic ? Vec3::Zero() : body.v;
            velocity.segment<3>(dof + 3) = body.kinematic ? Vec3::Zero() : body.w;
            blocks.emplace_back(dof, 6);
        }
        mass.resize(n, n);
        mass.setFromTriplets(triplets.begin(), triplets.end());
    }
};

namespace {

Simulation::Configuration integrate(const Simulation::Configuration& q,
                                    const Eigen::VectorXd& velocity, double h) {
    Simulation::Configuration out = q;
    const int nodes = static_cast<int>(q.x.size());
    for (int i = 0; i < nodes; ++i) {
        out.x[i] += h * velocity.segment<3>(3 * i);
    }
    for (std::size_t b = 0; b < q.c.size(); ++b) {
        const int dof = 3 * nodes + 6 * static_cast<int>(b);
        out.c[b] += h * velocity.segment<3>(dof);
        out.rotation[b] = orthonormalized(expMap(h * velocity.segment<3>(dof + 3)) * q.rotation[b]);
    }
    return out;
}

}  // namespace

StepReport Simulation::step(double dt_s) {
    StepReport report = pending_;
    pending_ = StepReport{};
    report.substeps = 0;
    if (!(dt_s > 0.0) || !std::isfinite(dt_s) || dt_s > 1.0) {
        report.rejected_input = true;
        report.rejection_reason = "time step must be finite and in (0, 1] s";
        report.substeps = 0;
        report.energy_j = totalEnergy();
        return report;
    }
    advance(dt_s, 0, report);
    report.substepped = report.substeps > 1;
    report.active_contacts = static_cast<int>(contact_forces_.size());
    report.energy_j = totalEnergy();
    return report;
}

bool Simulation::advance(double h, int depth, StepReport& report) {
    const Layout layout{nodeCount(), bodyCount()};
    const int n = layout.dofs();
    const Configuration q = currentConfiguration();

    SparseMatrix mass;
    std::vector<char> free_mask;
    Eigen::VectorXd velocity;
    std::vector<std::pair<int, int>> blocks;
    StepAssembly::build(*this, bodies_, pinned_, node_mass_, v_, mass, free_mask, velocity, blocks);

    // The Newton step starts from the inertial prediction q + h v, where the merit below is
    // evaluated first: linearising there makes the direction a descent direction of the
    // merit, and contacts about to happen this step are already in the set.
    const Configuration predicted = integrate(q, velocity, h);
    detectContacts(predicted);

    Assembler assembler(n);
    TermStats stats;
    // The assembled energy at the prediction is the merit's start value (same contact set:
    // every penetrating node was just detected there), so it is not evaluated twice.
    const double potential_predicted = EnergyTerms::potential(*this, predicted, &assembler, &stats);
    SparseMatrix tissue_hessian(n, n);
    tissue_hessian.setFromTriplets(assembler.tissue_triplets.begin(),
                                   assembler.tissue_triplets.end());
    SparseMatrix hessian(n, n);
    hessian.setFromTriplets(assembler.triplets.begin(), assembler.triplets.end());
    hessian += tissue_hessian;

    const double alpha = settings_.mass_damping_per_s;
    const double gamma = settings_.stiffness_damping_s;
    // D = alpha M + gamma H_tissue (Rayleigh on the tissue only).
    const SparseMatrix system =
        (1.0 + h * alpha) * mass + (h * h) * hessian + (h * gamma) * tissue_hessian;
    const Eigen::VectorXd damping_v =
        alpha * (mass * velocity) + gamma * (tissue_hessian * velocity);
    const Eigen::VectorXd rhs = -h * (assembler.gradient + damping_v);

    BlockJacobiPreconditioner preconditioner;
    preconditioner.compute(system, blocks, free_mask);
    if (warm_start_.size() != n || !warm_start_.allFinite()) {
        warm_start_ = Eigen::VectorXd::Zero(n);
    }
    Eigen::VectorXd delta = warm_start_;
    const PcgResult pcg =
        solvePcg(system, rhs, free_mask, preconditioner, settings_.pcg_max_iterations,
                 settings_.pcg_relative_tolerance, delta);
    report.pcg_iterations += pcg.iterations;
    report.pcg_relative_residual = pcg.relative_residual;
    if (!pcg.converged) {
        report.pcg_capped = true;
        report.clamped = true;
    }
    report.strain_limited_elements = stats.strain_limited_elements;
    report.inverted_elements = stats.inverted_elements;

    // Energy check. A step is accepted when it lowers the backward-Euler merit
    //   Phi(v+) = 1/2 dv^T M dv + U(q + h v+) + h/2 v+^T D v+   (whose minimiser is the step)
    // and does not raise the total energy 1/2 v^T M v + U(q). The exact backward-Euler step
    // satisfies both for convex energies; one Newton step on a non-convex or non-smooth one
    // (co-rotation, strain limits, contact set changes) may not, and then it is halved.
    struct Evaluation {
        double merit;
        double energy;
        double tissue;
    };
    const auto evaluate = [&](const Eigen::VectorXd& v_plus) {
        const Eigen::VectorXd dv = v_plus - velocity;
        const Eigen::VectorXd m_v = mass * v_plus;
        const double damping =
            alpha * v_plus.dot(m_v) + gamma * v_plus.dot(tissue_hessian * v_plus);
        const Configuration next = integrate(q, v_plus, h);
        const double tissue = EnergyTerms::tissue(*this, next, nullptr, nullptr);
        const double potential = tissue + EnergyTerms::external(*this, next, nullptr) +
                                 EnergyTerms::skeleton(*this, next, nullptr) +
                                 EnergyTerms::contact(*this, next, nullptr);
        return Evaluation{0.5 * dv.dot(mass * dv) + potential + 0.5 * h * damping,
                          0.5 * v_plus.dot(m_v) + potential, tissue};
    };
    const double energy_before = 0.5 * velocity.dot(mass * velocity) + currentTissueEnergy() +
                                 EnergyTerms::external(*this, q, nullptr) +
                                 EnergyTerms::skeleton(*this, q, nullptr) +
                                 EnergyTerms::contact(*this, q, nullptr);
    const double merit_start =
        potential_predicted + 0.5 * h *
                                  (alpha * velocity.dot(mass * velocity) +
                                   gamma * velocity.dot(tissue_hessian * velocity));
    const double energy_slack = 1e-12 + 1e-9 * std::abs(energy_before);
    double step_fraction = 1.0;
    bool accepted = false;
    double accepted_tissue = 0.0;
    Eigen::VectorXd v_plus = velocity;
    if (delta.allFinite() && std::isfinite(merit_start)) {
        for (int attempt = 0; attempt <= settings_.max_backtracks; ++attempt) {
            v_plus = velocity + step_fraction * delta;
            const Evaluation value = evaluate(v_plus);
            if (std::isfinite(value.merit) &&
                value.merit <= merit_start + 1e-12 * std::max(1.0, std::abs(merit_start)) &&
                value.energy <= energy_before + energy_slack) {
                accepted = true;
                accepted_tissue = value.tissue;
                break;
            }
            ++report.backtracks;
            step_fraction *= 0.5;
        }
    }
    if (!accepted && depth < settings_.max_substep_depth) {
        const bool first = advance(0.5 * h, depth + 1, report);
        const bool second = advance(0.5 * h, depth + 1, report);
        return first && second;
    }
    if (!accepted) {
        // Out of substeps: stop rather than gain energy. Positions stay, velocities vanish.
        report.clamped = true;
        v_plus.setZero();
    }
    warm_start_ = accepted ? delta : Eigen::VectorXd::Zero(n);

    // Speed clamp: a tracking teleport must not fling tissue across the scene.
    const double v_max = settings_.max_speed_m_per_s;
    bool nodes_clamped = false;
    for (int i = 0; i < layout.nodes + layout.bodies; ++i) {
        const int dof = i < layout.nodes ? 3 * i : layout.body(i - layout.nodes);
        const double speed = v_plus.segment<3>(dof).norm();
        if (speed > v_max) {
            v_plus.segment<3>(dof) *= v_max / speed;
            report.clamped = true;
            nodes_clamped = nodes_clamped || i < layout.nodes;
        }
    }
    const Configuration next = integrate(q, v_plus, h);
    for (int i = 0; i < layout.nodes; ++i) {
        x_[i] = next.x[i];
        ++x_generation_;
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
    if (accepted && !nodes_clamped) {
        // The nodes are where the accepted evaluation put them: its tissue energy is current.
        tissue_energy_j_ = accepted_tissue;
        tissue_energy_generation_ = x_generation_;
    }
    updateAnchors();
    ++report.substeps;
    return accepted;
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

double Simulation::totalEnergy() const {
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
    const Configuration q = currentConfiguration();
    return kinetic + currentTissueEnergy() + EnergyTerms::external(*this, q, nullptr) +
           EnergyTerms::skeleton(*this, q, nullptr) + EnergyTerms::contact(*this, q, nullptr);
}

double Simulation::currentTissueEnergy() const {
    if (tissue_energy_generation_ != x_generation_) {
        tissue_energy_j_ = EnergyTerms::tissue(*this, currentConfiguration(), nullptr, nullptr);
        tissue_energy_generation_ = x_generation_;
    }
    return tissue_energy_j_;
}

}  // namespace haptic::softhand
