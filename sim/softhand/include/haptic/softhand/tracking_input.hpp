#pragma once

// Tracking input of the soft hand: a hand pose (wrist pose + 15 flexion angles, the
// HandPose message, msgs/idl/HandPose.idl) turned into tracked poses of the model's bones,
// from a replay file, or from a scripted motion. Conventions in docs/softhand.md,
// "Tracking input".
//
// Wrist frame = the palm frame of the hand model at build time: origin at the palm centre,
// x towards the fingers, palm facing -z. joint_angles_rad: 5 fingers x 3 flexion angles,
// thumb, index, middle, ring, little; per finger MCP, PIP, DIP (thumb: its three joints from
// the palm out); rad, flexion positive. The fingertip model takes the pose of its distal
// phalanx from the same finger kinematics, so every model reads the same input.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "haptic/config/scene.hpp"
#include "haptic/msgs/messages.hpp"
#include "haptic/softhand/hand_kinematics.hpp"

namespace haptic::softhand {

inline constexpr std::size_t kHandPoseAngles = 15;

struct HandPoseInput {
    BonePose wrist;
    std::array<double, kHandPoseAngles> flexion_rad{};
};

// Checks and converts the message: finite values, unit quaternion (within 1e-3, then
// normalised), exactly 15 joint angles. Returns the reason when it is refused.
[[nodiscard]] std::optional<std::string> fromMessage(const msgs::HandPose& message,
                                                     HandPoseInput& out);

// The message for a pose (header and confidence left to the caller): what a tracker or a
// test publishes on the HandPose topic.
[[nodiscard]] msgs::HandPose toMessage(const HandPoseInput& pose);

// Maps hand poses to the tracked poses of a model's bones (HandModel::bones order).
class TrackedHand {
  public:
    // Call right after buildHand. `finger` is the finger of a fingertip model.
    TrackedHand(const HandModel& model, const config::HandConfig& hand);

    void bonePoses(const HandPoseInput& input, std::vector<BonePose>& poses) const;
    // Poses of the reference chain's bones (the model's own bones, or palm and phalanges of
    // the finger behind a fingertip model).
    void referencePoses(const HandPoseInput& input, std::vector<BonePose>& poses) const;
    // The pose that gives the model its build pose.
    [[nodiscard]] HandPoseInput buildPose() const;
    // Index of the finger's distal phalanx among the reference poses.
    [[nodiscard]] int referenceDistal(config::Finger finger) const {
        return referencePhalanx(finger, 2);
    }
    // The same for phalanx 0 (proximal), 1 (middle) or 2 (distal).
    [[nodiscard]] int referencePhalanx(config::Finger finger, int phalanx) const;

  private:
    HandKinematics reference_kinematics_;  // of a finger model behind a fingertip model
    std::vector<int> angle_of_joint_;      // reference joint -> index in flexion_rad
    bool fingertip_{false};
    int reference_distal_{-1};  // fingertip model: its distal phalanx in the reference
                                // fingertip model: distal build pose relative to reference
};

// Replay file (CSV, documented in docs/softhand.md): per row
//   t_s, wrist_x_m, wrist_y_m, wrist_z_m, qw, qx, qy, qz, 15 joint angles (rad)
// '#' starts a comment; blank lines are skipped; times strictly increase.
struct ReplayFrame {
    double t_s{0.0};
    HandPoseInput pose;
};

class ReplayTrack {
  public:
    // Throws std::runtime_error "<source>:<line>: <reason>" on a malformed row.
    // `text` is the file's content (this library does no I/O).
    static ReplayTrack parse(std::string_view text, const std::string& source_name);

    // Linear in position and angles, slerp in orientation; clamped at both ends, or
    // repeating with the file's duration when `loop`.
    [[nodiscard]] HandPoseInput at(double t_s, bool loop) const;
    [[nodiscard]] const std::vector<ReplayFrame>& frames() const { return frames_; }

  private:
    std::vector<ReplayFrame> frames_;
};

// Scripted press_slide_edge (loops with period kPeriod): the fingertip presses the target
// box's top face, slides across it along the box's x axis and over its +x edge, lifts and
// returns. A deterministic function of time.
class PressSlideEdgeScript {
  public:
    static constexpr double kPeriod = 6.0;
    static constexpr double kPressDepth = 0.003;  // of the lowest pad point below the face
    static constexpr double kLiftHeight = 0.010;

    // Throws std::invalid_argument when the target is not a box.
    PressSlideEdgeScript(const TrackedHand& hand, const config::HandConfig& config,
                         const config::SceneObject& target, bool loop);

    [[nodiscard]] HandPoseInput at(double t_s) const;
    // Where the script puts the lowest pad point, in the target's frame (top face centre at
    // (0, 0, half height)).
    [[nodiscard]] Vec3 padTargetInObject(double t_s) const;
    [[nodiscard]] double topFaceHalfLength() const { return half_extents_.x(); }

  private:
    [[nodiscard]] std::array<double, kHandPoseAngles> posture(double press) const;
    [[nodiscard]] double press(double t_s) const;

    const TrackedHand& hand_;
    config::Finger finger_;
    BonePose object_;
    Vec3 half_extents_;
    double pad_radius_m_{0.0};
    double distal_half_length_m_{0.0};
    bool loop_{true};
};

// Scripted grasp_lift_place_push: a lateral pinch (thumb pad against the radial side of the
// index) takes the target box across its y faces, lifts it kLiftHeight, sets it back where
// it stood, slides it kPushDistance along the world +x axis (into whatever stands there),
// opens and withdraws upwards. Palm down, fingers along +x. Needs a hand model with thumb
// and index. A deterministic function of time with period kPeriod.
class GraspLiftPlacePushScript {
  public:
    // Phase boundaries (s).
    static constexpr double kCloseEnd = 0.8;
    static constexpr double kLiftStart = 1.0;
    static constexpr double kLiftEnd = 2.0;
    static constexpr double kPlaceStart = 2.4;
    static constexpr double kPlaceEnd = 3.4;
    static constexpr double kPushStart = 3.6;
    static constexpr double kPushEnd = 5.0;
    static constexpr double kOpenEnd = 5.6;
    static constexpr double kPeriod = 6.5;
    static constexpr double kLiftHeight = 0.05;
    static constexpr double kPushDistance = 0.05;
    // How far the closed thumb would put its pad past the box face: the grip force comes
    // from the tracking springs pulling the thumb towards that.
    static constexpr double kSqueeze = 0.010;
    static constexpr double kOpenGap = 0.012;         // thumb pad to box face before closing
    static constexpr double kSetDownSqueeze = 0.004;  // the eased grip as the box lands

    // Throws std::invalid_argument when the target is not a box, the hand lacks the thumb or
    // the index, or the box does not fit between them.
    GraspLiftPlacePushScript(const TrackedHand& hand, const config::HandConfig& config,
                             const config::SceneObject& target, bool loop);

    [[nodiscard]] HandPoseInput at(double t_s) const;
    // Where the script carries the box centre (world).
    [[nodiscard]] Vec3 boxTarget(double t_s) const;

  private:
    [[nodiscard]] std::array<double, kHandPoseAngles> posture(double closure) const;
    // The held box's centre in the wrist frame at a thumb closure; optionally the y of the
    // thumb pad's surface.
    [[nodiscard]] Vec3 boxInWrist(double closure, double* thumb_surface_y) const;
    [[nodiscard]] double closureForGap(double gap_m) const;
    [[nodiscard]] double closure(double t_s) const;

    const TrackedHand& hand_;
    Vec3 start_{Vec3::Zero()};
    double half_width_m_{0.0};
    double half_length_m_{0.0};
    double thumb_pad_radius_m_{0.0};
    double index_side_radius_m_{0.0};
    double thumb_pad_offset_m_{0.0};
    double open_{0.0};
    double closed_{1.0};
    double eased_{1.0};
    bool loop_{true};
};

}  // namespace haptic::softhand
