#include "haptic/emu/virtual_user.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "haptic/emu/device_models.hpp"
#include "haptic/softhand/bullet_coupling.hpp"

namespace haptic::emu {

namespace {

const config::SceneObject& targetObject(const config::SceneConfig& scene) {
    const auto* object = scene.findObject(scene.tracking.target_object);
    if (object == nullptr) {
        throw std::invalid_argument("virtual user: tracking.target_object '" +
                                    scene.tracking.target_object + "' is not in scene '" +
                                    scene.name + "'");
    }
    return *object;
}

// Index of a finger's MCP angle in HandPoseInput::flexion_rad (thumb, index, ... by 3).
std::size_t firstAngle(config::Finger finger) {
    return 3 * static_cast<std::size_t>(finger);
}

}  // namespace

VirtualUser::VirtualUser(const config::VirtualUserConfig& config, std::string_view replay_text)
    : tracker_(config.tracker),
      impedance_(config.hand_impedance),
      pad_(config.pad),
      scene_(config.scene),
      noise_engine_(config.tracker.seed) {
    // The user's hand has the scene's geometry, so the intent of a script is the pose
    // handsim would give its own hand; only the bones matter here, not the tissue.
    model_ = std::make_unique<softhand::HandModel>(
        softhand::buildHand(scene_.hand, softhand::SolverSettings{}, softhand::HandBuildOptions{}));
    hand_ = std::make_unique<softhand::TrackedHand>(*model_, scene_.hand);
    // The skin of every simulated phalanx at rest, in its bone's frame (the model is still in
    // its build pose), for the user's finger penetration.
    const softhand::Simulation& sim = model_->simulation;
    std::vector<bool> on_skin(static_cast<std::size_t>(sim.nodeCount()), false);
    for (const int node : sim.skinNodes()) {
        on_skin[static_cast<std::size_t>(node)] = true;
    }
    for (std::size_t b = 0; b < model_->bones.size(); ++b) {
        const softhand::BoneInfo& bone = model_->bones[b];
        if (!bone.finger || bone.node_count == 0) {
            continue;
        }
        const softhand::Vec3& centre = sim.bodyPosition(bone.body);
        const softhand::Mat3& rotation = sim.bodyRotation(bone.body);
        auto& points = skin_[static_cast<std::size_t>(*bone.finger)];
        for (int node = bone.first_node; node < bone.first_node + bone.node_count; ++node) {
            // Only the surface can be deepest: an inner node lies behind a skin node.
            if (on_skin[static_cast<std::size_t>(node)]) {
                points.push_back({b, rotation.transpose() * (sim.nodePosition(node) - centre)});
            }
        }
    }
    // Moving objects are where handsim's physics puts them, which the user does not know.
    for (const config::SceneObject& object : scene_.objects) {
        if (object.isStatic() || object.shapeType() == config::ShapeType::kPlane) {
            obstacles_.push_back(
                {softhand::colliderShape(object),
                 softhand::Vec3(object.pose.position_m[0], object.pose.position_m[1],
                                object.pose.position_m[2]),
                 softhand::rotationFromRpy(object.pose.rpy_rad)});
        }
    }
    const config::TrackingConfig& tracking = scene_.tracking;
    switch (tracking.source) {
        case config::TrackingSource::kScripted:
            if (tracking.script == config::TrackingScript::kGraspLiftPlacePush) {
                script_ = std::make_unique<Script>(std::in_place_index<1>, *hand_, scene_.hand,
                                                   targetObject(scene_), tracking.loop);
            } else {
                script_ = std::make_unique<Script>(std::in_place_index<0>, *hand_, scene_.hand,
                                                   targetObject(scene_), tracking.loop);
            }
            break;
        case config::TrackingSource::kReplay:
            script_ = std::make_unique<Script>(
                softhand::ReplayTrack::parse(replay_text, tracking.replay_file.string()));
            break;
        case config::TrackingSource::kTopic:
            throw std::invalid_argument("virtual user: scene '" + scene_.name +
                                        "' tracks a topic; the user's intent needs a script or "
                                        "a replay file");
    }
}

VirtualUser::~VirtualUser() = default;

double VirtualUser::distalPhalanxLengthM(config::Finger finger) const {
    for (const softhand::BoneInfo& bone : model_->bones) {
        if (bone.finger == finger && bone.segment == softhand::Segment::kDistal) {
            return bone.length_m;
        }
    }
    throw std::invalid_argument("virtual user: scene '" + scene_.name + "' does not simulate the " +
                                std::string(config::toString(finger)) +
                                " finger's distal phalanx, where its thimble sits");
}

softhand::HandPoseInput VirtualUser::intent(double t_s) const {
    const bool loop = scene_.tracking.loop;
    return std::visit(
        [&](const auto& script) {
            if constexpr (std::is_same_v<std::decay_t<decltype(script)>, softhand::ReplayTrack>) {
                return script.at(t_s, loop);
            } else {
                return script.at(t_s);
            }
        },
        *script_);
}

void VirtualUser::wear(const config::DeviceConfig& device, DeviceEmulator& emulator) {
    const auto binding = scene_.devices.find(device.name);
    if (binding == scene_.devices.end()) {
        throw std::invalid_argument("virtual user: device '" + device.name +
                                    "' is not bound to a finger in scene '" + scene_.name + "'");
    }
    const config::Finger finger = binding->second.finger;
    ExoskeletonModel* exoskeleton = emulator.exoskeletonModel();
    if (exoskeleton == nullptr) {
        // A thimble moves no joint of the hand: it indents the pad.
        const ThimbleModel* thimble = emulator.thimbleModel();
        if (thimble != nullptr) {
            thimbles_.push_back(
                {thimble, UserPad(device.thimble(), pad_, 0.5 * distalPhalanxLengthM(finger))});
            worn_.push_back({finger, static_cast<int>(thimbles_.size()) - 1});
            felt_.push_back({device.name, 0.0, FeltPadContact{}});
        }
        return;
    }
    worn_.push_back({finger, -1});
    felt_.push_back({device.name, 0.0, FeltPadContact{}});
    const softhand::HandPoseInput start = intent(0.0);
    const std::size_t first = firstAngle(finger);
    const std::array<double, 3> q{start.flexion_rad[first], start.flexion_rad[first + 1],
                                  start.flexion_rad[first + 2]};
    exoskeleton->setHandImpedance(impedance_);
    exoskeleton->placeFinger(q);
    exoskeleton->setIntent(q);
    exoskeletons_.push_back({finger, exoskeleton});
}

void VirtualUser::drive(double t_s) {
    if (exoskeletons_.empty()) {
        return;
    }
    const softhand::HandPoseInput pose = intent(t_s);
    for (const WornExoskeleton& worn : exoskeletons_) {
        const std::size_t first = firstAngle(worn.finger);
        worn.model->setIntent(
            {pose.flexion_rad[first], pose.flexion_rad[first + 1], pose.flexion_rad[first + 2]});
    }
}

const std::vector<VirtualUser::Felt>& VirtualUser::feel(double t_s) {
    const softhand::HandPoseInput pose = actualPose(t_s);
    // Once per finger, however many devices it wears.
    std::array<double, 5> depth{};
    std::array<bool, 5> done{};
    for (std::size_t i = 0; i < worn_.size(); ++i) {
        const auto finger = static_cast<std::size_t>(worn_[i].finger);
        if (!done[finger]) {
            depth[finger] = fingerPenetrationM(worn_[i].finger, pose);
            done[finger] = true;
        }
        felt_[i].finger_penetration_m = depth[finger];
        if (worn_[i].thimble >= 0) {
            WornThimble& thimble = thimbles_[static_cast<std::size_t>(worn_[i].thimble)];
            felt_[i].pad = thimble.pad.feel(thimble.model->angleRad());
        }
    }
    return felt_;
}

double VirtualUser::fingerPenetrationM(config::Finger finger,
                                       const softhand::HandPoseInput& pose) const {
    const auto& points = skin_[static_cast<std::size_t>(finger)];
    if (points.empty()) {
        return std::nan("");
    }
    hand_->bonePoses(pose, bone_poses_);
    double deepest = 0.0;
    for (const SkinPoint& point : points) {
        const softhand::BonePose& bone = bone_poses_[point.bone];
        const softhand::Vec3 p_world = bone.position_m + bone.rotation * point.offset_m;
        for (const Obstacle& obstacle : obstacles_) {
            const softhand::SurfaceQuery query = softhand::querySurface(
                obstacle.shape, obstacle.rotation.transpose() * (p_world - obstacle.position_m));
            deepest = std::max(deepest, -query.phi_m);
        }
    }
    return deepest;
}

softhand::HandPoseInput VirtualUser::actualPose(double t_s) const {
    softhand::HandPoseInput pose = intent(t_s);
    for (const WornExoskeleton& worn : exoskeletons_) {
        const std::size_t first = firstAngle(worn.finger);
        const std::array<double, 3>& q = worn.model->jointRad();
        for (std::size_t j = 0; j < 3; ++j) {
            pose.flexion_rad[first + j] = q[j];
        }
    }
    return pose;
}

std::optional<msgs::HandPose> VirtualUser::track(std::int64_t now_ns, double t_s) {
    const auto period_ns = static_cast<std::int64_t>(std::llround(1e9 / tracker_.rate_hz));
    if (next_sample_ns_ < 0) {
        next_sample_ns_ = now_ns;
    }
    if (now_ns >= next_sample_ns_) {
        // A late call samples once and moves on: a tracker drops frames, it does not burst.
        next_sample_ns_ += period_ns;
        if (next_sample_ns_ <= now_ns) {
            next_sample_ns_ = now_ns + period_ns;
        }
        softhand::HandPoseInput pose = actualPose(t_s);
        for (int i = 0; i < 3; ++i) {
            pose.wrist.position_m[i] += tracker_.position_noise_m * unit_normal_(noise_engine_);
        }
        for (double& angle : pose.flexion_rad) {
            angle += tracker_.angle_noise_rad * unit_normal_(noise_engine_);
        }
        msgs::HandPose message = softhand::toMessage(pose);
        message.header.stamp_ns = now_ns;
        message.header.source_id.assign("virtual_user");
        message.confidence = 1.0;
        in_flight_.push_back(message);
    }
    const auto latency_ns = static_cast<std::int64_t>(std::llround(tracker_.latency_ms * 1e6));
    if (in_flight_.empty() || now_ns < in_flight_.front().header.stamp_ns + latency_ns) {
        return std::nullopt;
    }
    msgs::HandPose due = in_flight_.front();
    in_flight_.pop_front();
    due.header.seq = ++seq_;
    return due;
}

}  // namespace haptic::emu
