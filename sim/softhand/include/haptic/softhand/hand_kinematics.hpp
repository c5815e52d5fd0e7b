#pragma once

// Forward kinematics and joint Jacobians of a built hand model, from its build pose. The
// device outputs and the tracking inputs both speak in joint flexion angles; this is where
// they are turned into bone poses and back.
//
// Flexion of a joint is the rotation of its child bone about the joint's build-time hinge axis
// (the parent's +y at build time; for the fingers of this model positive flexion curls the
// tip towards the palm, -z at build time), relative to the build pose, measured as the twist
// part of the child's rotation relative to its parent. A universal joint (MCP) reports its
// flexion only; abduction is left out (the devices here are planar).

#include <array>
#include <optional>
#include <span>
#include <vector>

#include "haptic/softhand/elastic_tracking.hpp"

namespace haptic::softhand {

// The three phalanges of one finger and the joints in front of them.
struct FingerChain {
    config::Finger finger{config::Finger::kIndex};
    std::array<int, 3> bones{-1, -1, -1};   // index in HandModel::bones: proximal, middle, distal
    std::array<int, 3> joints{-1, -1, -1};  // simulation joint: MCP, PIP, DIP (thumb: CMC-MCP-IP)
};

class HandKinematics {
  public:
    // Call right after buildHand (the model must still be in its build pose).
    explicit HandKinematics(const HandModel& model);

    // The chain of `finger`, or nullopt when the model does not simulate its three phalanges
    // (the fingertip model has the distal phalanx only).
    [[nodiscard]] std::optional<FingerChain> chain(config::Finger finger) const;

    [[nodiscard]] int jointCount() const { return static_cast<int>(joints_.size()); }
    [[nodiscard]] const BonePose& buildPose(int bone) const { return build_[bone]; }

    // Current flexion of a simulation joint (rad).
    [[nodiscard]] double flexion(const Simulation& sim, int joint) const;
    // Current hinge axis (world, unit) and anchor (world) of a simulation joint.
    [[nodiscard]] Vec3 axis(const Simulation& sim, int joint) const;
    [[nodiscard]] Vec3 anchor(const Simulation& sim, int joint) const;

    // Bone poses (HandModel::bones order) for the root bone (bones[0]: palm, or the distal
    // phalanx of the fingertip model) at `root` and the flexion of every joint in simulation
    // joint order. `flexion` must have jointCount() entries.
    void forward(const BonePose& root, std::span<const double> flexion,
                 std::vector<BonePose>& poses) const;

  private:
    struct JointFrame {
        int parent_bone;
        int child_bone;
        Vec3 axis_m;    // build-time world axis
        Vec3 anchor_m;  // build-time world anchor
    };
    std::vector<int> bone_of_body_;
    std::vector<int> body_of_bone_;
    std::vector<BonePose> build_;
    std::vector<JointFrame> joints_;
    std::vector<std::optional<config::Finger>> finger_of_bone_;
    std::vector<Segment> segment_of_bone_;
};

}  // namespace haptic::softhand
