#include "haptic/softhand/hand_kinematics.hpp"

#include <Eigen/Geometry>
#include <stdexcept>

namespace haptic::softhand {

HandKinematics::HandKinematics(const HandModel& model) {
    const Simulation& sim = model.simulation;
    bone_of_body_.assign(static_cast<std::size_t>(sim.bodyCount()), -1);
    for (std::size_t k = 0; k < model.bones.size(); ++k) {
        const int body = model.bones[k].body;
        bone_of_body_[static_cast<std::size_t>(body)] = static_cast<int>(k);
        body_of_bone_.push_back(body);
        build_.push_back({sim.bodyPosition(body), sim.bodyRotation(body)});
        finger_of_bone_.push_back(model.bones[k].finger);
        segment_of_bone_.push_back(model.bones[k].segment);
    }
    for (int j = 0; j < sim.jointCount(); ++j) {
        const JointDesc& desc = sim.jointDesc(j);
        const int parent = bone_of_body_.at(static_cast<std::size_t>(desc.body_a));
        const int child = bone_of_body_.at(static_cast<std::size_t>(desc.body_b));
        if (parent < 0 || child < 0 || parent >= child) {
            throw std::logic_error("HandKinematics: joints must link bones parent-first");
        }
        joints_.push_back({parent, child, desc.axis_world.normalized(), desc.anchor_world_m});
    }
}

std::optional<FingerChain> HandKinematics::chain(config::Finger finger) const {
    FingerChain result;
    result.finger = finger;
    for (std::size_t k = 0; k < finger_of_bone_.size(); ++k) {
        if (finger_of_bone_[k] != finger) {
            continue;
        }
        const auto segment = segment_of_bone_[k];
        const int slot = segment == Segment::kProximal ? 0 : (segment == Segment::kMiddle ? 1 : 2);
        result.bones[static_cast<std::size_t>(slot)] = static_cast<int>(k);
    }
    for (std::size_t j = 0; j < joints_.size(); ++j) {
        for (std::size_t s = 0; s < 3; ++s) {
            if (joints_[j].child_bone == result.bones[s]) {
                result.joints[s] = static_cast<int>(j);
            }
        }
    }
    for (std::size_t s = 0; s < 3; ++s) {
        if (result.bones[s] < 0 || result.joints[s] < 0) {
            return std::nullopt;
        }
    }
    return result;
}

double HandKinematics::flexion(const Simulation& sim, int joint) const {
    const JointFrame& f = joints_.at(static_cast<std::size_t>(joint));
    const Mat3& parent = sim.bodyRotation(body_of_bone_[static_cast<std::size_t>(f.parent_bone)]);
    const Mat3& child = sim.bodyRotation(body_of_bone_[static_cast<std::size_t>(f.child_bone)]);
    // The rotation the joint applied in the build frame: R_a0 R_a^T R_b R_b0^T. Its twist
    // about the hinge axis is the flexion (swing-twist split of the quaternion).
    const Mat3 relative = build_[static_cast<std::size_t>(f.parent_bone)].rotation *
                          parent.transpose() * child *
                          build_[static_cast<std::size_t>(f.child_bone)].rotation.transpose();
    const Eigen::Quaterniond q(relative);
    return 2.0 * std::atan2(q.vec().dot(f.axis_m), q.w());
}

Vec3 HandKinematics::axis(const Simulation& sim, int joint) const {
    const JointFrame& f = joints_.at(static_cast<std::size_t>(joint));
    const auto bone = static_cast<std::size_t>(f.parent_bone);
    return sim.bodyRotation(body_of_bone_[bone]) * build_[bone].rotation.transpose() * f.axis_m;
}

Vec3 HandKinematics::anchor(const Simulation& sim, int joint) const {
    const JointFrame& f = joints_.at(static_cast<std::size_t>(joint));
    const auto bone = static_cast<std::size_t>(f.parent_bone);
    const int body = body_of_bone_[bone];
    return sim.bodyPosition(body) + sim.bodyRotation(body) * build_[bone].rotation.transpose() *
                                        (f.anchor_m - build_[bone].position_m);
}

void HandKinematics::forward(const BonePose& root, std::span<const double> flexion,
                             std::vector<BonePose>& poses) const {
    if (flexion.size() != joints_.size()) {
        throw std::invalid_argument("HandKinematics::forward: one flexion per joint required");
    }
    poses.assign(build_.size(), root);
    for (std::size_t j = 0; j < joints_.size(); ++j) {
        const JointFrame& f = joints_[j];
        const BonePose& parent0 = build_[static_cast<std::size_t>(f.parent_bone)];
        const BonePose& child0 = build_[static_cast<std::size_t>(f.child_bone)];
        const BonePose& parent = poses[static_cast<std::size_t>(f.parent_bone)];
        // Child = parent * parent0^-1 * (rotation by the flexion about the build-time hinge)
        // * child0, all rigid transforms.
        const Mat3 hinge = Eigen::AngleAxisd(flexion[j], f.axis_m).toRotationMatrix();
        const Mat3 carry = parent.rotation * parent0.rotation.transpose();
        BonePose& child = poses[static_cast<std::size_t>(f.child_bone)];
        child.rotation = carry * hinge * child0.rotation;
        child.position_m =
            parent.position_m +
            carry * (f.anchor_m + hinge * (child0.position_m - f.anchor_m) - parent0.position_m);
    }
}

}  // namespace haptic::softhand
