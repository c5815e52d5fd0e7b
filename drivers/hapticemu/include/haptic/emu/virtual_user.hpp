#pragma once

// The virtual user: one model of the user's hand that is the single truth for the tracker and
// for the devices (docs/drivers.md, "Virtual user"). Its intent is a scene's tracking script
// or replay; the finger an exoskeleton is worn on follows that intent through the hand
// impedance and the exoskeleton's actuator force (ExoskeletonModel), so the device moves the
// finger away from its intent. The thimble pushes its plate against the pad (UserPad: the
// user's own pad model gives the force felt) and reacts on the nail side of the same phalanx:
// an internal force that indents the pad but moves no joint. The tracker sees the
// actual pose, sampled at its rate and delivered after its latency, with noise.
// No I/O: hapticemu's main publishes what track() returns.

#include <array>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "haptic/config/virtual_user.hpp"
#include "haptic/emu/device_emulator.hpp"
#include "haptic/emu/user_pad.hpp"
#include "haptic/msgs/messages.hpp"
#include "haptic/softhand/collider.hpp"
#include "haptic/softhand/hand_builder.hpp"
#include "haptic/softhand/tracking_input.hpp"

namespace haptic::emu {

class VirtualUser {
  public:
    // `replay_text`: the content of the scene's replay file when its tracking source is
    // replay (this library reads no files). Throws std::invalid_argument when the scene's
    // tracking block gives no intent (a topic source) or a device's finger is not simulated.
    explicit VirtualUser(const config::VirtualUserConfig& config,
                         std::string_view replay_text = {});
    ~VirtualUser();
    VirtualUser(const VirtualUser&) = delete;
    VirtualUser& operator=(const VirtualUser&) = delete;

    // Puts `device` on the hand. An exoskeleton's finger joints become the user's: the
    // finger is placed at the intent of t = 0 and follows it through the hand impedance. A
    // thimble's plate presses on the user's pad (config pad).
    void wear(const config::DeviceConfig& device, DeviceEmulator& emulator);

    // What the user feels of each worn device at t_s (wear() order): how deep the finger it is
    // worn on reaches into the scene's static objects (its skin at the actual pose, as rigid
    // as its bones: the penetration of the user's own finger into where the virtual object
    // is; NaN for a finger the hand model does not simulate), and for a thimble the pad under
    // its plate where the thimble's model has it now.
    struct Felt {
        std::string device;
        double finger_penetration_m{0.0};
        FeltPadContact pad;  // pose_known false for a device that is not a thimble
    };
    [[nodiscard]] const std::vector<Felt>& feel(double t_s);
    // The deepest reach of `finger`'s skin into the scene's static objects at `pose` (0 when
    // clear of them; NaN when the hand model has no tissue on that finger).
    [[nodiscard]] double fingerPenetrationM(config::Finger finger,
                                            const softhand::HandPoseInput& pose) const;

    // Before the devices' models step at t_s (seconds since start): the worn exoskeletons'
    // fingers aim for the intent of that instant.
    void drive(double t_s);

    [[nodiscard]] softhand::HandPoseInput intent(double t_s) const;
    // The pose the hand has: the intent, with each worn exoskeleton's finger where the
    // device's model has it.
    [[nodiscard]] softhand::HandPoseInput actualPose(double t_s) const;

    // The tracker. Call at least once per millisecond with the monotonic clock and t_s of the
    // same instant; returns the messages that are due (at most one per call in steady state).
    // Each carries the stamp of the instant it was sampled at.
    [[nodiscard]] std::optional<msgs::HandPose> track(std::int64_t now_ns, double t_s);
    [[nodiscard]] std::uint64_t samplesPublished() const noexcept { return seq_; }

  private:
    // The scene hand's distal phalanx of the finger (throws std::invalid_argument without one).
    [[nodiscard]] double distalPhalanxLengthM(config::Finger finger) const;
    struct WornExoskeleton {
        config::Finger finger;
        ExoskeletonModel* model;
    };
    struct WornThimble {
        const ThimbleModel* model;
        UserPad pad;
    };
    struct WornDevice {
        config::Finger finger;
        int thimble{-1};  // index in thimbles_, -1: not a thimble
    };
    struct Obstacle {
        softhand::ColliderShape shape;
        softhand::Vec3 position_m;
        softhand::Mat3 rotation;
    };
    struct SkinPoint {
        std::size_t bone;         // index in the hand model's bones
        softhand::Vec3 offset_m;  // rest position in the bone's frame
    };
    using Script = std::variant<softhand::PressSlideEdgeScript, softhand::GraspLiftPlacePushScript,
                                softhand::ReplayTrack>;

    config::TrackerConfig tracker_;
    config::HandImpedanceConfig impedance_;
    config::UserPadConfig pad_;
    config::SceneConfig scene_;
    std::unique_ptr<softhand::HandModel> model_;
    std::unique_ptr<softhand::TrackedHand> hand_;
    std::unique_ptr<Script> script_;
    std::vector<WornExoskeleton> exoskeletons_;
    std::vector<WornThimble> thimbles_;
    std::vector<WornDevice> worn_;
    std::vector<Felt> felt_;                      // parallel to worn_
    std::vector<Obstacle> obstacles_;             // the scene's static objects
    std::array<std::vector<SkinPoint>, 5> skin_;  // per finger: its phalanges' tissue nodes
    mutable std::vector<softhand::BonePose> bone_poses_;

    std::mt19937 noise_engine_;
    std::normal_distribution<double> unit_normal_{0.0, 1.0};
    std::int64_t next_sample_ns_{-1};
    std::deque<msgs::HandPose> in_flight_;  // sampled, waiting out the latency
    std::uint64_t seq_{0};
};

}  // namespace haptic::emu
