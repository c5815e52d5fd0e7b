#include "haptic/softhand/elastic_tracking.hpp"

#include <stdexcept>

namespace haptic::softhand {

namespace {

SolverSettings skeletonSettings() {
    SolverSettings s;
    s.gravity_m_per_s2 = Vec3::Zero();
    s.mass_damping_per_s = 0.0;
    s.stiffness_damping_s = 0.0;
    s.max_speed_m_per_s = 1e3;  // the rate clamp is applied to the targets instead
    return s;
}

bool isRotation(const Mat3& r) {
    return r.allFinite() && (r.transpose() * r - Mat3::Identity()).norm() < 1e-6 &&
           r.determinant() > 0.0;
}

}  // namespace

ElasticTracking::ElasticTracking(const HandModel& model, TrackingSettings settings)
    : settings_(settings), skeleton_(skeletonSettings()) {
    const Simulation& sim = model.simulation;
    for (const auto& bone : model.bones) {
        const auto& body = sim.body(bone.body);
        RigidBodyDesc desc;
        desc.mass_kg = body.mass;
        desc.inertia_body_kg_m2 = body.inertia_body;
        desc.position_m = body.c;
        desc.rotation = body.rotation;
        desc.kinematic = body.kinematic;
        desc.gravity = false;
        const int b = skeleton_.addBody(desc);
        skeleton_.setTrackingStiffness(b, settings_.linear_stiffness_n_per_m,
                                       settings_.angular_stiffness_nm_per_rad);
        bodies_.push_back(b);
        tracked_.push_back({body.c, body.rotation});
    }
    previous_target_ = tracked_;
    // Joints refer to simulation bodies; map them to skeleton bodies through the bone list.
    for (int j = 0; j < sim.jointCount(); ++j) {
        JointDesc desc = sim.jointDesc(j);
        int mapped_a = -1;
        int mapped_b = -1;
        for (std::size_t k = 0; k < model.bones.size(); ++k) {
            mapped_a = model.bones[k].body == desc.body_a ? bodies_[k] : mapped_a;
            mapped_b = model.bones[k].body == desc.body_b ? bodies_[k] : mapped_b;
        }
        if (mapped_a < 0 || mapped_b < 0) {
            throw std::logic_error("ElasticTracking: joint between bodies that are not bones");
        }
        desc.body_a = mapped_a;
        desc.body_b = mapped_b;
        skeleton_.addJoint(desc);
    }
}

bool ElasticTracking::setTrackedPoses(std::span<const BonePose> poses, std::string* reason) {
    if (poses.size() != tracked_.size()) {
        if (reason != nullptr) {
            *reason = "tracked pose count " + std::to_string(poses.size()) + " != bone count " +
                      std::to_string(tracked_.size());
        }
        return false;
    }
    for (std::size_t i = 0; i < poses.size(); ++i) {
        if (!poses[i].position_m.allFinite() || !isRotation(poses[i].rotation)) {
            if (reason != nullptr) {
                *reason = "tracked pose of bone " + std::to_string(i) +
                          " is not finite or not a rotation; previous pose kept";
            }
            return false;
        }
    }
    tracked_.assign(poses.begin(), poses.end());
    return true;
}

bool ElasticTracking::update(HandModel& model, double dt_s) {
    Simulation& sim = model.simulation;
    // 1. Synchronised copy of the simulated skeleton.
    for (std::size_t k = 0; k < bodies_.size(); ++k) {
        const int b = model.bones[k].body;
        if (sim.body(b).kinematic) {
            // A kinematic bone (the palm of the single-finger model) follows the tracker.
            sim.setBodyPose(b, tracked_[k].position_m, tracked_[k].rotation);
        }
        skeleton_.setBodyPose(bodies_[k], sim.bodyPosition(b), sim.bodyRotation(b));
        skeleton_.setBodyVelocity(bodies_[k], Vec3::Zero(), Vec3::Zero());
        skeleton_.setTrackingTarget(bodies_[k], tracked_[k].position_m, tracked_[k].rotation);
    }
    // 2. Move it towards the tracked skeleton: Gauss-Newton steps regularised by M / dt^2.
    for (int it = 0; it < settings_.gauss_newton_iterations; ++it) {
        for (int b : bodies_) {
            skeleton_.setBodyVelocity(b, Vec3::Zero(), Vec3::Zero());
        }
        skeleton_.step(dt_s);
    }
    // 3. Its poses become the simulated bones' tracking targets, rate-limited.
    bool clamped = false;
    const double max_step = settings_.max_target_speed_m_per_s * dt_s;
    for (std::size_t k = 0; k < bodies_.size(); ++k) {
        Vec3 target = skeleton_.bodyPosition(bodies_[k]);
        const Vec3 move = target - previous_target_[k].position_m;
        if (move.norm() > max_step) {
            target = previous_target_[k].position_m + move * (max_step / move.norm());
            clamped = true;
        }
        previous_target_[k] = {target, skeleton_.bodyRotation(bodies_[k])};
        sim.setTrackingTarget(model.bones[k].body, target, previous_target_[k].rotation);
    }
    return clamped;
}

void ElasticTracking::resetToModel(const HandModel& model) {
    for (std::size_t k = 0; k < bodies_.size(); ++k) {
        const int b = model.bones[k].body;
        tracked_[k] = {model.simulation.bodyPosition(b), model.simulation.bodyRotation(b)};
        skeleton_.setBodyPose(bodies_[k], tracked_[k].position_m, tracked_[k].rotation);
    }
    previous_target_ = tracked_;
}

BonePose ElasticTracking::intermediatePose(int bone) const {
    return {skeleton_.bodyPosition(bodies_.at(bone)), skeleton_.bodyRotation(bodies_.at(bone))};
}

}  // namespace haptic::softhand
