#include "haptic/softhand/simulation.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "energy_terms.hpp"
#include "haptic/softhand/pcg.hpp"

namespace haptic::softhand {

namespace {

bool finite(const Vec3& v) {
    return v.allFinite();
}

bool isRotation(const Mat3& r) {
    return r.allFinite() && (r.transpose() * r - Mat3::Identity()).norm() < 1e-6 &&
           r.determinant() > 0.0;
}

}  // namespace

Simulation::Simulation(SolverSettings settings) : settings_(settings) {}

int Simulation::addTissue(const TetMesh& mesh, const TissueMaterial& m) {
    if (!(m.youngs_modulus_pa > 0.0) || !(m.poisson_ratio >= 0.0 && m.poisson_ratio < 0.5) ||
        !(m.density_kg_per_m3 > 0.0)) {
        throw std::invalid_argument("addTissue: E > 0, 0 <= nu < 0.5 and density > 0 required");
    }
    const int first = nodeCount();
    tissue_energy_valid_ = false;
    for (const Vec3& p : mesh.nodes_m) {
        rest_.push_back(p);
        x_.push_back(p);
        v_.push_back(Vec3::Zero());
        node_mass_.push_back(0.0);
        node_force_.push_back(Vec3::Zero());
        pinned_.push_back({false, false, false});
    }
    const double mu = m.youngs_modulus_pa / (2.0 * (1.0 + m.poisson_ratio));
    const double lambda = m.youngs_modulus_pa * m.poisson_ratio /
                          ((1.0 + m.poisson_ratio) * (1.0 - 2.0 * m.poisson_ratio));
    for (const auto& local : mesh.tets) {
        Tet tet{};
        for (int c = 0; c < 4; ++c) {
            tet.nodes[c] = first + local[c];
        }
        Mat3 dm;
        for (int c = 0; c < 3; ++c) {
            dm.col(c) = mesh.nodes_m[local[c + 1]] - mesh.nodes_m[local[0]];
        }
        tet.volume_m3 = dm.determinant() / 6.0;
        if (!(tet.volume_m3 > 0.0)) {
            throw std::invalid_argument("addTissue: rest tetrahedron with non-positive volume");
        }
        tet.rest_inverse = dm.inverse();
        tet.mu = mu;
        tet.lambda = lambda;
        tet.limit_stiffness = m.strain_limit_stiffness_ratio * m.youngs_modulus_pa;
        tet.strain_min = m.strain_min;
        tet.strain_max = m.strain_max;
        tet.strain_limits = m.strain_limits;
        for (int c = 0; c < 4; ++c) {
            node_mass_[tet.nodes[c]] += 0.25 * m.density_kg_per_m3 * tet.volume_m3;
        }
        tets_.push_back(tet);
    }
    for (int node : surfaceNodes(mesh)) {
        skin_.push_back(first + node);
    }
    return first;
}

int Simulation::addBody(const RigidBodyDesc& d) {
    if (!(d.mass_kg > 0.0) || !isRotation(d.rotation) || !finite(d.position_m)) {
        throw std::invalid_argument("addBody: positive mass, finite position, rotation required");
    }
    Body body{};
    body.mass = d.mass_kg;
    body.inertia_body = d.inertia_body_kg_m2;
    body.c = d.position_m;
    body.rotation = d.rotation;
    body.kinematic = d.kinematic;
    body.gravity = d.gravity;
    body.target_c = d.position_m;
    body.target_rotation = d.rotation;
    bodies_.push_back(body);
    return bodyCount() - 1;
}

int Simulation::addJoint(const JointDesc& d) {
    if (d.body_a < 0 || d.body_a >= bodyCount() || d.body_b < 0 || d.body_b >= bodyCount() ||
        d.body_a == d.body_b) {
        throw std::invalid_argument("addJoint: two distinct existing bodies required");
    }
    const Body& a = bodies_[d.body_a];
    const Body& b = bodies_[d.body_b];
    Joint joint{d,
                a.rotation.transpose() * (d.anchor_world_m - a.c),
                b.rotation.transpose() * (d.anchor_world_m - b.c),
                a.rotation.transpose() * d.axis_world.normalized(),
                a.rotation.transpose() * d.twist_world.normalized(),
                a.rotation.transpose() * b.rotation};
    joints_.push_back(joint);
    return static_cast<int>(joints_.size()) - 1;
}

void Simulation::attachNode(int node, int body, double stiffness) {
    const Body& b = bodies_.at(static_cast<std::size_t>(body));
    attachments_.push_back(
        {node, body, b.rotation.transpose() * (x_.at(node) - b.c), stiffness, Vec3::Zero()});
}

void Simulation::attachNodeAlong(int node, int body, const Vec3& direction_world,
                                 double stiffness) {
    const Body& b = bodies_.at(static_cast<std::size_t>(body));
    if (!(direction_world.norm() > 0.0)) {
        throw std::invalid_argument("attachNodeAlong: the direction must not be zero");
    }
    const Vec3 direction = b.rotation.transpose() * direction_world.normalized();
    attachments_.push_back(
        {node, body, b.rotation.transpose() * (x_.at(node) - b.c), stiffness, direction});
}

void Simulation::pinNode(int node, std::array<bool, 3> axes) {
    for (int a = 0; a < 3; ++a) {
        pinned_.at(node)[a] = pinned_.at(node)[a] || axes[a];
        if (axes[a]) {
            v_[node][a] = 0.0;
        }
    }
}

int Simulation::addCollider(const ColliderDesc& d) {
    if (d.body >= bodyCount() || !(d.friction >= 0.0)) {
        throw std::invalid_argument("addCollider: unknown body or negative friction");
    }
    colliders_.push_back({d, Vec3::Zero(), Mat3::Identity()});
    return static_cast<int>(colliders_.size()) - 1;
}

void Simulation::setTrackingStiffness(int body, double linear, double angular) {
    bodies_.at(static_cast<std::size_t>(body)).track_linear = linear;
    bodies_.at(static_cast<std::size_t>(body)).track_angular = angular;
}

bool Simulation::setTrackingTarget(int body, const Vec3& position_m, const Mat3& rotation) {
    if (body < 0 || body >= bodyCount()) {
        pending_.rejected_input = true;
        pending_.rejection_reason = "tracking target for unknown body " + std::to_string(body);
        return false;
    }
    if (!finite(position_m) || !isRotation(rotation)) {
        pending_.rejected_input = true;
        pending_.rejection_reason = "tracking target of body " + std::to_string(body) +
                                    " is not finite or not a rotation; previous target kept";
        return false;
    }
    bodies_[body].target_c = position_m;
    bodies_[body].target_rotation = rotation;
    return true;
}

void Simulation::setNodeForce(int node, const Vec3& force_n) {
    node_force_.at(node) = force_n;
}

void Simulation::setColliderPose(int collider, const Vec3& position_m, const Mat3& rotation) {
    auto& d = colliders_.at(static_cast<std::size_t>(collider)).desc;
    d.position_m = position_m;
    d.rotation = rotation;
}

void Simulation::setNodePosition(int node, const Vec3& position_m) {
    x_.at(node) = position_m;
    tissue_energy_valid_ = false;
}

void Simulation::setBodyPose(int body, const Vec3& position_m, const Mat3& rotation) {
    bodies_.at(static_cast<std::size_t>(body)).c = position_m;
    bodies_[body].rotation = rotation;
}

void Simulation::setBodyVelocity(int body, const Vec3& linear, const Vec3& angular) {
    bodies_.at(static_cast<std::size_t>(body)).v = linear;
    bodies_[body].w = angular;
}

Simulation::Configuration Simulation::currentConfiguration() const {
    Configuration q;
    currentConfiguration(q);
    return q;
}

void Simulation::currentConfiguration(Configuration& out) const {
    out.x = x_;
    out.c.resize(bodies_.size());
    out.rotation.resize(bodies_.size());
    for (std::size_t b = 0; b < bodies_.size(); ++b) {
        out.c[b] = bodies_[b].c;
        out.rotation[b] = bodies_[b].rotation;
    }
}

std::pair<Vec3, Mat3> Simulation::colliderPose(const Configuration& q, int collider) const {
    const auto& d = colliders_[collider].desc;
    if (d.body < 0) {
        return {d.position_m, d.rotation};
    }
    return {q.c[d.body], q.rotation[d.body]};
}

void Simulation::detectContacts(const Configuration& q) {
    contacts_.clear();
    const std::size_t slots = colliders_.size() * x_.size();
    if (anchors_.size() != slots) {
        // Tissue or colliders were added: every live anchor keeps its (node, collider).
        std::vector<Anchor> anchors(slots, Anchor{Vec3::Zero(), false});
        std::vector<char> valid(slots, 0);
        for (std::size_t slot = 0; slot < anchor_valid_.size(); ++slot) {
            if (anchor_valid_[slot] != 0) {
                const auto node = static_cast<int>(slot % anchor_node_count_);
                const auto collider = static_cast<int>(slot / anchor_node_count_);
                anchors[anchorSlot(node, collider)] = anchors_[slot];
                valid[anchorSlot(node, collider)] = 1;
            }
        }
        anchors_ = std::move(anchors);
        anchor_valid_ = std::move(valid);
        anchor_node_count_ = x_.size();
    }
    for (int ci = 0; ci < static_cast<int>(colliders_.size()); ++ci) {
        const auto [c, rotation] = colliderPose(q, ci);
        for (int node : skin_) {
            const auto query =
                querySurface(colliders_[ci].desc.shape, rotation.transpose() * (q.x[node] - c));
            const std::size_t slot = anchorSlot(node, ci);
            if (query.phi_m >= 0.0) {
                anchor_valid_[slot] = 0;  // contact lost: its anchor goes
                continue;
            }
            // A new contact anchors where the node meets the surface: zero friction force.
            if (anchor_valid_[slot] == 0) {
                anchors_[slot] = Anchor{
                    rotation.transpose() * (q.x[node] - c) - query.phi_m * query.normal, false};
                anchor_valid_[slot] = 1;
            }
            const Anchor& anchor = anchors_[slot];
            const double limit =
                colliders_[ci].desc.friction * settings_.contact_stiffness_n_per_m * -query.phi_m;
            contacts_.push_back(
                {node, ci, rotation * query.normal, anchor.local, limit, anchor.sliding});
        }
    }
}

void Simulation::updateAnchors() {
    currentConfiguration(work_.start);
    const Configuration& q = work_.start;
    const double k_n = settings_.contact_stiffness_n_per_m;
    const double k_f = settings_.friction_stiffness_n_per_m;
    contact_forces_.clear();
    // The contact set is brought to the new state too (projected anchors, lost contacts
    // gone): the next step's energy guard measures its reference with it before detecting
    // contacts again, and must not count friction springs the projection already relaxed.
    std::size_t kept = 0;
    for (auto& contact : contacts_) {
        const std::size_t slot = anchorSlot(contact.node, contact.collider);
        const auto [c, rotation] = colliderPose(q, contact.collider);
        const Vec3 local = rotation.transpose() * (x_[contact.node] - c);
        const auto query = querySurface(colliders_[contact.collider].desc.shape, local);
        if (query.phi_m >= 0.0) {
            anchor_valid_[slot] = 0;
            continue;
        }
        // Explicit Coulomb projection of the anchor (docs/algorithms.md §2.4.7), in the object
        // frame.
        const double normal_force = k_n * -query.phi_m;
        const Vec3 projected = local - query.phi_m * query.normal;
        const Mat3 tangent = Mat3::Identity() - query.normal * query.normal.transpose();
        Vec3 anchor = anchors_[slot].local;
        Vec3 stretch = tangent * (local - anchor);
        const double limit = colliders_[contact.collider].desc.friction * normal_force;
        const bool sliding = k_f * stretch.norm() > limit;
        if (sliding) {
            anchor = projected - (limit / k_f) * stretch.normalized();
            stretch = tangent * (local - anchor);
        }
        anchors_[slot] = Anchor{anchor, sliding};
        const Vec3 force_local = normal_force * query.normal - k_f * stretch;
        contact_forces_.push_back(
            {contact.node, contact.collider, rotation * force_local, sliding});
        contact.normal = rotation * query.normal;
        contact.anchor_local = anchor;
        contact.friction_limit_n = limit;
        contact.sliding = sliding;
        contacts_[kept++] = contact;
    }
    contacts_.resize(kept);
}

SurfaceQuery Simulation::queryCollider(int collider, const Vec3& p_world_m) const {
    const auto& d = colliders_[collider].desc;
    const Vec3& c = d.body < 0 ? d.position_m : bodies_[d.body].c;
    const Mat3& rotation = d.body < 0 ? d.rotation : bodies_[d.body].rotation;
    SurfaceQuery query = querySurface(d.shape, rotation.transpose() * (p_world_m - c));
    query.normal = rotation * query.normal;
    query.surface_point_m = c + rotation * query.surface_point_m;
    return query;
}

Vec3 Simulation::forceOnCollider(int collider) const {
    Vec3 sum = Vec3::Zero();
    for (const auto& f : contact_forces_) {
        if (f.collider == collider) {
            sum -= f.force_n;
        }
    }
    return sum;
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
        // A clamped step (PCG cap, energy rescale) may move little without having converged.
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
