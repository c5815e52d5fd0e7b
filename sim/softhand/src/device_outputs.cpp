#include "haptic/softhand/device_outputs.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "haptic/softhand/bullet_coupling.hpp"

namespace haptic::softhand {

namespace {

std::vector<int> skinOf(const Simulation& sim, const BoneInfo& bone) {
    std::vector<int> nodes;
    for (int node : sim.skinNodes()) {
        if (node >= bone.first_node && node < bone.first_node + bone.node_count) {
            nodes.push_back(node);
        }
    }
    return nodes;
}

// Below this the simulated skin does not press on the object: no normal to take from it.
constexpr double kMinPressForceN = 1e-6;
// A pressed sample's secant weight is taken over at least this depth: a sample grazing the
// object with a pressed node would otherwise weigh without bound (0.1 mm, about the plate's
// step at the servos' resolution).
constexpr double kMinSecantDepthM = 1e-4;

const BoneInfo& distalBone(const HandModel& model, config::Finger finger) {
    for (const auto& bone : model.bones) {
        if (bone.finger == finger && bone.segment == Segment::kDistal) {
            return bone;
        }
    }
    throw std::invalid_argument("the hand model has no distal phalanx of the " +
                                std::string(config::toString(finger)) + " finger");
}

// Finger frame F in the distal bone frame: same origin, x along the bone, z towards the pad
// (the bone's -z: the palm faces -z at build time).
const Mat3& boneFromFinger() {
    static const Mat3 rotation =
        Eigen::AngleAxisd(std::numbers::pi, Vec3::UnitX()).toRotationMatrix();
    return rotation;
}

}  // namespace

KinestheticOutput::KinestheticOutput(const HandModel& model, const HandKinematics& kinematics,
                                     config::Finger finger, KinestheticOutputSettings settings)
    : kinematics_(kinematics), settings_(settings) {
    const auto chain = kinematics_.chain(finger);
    if (!chain) {
        throw std::invalid_argument("the hand model does not simulate the joints of the " +
                                    std::string(config::toString(finger)) +
                                    " finger (an exoskeleton needs hand.model finger or hand)");
    }
    chain_ = *chain;
    for (std::size_t s = 0; s < 3; ++s) {
        const BoneInfo& bone = model.bones[static_cast<std::size_t>(chain_.bones[s])];
        const Simulation& sim = model.simulation;
        RigidSkin& skin = skin_[s];
        skin.body = bone.body;
        // From the build (rest) pose, wherever the hand is now.
        const BonePose& built = kinematics_.buildPose(chain_.bones[s]);
        for (int node : skinOf(sim, bone)) {
            skin.p_bone.push_back(built.rotation.transpose() *
                                  (sim.nodeRestPosition(node) - built.position_m));
        }
        nodes_[s] = {bone.first_node, bone.first_node + bone.node_count};
    }
}

std::array<double, 3> KinestheticOutput::jointAngles(const Simulation& sim) const {
    return {kinematics_.flexion(sim, chain_.joints[0]), kinematics_.flexion(sim, chain_.joints[1]),
            kinematics_.flexion(sim, chain_.joints[2])};
}

void KinestheticOutput::reset() {
    last_normal_.clear();
}

void KinestheticOutput::fill(const Simulation& sim, msgs::ConstraintSet& out) {
    const auto q = jointAngles(sim);
    out.dof = 3;
    out.q_sim_rad.fill(0.0);
    std::copy(q.begin(), q.end(), out.q_sim_rad.begin());
    out.constraints.clear();
    std::array<Vec3, 3> axes;
    std::array<Vec3, 3> anchors;
    for (std::size_t j = 0; j < 3; ++j) {
        axes[j] = kinematics_.axis(sim, chain_.joints[j]);
        anchors[j] = kinematics_.anchor(sim, chain_.joints[j]);
    }
    last_normal_.resize(static_cast<std::size_t>(sim.colliderCount()));
    for (std::size_t s = 0; s < 3; ++s) {
        const RigidSkin& skin = skin_[s];
        const Vec3& bone_position = sim.bodyPosition(skin.body);
        const Mat3& bone_rotation = sim.bodyRotation(skin.body);
        for (int collider = 0; collider < sim.colliderCount(); ++collider) {
            // The skin point of this phalanx deepest in this object stands for the contact.
            Vec3 point = Vec3::Zero();
            SurfaceQuery nearest;
            nearest.phi_m = std::numeric_limits<double>::infinity();
            for (const Vec3& p_bone : skin.p_bone) {
                const Vec3 p_world = bone_position + bone_rotation * p_bone;
                const SurfaceQuery query = sim.queryCollider(collider, p_world);
                if (query.phi_m < nearest.phi_m) {
                    nearest = query;
                    point = p_world;
                }
            }
            std::optional<Vec3>& last_normal = last_normal_[static_cast<std::size_t>(collider)][s];
            if (!(nearest.phi_m < settings_.contact_margin_m) || out.constraints.full()) {
                last_normal.reset();
                continue;
            }
            // Outside a convex object the distance's gradient is continuous, inside it is
            // not: 1-2 mm inside a box near an edge the side face can be the nearest one for
            // a frame, and a constraint along it asks for several times the force. So a
            // penetrating contact is pushed out along the normal the object presses the
            // simulated skin with (the normal parts of its contact forces on this phalanx).
            // Its depth stays the point's distance to its nearest face: continuous, and at an
            // edge less than the depth along that normal, so an edge renders rounded over the
            // depth of the press (measuring along a blended normal to a plane cut deep into
            // the box there and asked for 10 times the force).
            Vec3 normal = nearest.normal;
            if (nearest.phi_m < 0.0) {
                Vec3 pressed = Vec3::Zero();
                for (const Simulation::ContactForce& contact : sim.contactForces()) {
                    if (contact.collider != collider || contact.node < nodes_[s].first ||
                        contact.node >= nodes_[s].second) {
                        continue;
                    }
                    const Vec3 n =
                        sim.queryCollider(collider, sim.nodePosition(contact.node)).normal;
                    pressed += std::max(contact.force_n.dot(n), 0.0) * n;
                }
                if (pressed.norm() > kMinPressForceN) {
                    normal = pressed.normalized();
                }
            }
            // In the closed loop the pressed skin can still lie on the side face, or lift, for a
            // single frame at an edge (the soak's 4-6 N spikes, all at the script's edge phase):
            // the row's normal follows the contact's at a bounded turn rate.
            if (last_normal) {
                const Vec3 axis = last_normal->cross(normal);
                const double angle = std::atan2(axis.norm(), last_normal->dot(normal));
                if (angle > kMaxNormalTurnRad) {
                    normal = axis.norm() > 1e-12
                                 ? Vec3(Eigen::AngleAxisd(kMaxNormalTurnRad, axis.normalized()) *
                                        *last_normal)
                                 : *last_normal;  // opposite: no direction to turn in
                }
            }
            // A node on phalanx s moves with joints 0..s: d phi / d q_j = n . (u_j x r_j).
            msgs::LinearConstraint constraint;
            double b = -nearest.phi_m;
            double norm_squared = 0.0;
            for (std::size_t j = 0; j <= s; ++j) {
                const double a = normal.dot(axes[j].cross(point - anchors[j]));
                constraint.a[j] = a;
                b += a * q[j];
                norm_squared += a * a;
            }
            if (!(norm_squared > settings_.min_gradient_m * settings_.min_gradient_m)) {
                last_normal.reset();
                continue;
            }
            last_normal = normal;
            constraint.b = b;
            // The same contact for hapticd's evaluation on the finger's kinematics: the point
            // rides on joints 0..s, the row above is its linearisation at q.
            msgs::ContactKinematics& contact = constraint.contact;
            contact.joints = static_cast<std::int16_t>(s + 1);
            contact.gap_m = nearest.phi_m;
            contact.normal = {normal.x(), normal.y(), normal.z()};
            for (std::size_t j = 0; j <= s; ++j) {
                const Vec3 lever = point - anchors[j];
                contact.q_ref_rad[j] = q[j];
                contact.axis[j] = {axes[j].x(), axes[j].y(), axes[j].z()};
                contact.lever_m[j] = {lever.x(), lever.y(), lever.z()};
            }
            out.constraints.push_back(constraint);
        }
    }
    out.reference_torque_nm = referenceTorques(sim, q, axes, anchors);
}

std::array<double, msgs::kMaxJointDofs> KinestheticOutput::referenceTorques(
    const Simulation& sim, const std::array<double, 3>& q, const std::array<Vec3, 3>& axes,
    const std::array<Vec3, 3>& anchors) const {
    std::array<double, msgs::kMaxJointDofs> reference{};
    const auto onFinger = [this](int node) {
        return std::any_of(nodes_.begin(), nodes_.end(), [node](const auto& range) {
            return node >= range.first && node < range.second;
        });
    };
    const auto& contacts = sim.contactForces();
    if (std::none_of(contacts.begin(), contacts.end(), [&](const Simulation::ContactForce& c) {
            return onFinger(c.node) && c.force_n.norm() > kMinPressForceN;
        })) {
        return reference;  // free space: the device is to be transparent
    }
    // The fully actuated reference is the coupling between the tracked finger and the
    // simulated one (docs/softhand.md, "Exoskeleton: ConstraintSet"): the generalised force of the
    // tracking springs on the three phalanges, less the finger's own weight, which those springs
    // carry in free space and the user's muscles carry on a real hand. A node on phalanx s
    // moves with joints 0..s: tau_j = u_j . ((c - anchor_j) x f + m). At rest this equals the
    // contact's generalised force; within a step it is that force through the phalanges' mass,
    // so a single frame's contact impulse (a node caught at an edge) is not in it.
    const Vec3& gravity = sim.settings().gravity_m_per_s2;
    std::array<double, 3> coupling{0.0, 0.0, 0.0};
    for (std::size_t s = 0; s < 3; ++s) {
        const Simulation::Body& body = sim.body(skin_[s].body);
        Vec3 force = body.track_linear * (body.target_c - body.c);
        if (body.gravity) {
            force += body.mass * gravity;
        }
        const Vec3 moment =
            -body.track_angular * logMap(body.rotation * body.target_rotation.transpose());
        for (std::size_t j = 0; j <= s; ++j) {
            coupling[j] += axes[j].dot((body.c - anchors[j]).cross(force) + moment);
        }
        for (int node = nodes_[s].first; node < nodes_[s].second; ++node) {
            const Vec3 weight = sim.nodeMass(node) * gravity;
            for (std::size_t j = 0; j <= s; ++j) {
                coupling[j] += axes[j].dot((sim.nodePosition(node) - anchors[j]).cross(weight));
            }
        }
    }
    // The springs pull the finger into the object; the reference is what the object does to
    // it, the force the device is to apply to the user's finger. At rest the springs also
    // balance a joint pressed past its limit (the limit's torque -k v about u_j, v the
    // violation, as the sim's coupling energy has it): that torque is the finger's own
    // anatomy, which the user's joint carries without the device, so it is taken out.
    for (std::size_t j = 0; j < 3; ++j) {
        const JointDesc& joint = sim.jointDesc(chain_.joints[j]);
        reference[j] = -coupling[j] + joint.limit_stiffness_nm_per_rad * joint.limitViolation(q[j]);
    }
    return reference;
}

TactileOutput::TactileOutput(const HandModel& model, config::Finger finger,
                             const config::Transform& finger_from_device,
                             const TissueMaterial& material, TactileOutputSettings settings) {
    const BoneInfo& bone = distalBone(model, finger);
    const Simulation& sim = model.simulation;
    bone_ = static_cast<std::size_t>(&bone - model.bones.data());
    body_ = bone.body;
    nodes_ = {bone.first_node, bone.first_node + bone.node_count};
    const Mat3 finger_rotation_device = rotationFromRpy(finger_from_device.rpy_rad);
    const Vec3 finger_translation_device(finger_from_device.translation_m[0],
                                         finger_from_device.translation_m[1],
                                         finger_from_device.translation_m[2]);
    bone_from_device_rotation_ = boneFromFinger() * finger_rotation_device;
    bone_from_device_translation_m_ = boneFromFinger() * finger_translation_device;

    // Pad radius and length from the rest skin: the largest distance from the bone axis.
    const Vec3& centre = sim.bodyPosition(bone.body);
    const Mat3& rotation = sim.bodyRotation(bone.body);
    const double half_length = 0.5 * bone.length_m;
    double radius = 0.0;
    const std::vector<int> skin = skinOf(sim, bone);
    for (int node : skin) {
        const Vec3 p_bone = rotation.transpose() * (sim.nodePosition(node) - centre);
        radius = std::max(radius, std::hypot(p_bone.y(), p_bone.z()));
    }
    struct Candidate {
        double distance_m;  // to the device origin
        Vec3 p_bone_m;      // rest point
        int node;
    };
    std::vector<Candidate> candidates;
    for (int node : skin) {
        const Vec3 p_bone = rotation.transpose() * (sim.nodePosition(node) - centre);
        // The pad: skin facing the palm side, clear of the flanks at the axis height.
        if ((boneFromFinger().transpose() * p_bone).z() > 0.25 * radius) {
            candidates.push_back({(p_bone - bone_from_device_translation_m_).norm(), p_bone, node});
        }
    }
    if (candidates.empty() || !(radius > 0.0)) {
        throw std::invalid_argument("tactile output: the distal phalanx has no pad skin nodes");
    }
    // The pad half of the tissue surface: half the cylinder side plus the lower quarter of
    // the tip sphere, shared evenly by the pad-side skin nodes.
    const double pad_area =
        std::numbers::pi * radius * 2.0 * half_length * 0.5 + std::numbers::pi * radius * radius;
    const double area = pad_area / static_cast<double>(candidates.size());
    std::sort(candidates.begin(), candidates.end(),
              [](const auto& a, const auto& b) { return a.distance_m < b.distance_m; });
    const auto count = std::min<std::size_t>(
        candidates.size(),
        std::min<std::size_t>(static_cast<std::size_t>(std::max(settings.max_samples, 1)),
                              msgs::kMaxContactSamples));
    on_pad_.assign(static_cast<std::size_t>(nodes_.second - nodes_.first), 0);
    pressed_.assign(on_pad_.size(), 0);
    normal_force_n_.assign(on_pad_.size(), 0.0);
    for (std::size_t i = 0; i < count; ++i) {
        samples_.push_back({candidates[i].p_bone_m, area, candidates[i].node});
        on_pad_[static_cast<std::size_t>(candidates[i].node - nodes_.first)] = 1;
    }
    // The bone radius is 0.35 r (hand_builder); the pad tissue is the rest.
    pad_stiffness_pa_per_m_ = settings.pad_stiffness_pa_per_m > 0.0
                                  ? settings.pad_stiffness_pa_per_m
                                  : material.youngs_modulus_pa / (0.65 * radius);
}

BonePose TactileOutput::deviceFrame(const BonePose& finger_bone) const {
    return {finger_bone.position_m + finger_bone.rotation * bone_from_device_translation_m_,
            finger_bone.rotation * bone_from_device_rotation_};
}

void TactileOutput::fill(const Simulation& sim, const BonePose& finger_bone,
                         msgs::ContactSurface& out) const {
    out.samples.clear();
    const Mat3& bone_rotation = finger_bone.rotation;
    const Vec3& bone_position = finger_bone.position_m;
    const BonePose device = deviceFrame(finger_bone);
    const auto nearestSurface = [&sim](const Vec3& p_world) {
        SurfaceQuery nearest;
        nearest.phi_m = std::numeric_limits<double>::infinity();
        for (int collider = 0; collider < sim.colliderCount(); ++collider) {
            const SurfaceQuery query = sim.queryCollider(collider, p_world);
            if (query.phi_m < nearest.phi_m) {
                nearest = query;
            }
        }
        return nearest;
    };
    // The reference: net force and moment of the contacts on the sampled pad, the part of the
    // fingertip the plate can render (a tip-first touch is not the thimble's to render).
    std::fill(pressed_.begin(), pressed_.end(), 0);
    std::fill(normal_force_n_.begin(), normal_force_n_.end(), 0.0);
    Vec3 force = Vec3::Zero();
    Vec3 moment = Vec3::Zero();
    // The sim's pad contact carried rigidly onto the user's (tracked) pad: each force from the
    // same place and in the same direction relative to the finger, so the reference is the
    // contact as the simulated finger has it, whatever the two fingers' offset.
    const Mat3 tracked_from_sim = finger_bone.rotation * sim.bodyRotation(body_).transpose();
    const Vec3& sim_bone_position = sim.bodyPosition(body_);
    for (const Simulation::ContactForce& contact : sim.contactForces()) {
        if (contact.node >= nodes_.first && contact.node < nodes_.second &&
            on_pad_[static_cast<std::size_t>(contact.node - nodes_.first)] != 0) {
            const Vec3 force_on_user_pad = tracked_from_sim * contact.force_n;
            force += force_on_user_pad;
            if (contact.force_n.norm() > kMinPressForceN) {
                pressed_[static_cast<std::size_t>(contact.node - nodes_.first)] = 1;
            }
            const Vec3 normal =
                sim.queryCollider(contact.collider, sim.nodePosition(contact.node)).normal;
            normal_force_n_[static_cast<std::size_t>(contact.node - nodes_.first)] +=
                std::max(contact.force_n.dot(normal), 0.0);
            const Vec3 on_user_pad =
                bone_position +
                tracked_from_sim * (sim.nodePosition(contact.node) - sim_bone_position);
            moment += (on_user_pad - device.position_m).cross(force_on_user_pad);
        }
    }
    const bool pad_pressed = std::find(pressed_.begin(), pressed_.end(), 1) != pressed_.end();
    for (const Sample& sample : samples_) {
        const Vec3 p_world = bone_position + bone_rotation * sample.p_bone_m;
        SurfaceQuery nearest = nearestSurface(p_world);
        // Where the simulated skin presses on an object deeper than the rigid pad point (the
        // tissue bulges past its rest shape around a light press: measured up to 1.4 mm in
        // the demo's onsets, with 0.2-0.65 N on the pad, the rigid point clear), the sample
        // takes the skin's depth: the plate must not stay retracted while the pad touches.
        // Only where the contact pushes on that node.
        if (pressed_[static_cast<std::size_t>(sample.node - nodes_.first)] != 0) {
            const SurfaceQuery skin = nearestSurface(sim.nodePosition(sample.node));
            if (skin.phi_m < 0.0 && skin.phi_m < nearest.phi_m) {
                nearest = skin;
            }
        } else if (!pad_pressed) {
            // A pad the sim presses nowhere (its reference 0 N) is in contact nowhere, wherever
            // the rigid pad points lie: after a release, or beside a tip-first touch, they can
            // sit inside an object the skin does not press (CI saw the plate raised for
            // seconds on a pad with 0 N).
            nearest.phi_m = std::max(nearest.phi_m, 0.0);
        }
        msgs::ContactSample out_sample;
        const Vec3 p_device = device.rotation.transpose() * (p_world - device.position_m);
        const Vec3 normal_device = device.rotation.transpose() * nearest.normal.normalized();
        for (int i = 0; i < 3; ++i) {
            out_sample.p_device_m[static_cast<std::size_t>(i)] = p_device[i];
            out_sample.normal_device[static_cast<std::size_t>(i)] = normal_device[i];
        }
        // No object at all: far away, pointing back at the pad.
        out_sample.signed_distance_m = std::isfinite(nearest.phi_m) ? nearest.phi_m : 1.0;
        // Weight: the patch's stiffness, at least the linear pad's (area times its stiffness
        // per area), which is what hapticd's pad force limits judge the user's pad with: a
        // softer weight would let the plate press deeper than they allow today. Where the FEM
        // presses the sample's node harder than that, the contact's secant (the normal force
        // there over the depth sent): the optimiser's fit is then weighted by contact stiffness
        // (docs/algorithms.md §3.3) and matches force on curved objects better.
        const double area_weight = sample.area_m2 * pad_stiffness_pa_per_m_;
        out_sample.weight = area_weight;
        const double pressed_n =
            normal_force_n_[static_cast<std::size_t>(sample.node - nodes_.first)];
        if (out_sample.signed_distance_m < 0.0 && pressed_n > kMinPressForceN) {
            out_sample.weight = std::max(
                area_weight, pressed_n / std::max(-out_sample.signed_distance_m, kMinSecantDepthM));
        }
        out.samples.push_back(out_sample);
    }
    const Vec3 force_device = device.rotation.transpose() * force;
    const Vec3 moment_device = device.rotation.transpose() * moment;
    for (int i = 0; i < 3; ++i) {
        out.reference_force_device_n[static_cast<std::size_t>(i)] = force_device[i];
        out.reference_moment_device_nm[static_cast<std::size_t>(i)] = moment_device[i];
    }
}

}  // namespace haptic::softhand
