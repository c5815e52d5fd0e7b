#include <vector>

#include "energy_terms.hpp"

namespace haptic::softhand {

namespace {

std::array<JacobianBlock, 2> angularPair(int dof_a, int dof_b) {
    return {JacobianBlock{dof_b + 3, Mat3::Identity()},
            JacobianBlock{dof_a + 3, -Mat3::Identity()}};
}

}  // namespace

double EnergyTerms::skeleton(const Sim& sim, const Sim::Configuration& q, Assembler* assembler) {
    double energy = 0.0;
    JacobianBlocks blocks;
    for (const auto& attachment : sim.attachments_) {
        const int b = attachment.body;
        const Vec3 lever = q.rotation[b] * attachment.offset_local;
        const Vec3 residual = q.x[attachment.node] - (q.c[b] + lever);
        blocks.clear();
        blocks.push_back({nodeDof(attachment.node), Mat3::Identity()});
        appendBodyPoint(blocks, bodyDof(sim, b), lever, -1.0);
        if (attachment.direction_local.isZero()) {
            energy += addResidualTerm(assembler, attachment.stiffness * Mat3::Identity(), residual,
                                      blocks);
        } else {
            const Vec3 direction = q.rotation[b] * attachment.direction_local;
            energy +=
                addResidualTerm(assembler, attachment.stiffness * direction * direction.transpose(),
                                residual, blocks);
        }
    }
    for (int b = 0; b < sim.bodyCount(); ++b) {
        const auto& body = sim.bodies_[b];
        if (body.track_linear > 0.0) {
            const JacobianBlock block{bodyDof(sim, b), Mat3::Identity()};
            energy += addResidualTerm(assembler, body.track_linear * Mat3::Identity(),
                                      q.c[b] - body.target_c, std::span(&block, 1));
        }
        if (body.track_angular > 0.0) {
            const JacobianBlock block{bodyDof(sim, b) + 3, Mat3::Identity()};
            const Vec3 theta = logMap(q.rotation[b] * body.target_rotation.transpose());
            energy += addResidualTerm(assembler, body.track_angular * Mat3::Identity(), theta,
                                      std::span(&block, 1));
        }
    }
    for (const auto& joint : sim.joints_) {
        const auto& d = joint.desc;
        const int a = d.body_a;
        const int b = d.body_b;
        const Vec3 lever_a = q.rotation[a] * joint.anchor_a_local;
        const Vec3 lever_b = q.rotation[b] * joint.anchor_b_local;
        const Vec3 separation = (q.c[a] + lever_a) - (q.c[b] + lever_b);
        blocks.clear();
        appendBodyPoint(blocks, bodyDof(sim, a), lever_a, 1.0);
        appendBodyPoint(blocks, bodyDof(sim, b), lever_b, -1.0);
        energy += addResidualTerm(assembler, d.positional_stiffness_n_per_m * Mat3::Identity(),
                                  separation, blocks);
        if (d.type == JointType::kBall) {
            continue;
        }
        // Relative rotation in the world frame; zero in the build pose.
        const Vec3 theta =
            logMap(q.rotation[b] * (q.rotation[a] * joint.rest_relative).transpose());
        const Vec3 axis = q.rotation[a] * joint.axis_a_local;
        const auto pair = angularPair(bodyDof(sim, a), bodyDof(sim, b));
        if (d.type == JointType::kHinge) {
            const Mat3 off_axis = Mat3::Identity() - axis * axis.transpose();
            energy += addResidualTerm(assembler, d.alignment_stiffness_nm_per_rad * off_axis, theta,
                                      pair);
        } else {
            const Vec3 twist = q.rotation[a] * joint.twist_a_local;
            energy += addResidualTerm(assembler,
                                      d.alignment_stiffness_nm_per_rad * twist * twist.transpose(),
                                      theta, pair);
        }
        const double violation = d.limitViolation(axis.dot(theta));
        if (violation != 0.0) {
            energy +=
                addResidualTerm(assembler, d.limit_stiffness_nm_per_rad * axis * axis.transpose(),
                                violation * axis, pair);
        }
    }
    return energy;
}

double EnergyTerms::contact(const Sim& sim, const Sim::Configuration& q, Assembler* assembler) {
    const double k_n = sim.settings_.contact_stiffness_n_per_m;
    const double k_f = sim.settings_.friction_stiffness_n_per_m;
    double energy = 0.0;
    JacobianBlocks blocks;
    // Normal penalty on the true penetration of every skin node, detected or not: the energy
    // check then sees a step that tunnels into an object, and a Newton iteration after the
    // first linearises the nodes that touched within the step.
    for (int ci = 0; ci < static_cast<int>(sim.colliders_.size()); ++ci) {
        const auto [c, rotation] = sim.colliderPose(q, ci);
        const int body = sim.colliders_[ci].desc.body;
        for (int node : sim.skin_) {
            const auto query =
                querySurface(sim.colliders_[ci].desc.shape, rotation.transpose() * (q.x[node] - c));
            if (!(query.phi_m < 0.0)) {
                continue;
            }
            if (assembler == nullptr) {
                energy += 0.5 * k_n * query.phi_m * query.phi_m;
                continue;
            }
            const Vec3 normal = rotation * query.normal;
            const Vec3 surface = c + rotation * query.surface_point_m;
            blocks.clear();
            blocks.push_back({nodeDof(node), Mat3::Identity()});
            if (body >= 0) {
                appendBodyPoint(blocks, bodyDof(sim, body), surface - q.c[body], -1.0);
            }
            energy += addResidualTerm(assembler, k_n * normal * normal.transpose(),
                                      query.phi_m * normal, blocks);
        }
    }
    for (const auto& contact : sim.contacts_) {
        const auto& collider = sim.colliders_[contact.collider];
        const auto [c, rotation] = sim.colliderPose(q, contact.collider);
        const Vec3& x = q.x[contact.node];
        const int body = collider.desc.body;
        const Vec3 anchor = c + rotation * contact.anchor_local;
        const Mat3 tangent = Mat3::Identity() - contact.normal * contact.normal.transpose();
        blocks.clear();
        blocks.push_back({nodeDof(contact.node), Mat3::Identity()});
        if (body >= 0) {
            appendBodyPoint(blocks, bodyDof(sim, body), anchor - q.c[body], -1.0);
        }
        // Friction spring capped at the Coulomb force (a Huber energy): inside the radius
        // mu f_N / k_f it sticks; beyond it the force stays mu f_N, so a sliding node feels
        // kinetic friction within the implicit step instead of a lagged-anchor drag.
        const Vec3 stretch = tangent * (x - anchor);
        const double length = stretch.norm();
        const double radius = k_f > 0.0 ? contact.friction_limit_n / k_f : 0.0;
        // A node that slid last step sits exactly on the radius; linearising the stick
        // branch there would make the one Newton step believe it sticks.
        const bool slide_branch =
            length > radius || (contact.sliding && length >= 0.999 * radius && length > 0.0);
        if (!slide_branch) {
            energy += addResidualTerm(assembler, k_f * tangent, stretch, blocks);
        } else {
            const Vec3 direction = stretch / length;
            energy += contact.friction_limit_n * (length - 0.5 * radius);
            const Mat3 across = tangent - direction * direction.transpose();
            addLinearizedTerm(assembler, contact.friction_limit_n * direction,
                              (contact.friction_limit_n / length) * across, blocks);
        }
    }
    return energy;
}

}  // namespace haptic::softhand
