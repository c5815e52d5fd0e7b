// handsim's tracking sources (scene tracking.source, sim.yaml tracking_filter) as handsim
// builds them (makeTrackingSource, the executable's own code): a replay file is replayed,
// held or looped as tracking.loop says; poses from a HandPose topic, written here by a real
// Fast DDS writer, pass as they come without a filter and through the One Euro filter each
// tracking_filter key shapes.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "HandPosePubSubTypes.h"
#include "haptic/config/scene.hpp"
#include "haptic/config/sim.hpp"
#include "haptic/ipc/dds_participant.hpp"
#include "haptic/msgs/conversions.hpp"
#include "haptic/softhand/scene_simulation.hpp"
#include "haptic/softhand/tracking_input.hpp"
#include "tracking_source.hpp"

namespace haptic::handsim {
namespace {

using ::testing::HasSubstr;
using namespace std::chrono_literals;

const std::string kConfigDir = HAPTIC_CONFIG_DIR;

config::SceneConfig thimbleScene() {
    return config::loadSceneConfig(kConfigDir + "/scenes/thimble_only.yaml");
}

ipc::DdsParticipant makeParticipant() {
    return ipc::DdsParticipant(
        ipc::DdsSettings{static_cast<std::uint32_t>(100 + ::getpid() % 100),
                         kConfigDir + "/dds_profiles.xml", "haptic_participant"},
        "handsim_tracking_source_test");
}

// One replay row: t, wrist xyz, quaternion (w x y z), 15 angles all `angle`.
std::string replayRow(double t_s, double x_m, double angle_rad) {
    std::string row = std::to_string(t_s) + ", " + std::to_string(x_m) + ", 0, 0.1, 1, 0, 0, 0";
    for (int i = 0; i < 15; ++i) {
        row += ", " + std::to_string(angle_rad);
    }
    return row + "\n";
}

// tracking.script and tracking.target_object: handsim runs the script the scene names on the
// object it names, and holds its last pose or loops it as tracking.loop says.
TEST(HandsimTrackingSource, AScriptedSceneRunsTheScriptItNamesOnItsTarget) {
    auto participant = makeParticipant();
    const auto samePose = [](const softhand::HandPoseInput& a, const softhand::HandPoseInput& b) {
        return (a.wrist.position_m - b.wrist.position_m).norm() < 1e-12 &&
               std::abs(a.flexion_rad[4] - b.flexion_rad[4]) < 1e-12;
    };
    {
        auto scene = config::loadSceneConfig(kConfigDir + "/scenes/grasp_box.yaml");
        ASSERT_EQ(scene.tracking.script, config::TrackingScript::kGraspLiftPlacePush);
        const softhand::SceneSimulation sim(scene, {});
        const softhand::GraspLiftPlacePushScript script(
            sim.trackedHand(), scene.hand, *scene.findObject("box"), scene.tracking.loop);
        const auto source = makeTrackingSource(scene, sim, participant);
        EXPECT_EQ(source->describe(), "scripted grasp_lift_place_push on 'box'");
        EXPECT_TRUE(samePose(source->initialPose(), script.at(0.0)));
        std::string rejection;
        const auto lifted = source->poll(1.5, rejection);
        ASSERT_TRUE(lifted.has_value()) << rejection;
        EXPECT_TRUE(samePose(*lifted, script.at(1.5)));
    }
    // The thimble scene with the press script on another box of its own, and each loop value.
    auto scene = thimbleScene();
    ASSERT_EQ(scene.tracking.script, config::TrackingScript::kPressSlideEdge);
    config::SceneObject other = *scene.findObject(scene.tracking.target_object);
    other.name = "other_block";
    other.pose.position_m[0] += 0.05;
    scene.objects.push_back(other);
    scene.tracking.target_object = "other_block";
    const softhand::SceneSimulation sim(scene, {});
    std::vector<softhand::HandPoseInput> late;
    for (const bool loop : {false, true}) {
        scene.tracking.loop = loop;
        const softhand::PressSlideEdgeScript script(sim.trackedHand(), scene.hand, other, loop);
        const auto source = makeTrackingSource(scene, sim, participant);
        EXPECT_EQ(source->describe(), "scripted press_slide_edge on 'other_block'");
        std::string rejection;
        const double t = softhand::PressSlideEdgeScript::kPeriod + 1.0;
        const auto polled = source->poll(t, rejection);
        ASSERT_TRUE(polled.has_value()) << rejection;
        EXPECT_TRUE(samePose(*polled, script.at(t))) << "loop " << loop;
        late.push_back(*polled);
    }
    EXPECT_FALSE(samePose(late[0], late[1])) << "holding and looping gave the same pose";
}

TEST(HandsimTrackingSource, AReplaySceneReplaysItsFileAndHoldsOrLoopsAsTrackingLoopSays) {
    // Removed however the test ends.
    struct TemporaryFile {
        std::filesystem::path path;
        ~TemporaryFile() { std::filesystem::remove(path); }
    } const replay{std::filesystem::temp_directory_path() /
                   ("handsim_replay_" + std::to_string(::getpid()) + ".csv")};
    const auto& file = replay.path;
    std::ofstream(file) << "# t_s, wrist xyz, quaternion, 15 angles\n"
                        << replayRow(0.0, 0.0, 0.1) << replayRow(1.0, 0.02, 0.5);
    auto scene = thimbleScene();
    scene.tracking.source = config::TrackingSource::kReplay;
    scene.tracking.replay_file = file;
    const softhand::SceneSimulation sim(scene, {});
    auto participant = makeParticipant();
    for (const bool loop : {false, true}) {
        scene.tracking.loop = loop;
        const auto source = makeTrackingSource(scene, sim, participant);
        EXPECT_EQ(source->describe(),
                  "replay of " + file.string() + " (2 frames" + (loop ? ", looping)" : ")"));
        EXPECT_NEAR(source->initialPose().wrist.position_m.x(), 0.0, 1e-12);
        std::string rejection;
        const auto middle = source->poll(0.25, rejection);
        ASSERT_TRUE(middle.has_value());
        EXPECT_NEAR(middle->wrist.position_m.x(), 0.005, 1e-9);
        EXPECT_NEAR(middle->wrist.position_m.z(), 0.1, 1e-9);
        EXPECT_NEAR(middle->flexion_rad[7], 0.2, 1e-9);
        const auto later = source->poll(1.25, rejection);
        ASSERT_TRUE(later.has_value());
        EXPECT_NEAR(later->wrist.position_m.x(), loop ? 0.005 : 0.02, 1e-9)
            << (loop ? "looped to the start" : "held at the end");
        EXPECT_TRUE(rejection.empty()) << rejection;
    }
}

// What each source made of the same stream of HandPose samples.
struct Response {
    std::vector<double> wrist_x_m;
    std::vector<double> angle_rad;
};

class TopicSourceTest : public ::testing::Test {
  protected:
    TopicSourceTest()
        : scene_(topicScene()),
          sim_(scene_, {}),
          participant_(makeParticipant()),
          writer_(participant_.createWriter<idl::HandPosePubSubType>(scene_.tracking.topic,
                                                                     ipc::TopicKind::kStream)),
          rest_(sim_.trackedHand().buildPose()) {}

    static config::SceneConfig topicScene() {
        auto scene = thimbleScene();
        scene.tracking.source = config::TrackingSource::kTopic;
        // tracking.topic: a name of this process's own, so no other test's poses arrive.
        scene.tracking.topic = "tracking/test_" + std::to_string(::getpid());
        return scene;
    }

    // A tracker at 90 Hz: the hand at rest, then the wrist 10 mm along x and every flexion
    // angle 0.2 rad further, held. Each source polls every sample.
    std::vector<Response> run(
        const std::vector<std::optional<config::TrackingFilterConfig>>& filters) {
        std::vector<std::unique_ptr<TrackingSource>> sources;
        for (const auto& filter : filters) {
            sources.push_back(makeTrackingSource(scene_, sim_, participant_, filter));
        }
        std::vector<std::int64_t> stamps_ns;
        for (int i = 0; i < 90; ++i) {
            stamps_ns.push_back(1'000'000'000 + i * kTrackerPeriodNs);
        }
        return run(sources, stamps_ns, 10);
    }

    // Samples stamped `stamps_ns`, the step from sample `step_at` on, through each source.
    std::vector<Response> run(const std::vector<std::unique_ptr<TrackingSource>>& sources,
                              const std::vector<std::int64_t>& stamps_ns, std::size_t step_at) {
        const auto deadline = std::chrono::steady_clock::now() + 20s;
        while (writer_.matchedReaders() < static_cast<int>(sources.size()) &&
               std::chrono::steady_clock::now() < deadline) {
            std::this_thread::sleep_for(10ms);
        }
        EXPECT_EQ(writer_.matchedReaders(), static_cast<int>(sources.size()));
        std::vector<Response> responses(sources.size());
        for (std::size_t i = 0; i < stamps_ns.size(); ++i) {
            softhand::HandPoseInput pose = rest_;
            if (i >= step_at) {
                pose.wrist.position_m.x() += 0.01;
                for (double& angle : pose.flexion_rad) {
                    angle += 0.2;
                }
            }
            msgs::HandPose message = softhand::toMessage(pose);
            message.header.seq = static_cast<std::uint64_t>(i + 1);
            message.header.stamp_ns = stamps_ns[i];
            message.header.source_id.assign("tracking_source_test");
            message.confidence = 1.0;
            EXPECT_TRUE(writer_.write(msgs::toIdl(message)));
            for (std::size_t s = 0; s < sources.size(); ++s) {
                std::optional<softhand::HandPoseInput> polled;
                std::string rejection;
                const auto sample_deadline = std::chrono::steady_clock::now() + 5s;
                while (!polled && std::chrono::steady_clock::now() < sample_deadline) {
                    polled = sources[s]->poll(0.0, rejection);
                    if (!polled) {
                        std::this_thread::sleep_for(1ms);
                    }
                }
                EXPECT_TRUE(rejection.empty()) << rejection;
                if (!polled) {
                    ADD_FAILURE() << "source " << s << " received no sample " << i;
                    return responses;
                }
                responses[s].wrist_x_m.push_back(polled->wrist.position_m.x() -
                                                 rest_.wrist.position_m.x());
                responses[s].angle_rad.push_back(polled->flexion_rad[4] - rest_.flexion_rad[4]);
            }
        }
        return responses;
    }

    static constexpr std::int64_t kTrackerPeriodNs = 11'111'111;
    config::SceneConfig scene_;
    softhand::SceneSimulation sim_;
    ipc::DdsParticipant participant_;
    ipc::DdsWriter<idl::HandPose> writer_;
    softhand::HandPoseInput rest_;
};

TEST_F(TopicSourceTest, EachTrackingFilterKeyShapesTheStepResponse) {
    const auto shipped = config::loadSimConfig(kConfigDir + "/sim.yaml").tracking_filter;
    ASSERT_TRUE(shipped.has_value());
    ASSERT_TRUE(shipped->angle_beta_s_per_rad.has_value());
    auto slower = *shipped;
    slower.min_cutoff_hz = 0.5;
    auto faster_in_motion = *shipped;
    faster_in_motion.position_beta_s_per_m = 500.0;
    auto other_derivative = *shipped;
    other_derivative.derivative_cutoff_hz = 10.0;
    auto no_angles = *shipped;
    no_angles.angle_beta_s_per_rad.reset();
    auto angles_faster_in_motion = *shipped;
    angles_faster_in_motion.angle_beta_s_per_rad = 100.0;
    const auto responses = run({std::nullopt, shipped, slower, faster_in_motion, other_derivative,
                                no_angles, angles_faster_in_motion});
    ASSERT_EQ(responses.size(), 7U);
    for (const auto& response : responses) {
        ASSERT_EQ(response.wrist_x_m.size(), 90U);
    }
    const auto& raw = responses[0];
    const auto& filtered = responses[1];
    // Without tracking_filter the samples pass as they come.
    EXPECT_NEAR(raw.wrist_x_m[9], 0.0, 1e-12);
    EXPECT_NEAR(raw.wrist_x_m[10], 0.01, 1e-12);
    EXPECT_NEAR(raw.angle_rad[10], 0.2, 1e-12);
    // Through the shipped filter the step arrives over several samples and settles.
    EXPECT_GT(filtered.wrist_x_m[10], 0.0);
    EXPECT_LT(filtered.wrist_x_m[10], 0.009);
    EXPECT_GT(filtered.angle_rad[10], 0.0);
    EXPECT_LT(filtered.angle_rad[10], 0.18);
    EXPECT_NEAR(filtered.wrist_x_m[89], 0.01, 1e-4);
    EXPECT_NEAR(filtered.angle_rad[89], 0.2, 2e-3);
    // min_cutoff_hz: a lower cutoff lags more.
    EXPECT_LT(responses[2].wrist_x_m[12], filtered.wrist_x_m[12]);
    // position_beta_s_per_m: a higher beta opens the cutoff with the speed, lagging less;
    // the angles keep theirs.
    EXPECT_GT(responses[3].wrist_x_m[12], filtered.wrist_x_m[12]);
    EXPECT_NEAR(responses[3].angle_rad[12], filtered.angle_rad[12], 1e-12);
    // derivative_cutoff_hz: the speed that opens the cutoff is smoothed differently.
    EXPECT_GT(std::abs(responses[4].wrist_x_m[12] - filtered.wrist_x_m[12]), 1e-6);
    // Without angle_beta_s_per_rad the angles pass unfiltered; the wrist is filtered as before.
    EXPECT_NEAR(responses[5].angle_rad[10], 0.2, 1e-12);
    EXPECT_NEAR(responses[5].wrist_x_m[12], filtered.wrist_x_m[12], 1e-12);
    // angle_beta_s_per_rad's value: a higher beta lets the angles lag less, the wrist as before.
    EXPECT_GT(responses[6].angle_rad[12], filtered.angle_rad[12] + 1e-4);
    EXPECT_NEAR(responses[6].wrist_x_m[12], filtered.wrist_x_m[12], 1e-12);
}

// tracking.timeout_ms (default 100): a gap in the tracker's samples longer than it restarts
// the filter at the next sample (it passes as it comes); a shorter one is filtered across.
TEST_F(TopicSourceTest, AGapLongerThanTheTrackingTimeoutRestartsTheFilter) {
    const auto filter = config::loadSimConfig(kConfigDir + "/sim.yaml").tracking_filter;
    ASSERT_TRUE(filter.has_value());
    ASSERT_EQ(scene_.tracking.timeout_ms, 100);
    auto longer = scene_;
    longer.tracking.timeout_ms = 300;
    std::vector<std::unique_ptr<TrackingSource>> sources;
    sources.push_back(makeTrackingSource(scene_, sim_, participant_, filter));
    sources.push_back(makeTrackingSource(longer, sim_, participant_, filter));
    std::vector<std::int64_t> stamps_ns;
    for (int i = 0; i < 5; ++i) {
        stamps_ns.push_back(1'000'000'000 + i * kTrackerPeriodNs);
    }
    stamps_ns.push_back(stamps_ns.back() + 150'000'000);  // 150 ms without a sample
    const auto responses = run(sources, stamps_ns, 5);
    ASSERT_EQ(responses.size(), 2U);
    ASSERT_EQ(responses[0].wrist_x_m.size(), 6U);
    ASSERT_EQ(responses[1].wrist_x_m.size(), 6U);
    EXPECT_NEAR(responses[0].wrist_x_m[5], 0.01, 1e-12) << "restarted: the sample as it came";
    EXPECT_NEAR(responses[0].angle_rad[5], 0.2, 1e-12);
    EXPECT_LT(responses[1].wrist_x_m[5], 0.009) << "filtered across a gap within the timeout";
    EXPECT_GT(responses[1].wrist_x_m[5], 0.0);
}

}  // namespace
}  // namespace haptic::handsim
