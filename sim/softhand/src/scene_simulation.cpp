#include "haptic/softhand/scene_simulation.hpp"

#include <sched.h>

#include <limits>
#include <stdexcept>
#include <thread>

namespace haptic::softhand {

int usableCores() {
    // The CPUs this process may run on (taskset, a cpuset), not the machine's.
    cpu_set_t allowed;
    CPU_ZERO(&allowed);
    if (::sched_getaffinity(0, sizeof(allowed), &allowed) == 0) {
        return CPU_COUNT(&allowed);
    }
    return static_cast<int>(std::thread::hardware_concurrency());
}

SolverSettings withRealtimeLimits(SolverSettings physics, const config::SolverLimits& limits) {
    physics.pcg_max_iterations = limits.pcg_max_iterations;
    physics.pcg_relative_tolerance = SolverSettings{}.pcg_relative_tolerance;
    physics.max_newton_iterations = limits.newton_iterations;
    physics.max_backtracks = 2;
    physics.max_substep_depth = 0;
    physics.newton_tolerance_m = std::numeric_limits<double>::infinity();
    // Only where a second core can take it.
    physics.use_helper_thread = limits.helper_thread && usableCores() >= 2;
    return physics;
}

SceneSimulationSettings realtimeSceneSettings(const config::SolverLimits& limits) {
    SceneSimulationSettings settings;
    settings.solver = withRealtimeLimits(settings.solver, limits);
    return settings;
}

SceneSimulation::SceneSimulation(const config::SceneConfig& scene,
                                 const std::vector<DeviceRequest>& devices,
                                 const SceneSimulationSettings& settings)
    : model_(buildHand(scene.hand, settings.solver, settings.build)), hand_(scene.hand) {
    // Everything that reads the build pose comes before the hand is placed.
    tracked_hand_ = std::make_unique<TrackedHand>(model_, scene.hand);
    const HandKinematics kinematics(model_);
    for (const auto& device : devices) {
        if (device.kinesthetic) {
            kinesthetic_.emplace_back(
                KinestheticOutput(model_, kinematics, device.finger, settings.kinesthetic));
            tactile_.emplace_back();
        } else {
            TactileOutputSettings tactile;
            tactile.max_samples = device.max_samples;
            tactile_.emplace_back(TactileOutput(model_, device.finger, device.finger_from_device,
                                                settings.build.tissue, tactile));
            kinesthetic_.emplace_back();
        }
    }
    tracking_ = std::make_unique<ElasticTracking>(model_, settings.tracking);
    coupling_ = std::make_unique<BulletCoupling>(scene.objects, model_.simulation, settings.engine);
}

void SceneSimulation::reset(const HandPoseInput& pose) {
    tracked_hand_->bonePoses(pose, poses_);
    Simulation& sim = model_.simulation;
    for (std::size_t k = 0; k < model_.bones.size(); ++k) {
        const BoneInfo& bone = model_.bones[k];
        const Vec3 c0 = sim.bodyPosition(bone.body);
        const Mat3 r0 = sim.bodyRotation(bone.body);
        const Mat3 rotation = poses_[k].rotation * r0.transpose();
        for (int node = bone.first_node; node < bone.first_node + bone.node_count; ++node) {
            sim.setNodePosition(node,
                                poses_[k].position_m + rotation * (sim.nodePosition(node) - c0));
        }
        sim.setBodyPose(bone.body, poses_[k].position_m, poses_[k].rotation);
        sim.setBodyVelocity(bone.body, Vec3::Zero(), Vec3::Zero());
        sim.setTrackingTarget(bone.body, poses_[k].position_m, poses_[k].rotation);
    }
    tracking_->resetToModel(model_);
    for (auto& output : kinesthetic_) {
        if (output) {
            output->reset();
        }
    }
}

std::optional<std::string> SceneSimulation::setHandPose(const HandPoseInput& pose) {
    tracked_hand_->bonePoses(pose, poses_);
    std::string reason;
    if (!tracking_->setTrackedPoses(poses_, &reason)) {
        pending_rejection_ = reason;
        return reason;
    }
    return std::nullopt;
}

StepReport SceneSimulation::step(double dt_s) {
    const bool target_clamped = tracking_->update(model_, dt_s);
    StepReport report = model_.simulation.step(dt_s);
    coupling_->exchange(model_.simulation, dt_s);
    report.clamped = report.clamped || target_clamped;
    if (!pending_rejection_.empty()) {
        report.rejected_input = true;
        report.rejection_reason = "hand pose: " + pending_rejection_;
        pending_rejection_.clear();
    }
    return report;
}

void SceneSimulation::fill(std::size_t device, msgs::ConstraintSet& out) {
    kinesthetic_.at(device).value().fill(model_.simulation, out);
}

void SceneSimulation::fill(std::size_t device, msgs::ContactSurface& out) const {
    const TactileOutput& output = tactile_.at(device).value();
    output.fill(model_.simulation, tracking_->trackedPoses().at(output.bone()), out);
}

const KinestheticOutput* SceneSimulation::kinesthetic(std::size_t device) const {
    return kinesthetic_.at(device) ? &*kinesthetic_[device] : nullptr;
}

const TactileOutput* SceneSimulation::tactile(std::size_t device) const {
    return tactile_.at(device) ? &*tactile_[device] : nullptr;
}

SceneSize SceneSimulation::size() const {
    const Simulation& sim = model_.simulation;
    SceneSize out{sim.nodeCount(), sim.tetCount(), sim.jointCount(), sim.colliderCount(), {}};
    for (const BoneInfo& bone : model_.bones) {
        out.bone_names.push_back(bone.name);
    }
    return out;
}

std::string toString(const SceneSize& size) {
    std::string bones;
    for (const std::string& name : size.bone_names) {
        bones += (bones.empty() ? "" : " ") + name;
    }
    return std::to_string(size.nodes) + " nodes, " + std::to_string(size.tetrahedra) +
           " tetrahedra, " + std::to_string(size.bone_names.size()) + " bones (" + bones + "), " +
           std::to_string(size.joints) + " joints, " + std::to_string(size.colliders) +
           " colliders";
}

std::string SceneSimulation::modelName() const {
    std::string fingers;
    if (hand_.model != config::HandModel::kHand) {
        fingers =
            "_" + std::string(config::toString(hand_.finger.value_or(config::Finger::kIndex)));
    }
    for (const config::Finger finger : hand_.fingers) {  // a hand with some fingers only
        fingers += "_" + std::string(config::toString(finger));
    }
    return "softhand_" + std::string(config::toString(hand_.model)) + fingers + "_res" +
           std::to_string(hand_.resolution);
}

}  // namespace haptic::softhand
