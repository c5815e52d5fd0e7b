#include "tracking_source.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <variant>

#include "HandPosePubSubTypes.h"
#include "haptic/msgs/conversions.hpp"
#include "haptic/softhand/tracking_filter.hpp"

namespace haptic::handsim {
namespace {

class ScriptedSource final : public TrackingSource {
  public:
    ScriptedSource(const config::SceneConfig& scene, const softhand::SceneSimulation& sim)
        : script_(makeScript(scene, sim)), name_(scene.tracking.target_object) {}
    [[nodiscard]] softhand::HandPoseInput initialPose() const override {
        return std::visit([](const auto& script) { return script.at(0.0); }, script_);
    }
    std::optional<softhand::HandPoseInput> poll(double t_s, std::string&) override {
        return std::visit([t_s](const auto& script) { return script.at(t_s); }, script_);
    }
    [[nodiscard]] std::string describe() const override {
        return "scripted " +
               std::string(config::toString(script_.index() == 0
                                                ? config::TrackingScript::kPressSlideEdge
                                                : config::TrackingScript::kGraspLiftPlacePush)) +
               " on '" + name_ + "'";
    }

  private:
    static const config::SceneObject& target(const config::SceneConfig& scene) {
        const auto* object = scene.findObject(scene.tracking.target_object);
        if (object == nullptr) {
            throw std::invalid_argument("tracking.target_object '" + scene.tracking.target_object +
                                        "' is not in the scene");
        }
        return *object;
    }
    using Script = std::variant<softhand::PressSlideEdgeScript, softhand::GraspLiftPlacePushScript>;
    static Script makeScript(const config::SceneConfig& scene,
                             const softhand::SceneSimulation& sim) {
        const auto& tracking = scene.tracking;
        if (tracking.script == config::TrackingScript::kGraspLiftPlacePush) {
            return Script(std::in_place_index<1>, sim.trackedHand(), scene.hand, target(scene),
                          tracking.loop);
        }
        return Script(std::in_place_index<0>, sim.trackedHand(), scene.hand, target(scene),
                      tracking.loop);
    }
    Script script_;
    std::string name_;
};

class ReplaySource final : public TrackingSource {
  public:
    explicit ReplaySource(const config::TrackingConfig& tracking)
        : track_(load(tracking.replay_file)), loop_(tracking.loop), path_(tracking.replay_file) {}
    [[nodiscard]] softhand::HandPoseInput initialPose() const override {
        return track_.at(0.0, loop_);
    }
    std::optional<softhand::HandPoseInput> poll(double t_s, std::string&) override {
        return track_.at(t_s, loop_);
    }
    [[nodiscard]] std::string describe() const override {
        return "replay of " + path_.string() + " (" + std::to_string(track_.frames().size()) +
               " frames" + (loop_ ? ", looping)" : ")");
    }

  private:
    static softhand::ReplayTrack load(const std::filesystem::path& path) {
        std::ifstream file(path);
        if (!file) {
            throw std::runtime_error(path.string() + ": cannot open the replay file");
        }
        std::stringstream text;
        text << file.rdbuf();
        return softhand::ReplayTrack::parse(text.str(), path.string());
    }
    softhand::ReplayTrack track_;
    bool loop_;
    std::filesystem::path path_;
};

class TopicSource final : public TrackingSource {
  public:
    TopicSource(const config::SceneConfig& scene, const softhand::SceneSimulation& sim,
                ipc::DdsParticipant& participant,
                const std::optional<config::TrackingFilterConfig>& filter)
        : reader_(participant.createReader<idl::HandPosePubSubType>(scene.tracking.topic,
                                                                    ipc::TopicKind::kStream)),
          initial_(sim.trackedHand().buildPose()),
          topic_(scene.tracking.topic),
          gap_s_(1e-3 * scene.tracking.timeout_ms) {
        if (filter) {
            softhand::TrackingFilterSettings settings;
            settings.angles.reset();
            if (filter->angle_beta_s_per_rad) {
                settings.angles = softhand::OneEuroParameters{filter->min_cutoff_hz,
                                                              *filter->angle_beta_s_per_rad,
                                                              filter->derivative_cutoff_hz};
            }
            settings.position = {filter->min_cutoff_hz, filter->position_beta_s_per_m,
                                 filter->derivative_cutoff_hz};
            filter_.emplace(settings);
        }
        // Until the tracker speaks, the hand waits well above the scene's objects.
        initial_.wrist.position_m.z() += 0.3;
    }
    [[nodiscard]] softhand::HandPoseInput initialPose() const override { return initial_; }
    std::optional<softhand::HandPoseInput> poll(double, std::string& rejection) override {
        std::optional<softhand::HandPoseInput> latest;
        idl::HandPose sample;
        std::int64_t received_ns = 0;
        while (reader_.take(sample, received_ns)) {
            msgs::HandPose message;
            softhand::HandPoseInput input;
            const auto converted = msgs::fromIdl(sample, message);
            if (!converted.ok()) {
                rejection = "HandPose on '" + topic_ + "': " + converted.error;
                continue;
            }
            if (const auto reason = softhand::fromMessage(message, input)) {
                rejection = "HandPose on '" + topic_ + "': " + *reason;
                continue;
            }
            // Every sample through the filter, in order, at the tracker's own stamps; after a
            // silence longer than the tracking timeout it starts afresh at the new pose.
            latest = filter_
                         ? filter_->filter(
                               input, 1e-9 * static_cast<double>(message.header.stamp_ns), gap_s_)
                         : input;
            origin_ = {message.header.stamp_ns, received_ns};
        }
        return latest;
    }
    [[nodiscard]] msgs::TrackingOrigin origin() const override { return origin_; }
    [[nodiscard]] std::string describe() const override {
        return "HandPose topic '" + topic_ + "'" + (filter_ ? " through the One Euro filter" : "");
    }

  private:
    ipc::DdsReader<idl::HandPose> reader_;
    softhand::HandPoseInput initial_;
    std::string topic_;
    double gap_s_;
    std::optional<softhand::HandPoseFilter> filter_;
    msgs::TrackingOrigin origin_{};
};

}  // namespace

std::unique_ptr<TrackingSource> makeTrackingSource(
    const config::SceneConfig& scene, const softhand::SceneSimulation& sim,
    ipc::DdsParticipant& participant, const std::optional<config::TrackingFilterConfig>& filter) {
    switch (scene.tracking.source) {
        case config::TrackingSource::kScripted:
            return std::make_unique<ScriptedSource>(scene, sim);
        case config::TrackingSource::kReplay:
            return std::make_unique<ReplaySource>(scene.tracking);
        case config::TrackingSource::kTopic:
            return std::make_unique<TopicSource>(scene, sim, participant, filter);
    }
    throw std::invalid_argument("unknown tracking source");
}

}  // namespace haptic::handsim
