#pragma once

// What the soft hand sends to the daemon each simulation step (msgs/idl/ConstraintSet.idl,
// ContactSurface.idl). Conventions are listed in docs/softhand.md.
//
// Kinesthetic (exoskeleton on a finger): q_sim_rad = the simulated finger's flexion
// [MCP, PIP, DIP] (rad, flexion positive, HandKinematics), and for each (phalanx, object)
// pair whose rigid skin (the build-pose skin carried by its bone) comes nearer than the
// contact margin one linearised non-penetration constraint a^T q >= b:
// phi(q_sim) + a^T (q - q_sim) >= 0 with a_j = n . (axis_j x (x - anchor_j)), x the rigid
// skin point deepest in the object, phi its signed distance. n is the object's normal at x
// while x is outside; inside, the direction of the normal forces the object presses the
// simulated skin with (docs/softhand.md, "Exoskeleton: ConstraintSet").
//
// Tactile (thimble on the fingertip): the finger-pad skin nodes, carried rigidly by the
// user's distal phalanx as tracked (the undeformed pad on the finger the device is strapped
// to), in the device base frame D, with their signed distance to the nearest object
// (negative = penetrating), that object's outward normal in D, and weight = sample area x pad
// stiffness per area (N/m).

#include <optional>
#include <vector>

#include "haptic/config/types.hpp"
#include "haptic/msgs/messages.hpp"
#include "haptic/softhand/hand_kinematics.hpp"

namespace haptic::softhand {

struct KinestheticOutputSettings {
    double contact_margin_m{0.003};  // constraints are sent for gaps below this
    double min_gradient_m{1e-6};     // |a| below this carries no information: not sent
};

class KinestheticOutput {
  public:
    // Throws std::invalid_argument when the model does not simulate the finger's phalanges.
    KinestheticOutput(const HandModel& model, const HandKinematics& kinematics,
                      config::Finger finger, KinestheticOutputSettings settings = {});

    [[nodiscard]] std::array<double, 3> jointAngles(const Simulation& sim) const;
    // Fills everything but the header: a constraint row per phalanx and object within the
    // margin, and the reference torques (the tracking coupling's, while the finger touches
    // anything; 0 otherwise). Once per simulation step: each row's normal turns by at most
    // kMaxNormalTurnRad from the one the same contact had in the previous call.
    void fill(const Simulation& sim, msgs::ConstraintSet& out);
    // The hand was placed (no continuity with the previous step): forget the last normals.
    void reset();

    // A finger rolls over an edge in tens of ms; at 60-200 Hz this lets the normal turn by
    // 90 degrees within 6 frames, while a face taken for another for one frame (the pressed
    // skin briefly on the side face, or not pressed at all) is not followed.
    static constexpr double kMaxNormalTurnRad = 0.26;

  private:
    HandKinematics kinematics_;
    KinestheticOutputSettings settings_;
    FingerChain chain_;
    // The skin of each phalanx as built, rigid with its bone: the finger the exoskeleton's
    // kinematics model (g(chi(q)) of docs/algorithms.md, subspace proxy), not the tissue the
    // contact deforms. A constraint from deformed skin sits wherever the sim's bone is (the pressed
    // tissue lies on the surface), so it would move with the tracked hand, its noise and its
    // latency, and the 1 kHz loop would follow the tracker instead of the object.
    struct RigidSkin {
        int body{-1};
        std::vector<Vec3> p_bone;  // rest positions in the bone frame
    };
    std::array<RigidSkin, 3> skin_;
    // The fully actuated reference torques of fill() at joint angles `q` (jointAngles()): 0
    // without contact on the finger.
    [[nodiscard]] std::array<double, msgs::kMaxJointDofs> referenceTorques(
        const Simulation& sim, const std::array<double, 3>& q, const std::array<Vec3, 3>& axes,
        const std::array<Vec3, 3>& anchors) const;

    // [first, end) node ids of each phalanx: its contacts, and its tissue's weight
    std::array<std::pair<int, int>, 3> nodes_{};
    // The normal of each (object, phalanx) row sent in the last call; empty: no row.
    std::vector<std::array<std::optional<Vec3>, 3>> last_normal_;
};

struct TactileOutputSettings {
    int max_samples{64};  // the thimble optimiser's pad_samples
    // Pad stiffness per unit area (Pa/m): the pressure rise per metre of indentation of the
    // stand-in pad, E / (pad tissue thickness) at the build material. 0 = derive it so.
    double pad_stiffness_pa_per_m{0.0};
};

class TactileOutput {
  public:
    // `finger_from_device` is the thimble's finger_calibration.T_finger_device. Finger frame
    // F: origin at the centre of the distal phalanx on its axis, x along the phalanx towards
    // the tip, z from the nail towards the pad, y = z x x. Throws std::invalid_argument when
    // the model has no distal phalanx for `finger`.
    TactileOutput(const HandModel& model, config::Finger finger,
                  const config::Transform& finger_from_device, const TissueMaterial& material,
                  TactileOutputSettings settings = {});

    [[nodiscard]] int sampleCount() const { return static_cast<int>(samples_.size()); }
    // The distal phalanx the device is worn on (index into HandModel::bones).
    [[nodiscard]] std::size_t bone() const { return bone_; }
    // Device base frame in the world for a pose of that phalanx.
    [[nodiscard]] BonePose deviceFrame(const BonePose& finger_bone) const;
    // Fills everything but the header. `finger_bone` is the user's distal phalanx as tracked
    // (ElasticTracking::trackedPoses): the device is strapped to the user's finger, not to the
    // simulated one, which the objects hold back (docs/algorithms.md §3.2, the bone
    // kinematically attached to the tracked finger frame F). The samples' depths are where the
    // virtual object lies against the user's pad; the reference is the sim's contact on its pad,
    // the coupling force between the tracked and the simulated finger there.
    void fill(const Simulation& sim, const BonePose& finger_bone, msgs::ContactSurface& out) const;

  private:
    struct Sample {
        Vec3 p_bone_m;  // rest position in the distal bone frame
        double area_m2;
        int node;  // the skin node it was taken from
    };
    std::size_t bone_{0};
    int body_{-1};                 // the simulated distal phalanx
    std::pair<int, int> nodes_{};  // [first, end) node ids of the distal phalanx
    // Per node of the distal phalanx (from nodes_.first): 1 for a sampled pad node, the skin
    // the thimble's plate can press on; the reference counts the contacts there only.
    std::vector<char> on_pad_;
    // Per node as on_pad_, refilled by every fill(): 1 where the sim's contact pushes on it.
    mutable std::vector<char> pressed_;
    // Per node as on_pad_, refilled by every fill(): the normal force the contact presses it with.
    mutable std::vector<double> normal_force_n_;
    Mat3 bone_from_device_rotation_;
    Vec3 bone_from_device_translation_m_;
    double pad_stiffness_pa_per_m_{0.0};
    std::vector<Sample> samples_;
};

}  // namespace haptic::softhand
