#pragma once

// Where handsim's hand pose comes from (scene tracking.source): the scripted motion, a
// replay file, or the HandPose DDS topic. Poll once per step.

#include <memory>
#include <optional>
#include <string>

#include "haptic/config/scene.hpp"
#include "haptic/config/sim.hpp"
#include "haptic/ipc/dds_participant.hpp"
#include "haptic/softhand/scene_simulation.hpp"

namespace haptic::handsim {

class TrackingSource {
  public:
    virtual ~TrackingSource() = default;
    // The pose to start from (the hand is placed there at rest).
    [[nodiscard]] virtual softhand::HandPoseInput initialPose() const = 0;
    // The pose at time t_s since start, or nullopt when there is no new input (topic).
    // `rejection` receives the reason when an input was refused (NaN, bad quaternion, ...).
    virtual std::optional<softhand::HandPoseInput> poll(double t_s, std::string& rejection) = 0;
    [[nodiscard]] virtual std::string describe() const = 0;
    // The newest tracker sample taken so far (zero for scripts and replays): the sim's outputs
    // carry it so the tracker-to-force latency can be measured downstream.
    [[nodiscard]] virtual msgs::TrackingOrigin origin() const { return {}; }
};

// Throws std::runtime_error (replay file errors carry file:line) or std::invalid_argument.
// `filter` (sim.yaml tracking_filter) smooths the poses of a topic, i.e. of a real tracker;
// scripts and replays are used as they are.
[[nodiscard]] std::unique_ptr<TrackingSource> makeTrackingSource(
    const config::SceneConfig& scene, const softhand::SceneSimulation& sim,
    ipc::DdsParticipant& participant,
    const std::optional<config::TrackingFilterConfig>& filter = std::nullopt);

}  // namespace haptic::handsim
