// `hapticctl record` against a real haptic/telemetry writer that leaves out 50 ticks, as a
// loss between hapticd and the recorder would (a dropped queue, DDS overwriting a sample): the
// recording keeps every row that came, and hapticctl reports the 50 it never saw (#19).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <thread>

#include "HapticTelemetryPubSubTypes.h"
#include "child_process.hpp"
#include "haptic/ipc/dds_participant.hpp"
#include "haptic/ipc/topics.hpp"
#include "haptic/msgs/conversions.hpp"

namespace haptic::testing {
namespace {

using ::testing::HasSubstr;
using namespace std::chrono_literals;

// A domain no other test uses (the others: 1-229).
constexpr int kDomain = 231;

TEST(RecordLoss, ARecordingReportsTheTicksItNeverReceived) {
    ipc::DdsSettings settings;
    settings.domain_id = kDomain;
    settings.profiles_file = std::string(HAPTIC_CONFIG_DIR) + "/dds_profiles.xml";
    ipc::DdsParticipant hapticd_side(settings, "telemetry-writer");
    auto writer = hapticd_side.createWriter<idl::HapticTelemetryPubSubType>(
        ipc::kTelemetryTopic, ipc::TopicKind::kStream);

    ChildProcess record({HAPTICCTL_PATH, "--dds-domain", std::to_string(kDomain), "--timeout", "20",
                         "record", "-", "--duration", "2"},
                        "hapticctl-record");
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    while (writer.matchedReaders() == 0 && std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(20ms);
    }
    ASSERT_GT(writer.matchedReaders(), 0) << record.stderrText();

    // Ticks 0..199 of device 0 in batches of 10, as hapticd publishes them, without 100..149.
    msgs::HapticTelemetry batch;
    std::uint64_t sequence = 0;
    for (std::uint64_t first = 0; first < 200; first += 10) {
        batch = msgs::HapticTelemetry{};
        batch.header.seq = ++sequence;
        for (std::uint64_t tick = first; tick < first + 10; ++tick) {
            if (tick >= 100 && tick < 150) {
                continue;
            }
            msgs::TelemetrySample sample;
            sample.tick = tick;
            sample.stamp_ns = static_cast<std::int64_t>(tick) * 1'000'000;
            ASSERT_TRUE(batch.samples.push_back(sample));
        }
        if (batch.samples.size() > 0) {
            ASSERT_TRUE(writer.write(msgs::toIdl(batch)));
        }
        std::this_thread::sleep_for(10ms);  // the 1 kHz daemon's pace, 10 ticks a batch
    }

    ASSERT_EQ(record.waitFor(15s), std::optional<int>(0)) << record.stderrText();
    const std::string csv = record.stdoutText();
    const auto rows = std::count(csv.begin(), csv.end(), '\n');
    // 150 rows of samples, the CSV header and the provenance lines.
    EXPECT_GE(rows, 150 + 1);
    EXPECT_THAT(record.stderrText(), HasSubstr("150 rows written to stdout"));
    EXPECT_THAT(record.stderrText(), HasSubstr("50 samples missing"));
}

}  // namespace
}  // namespace haptic::testing
