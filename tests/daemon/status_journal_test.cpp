// The journal lines hapticd's non-RT thread logs from consecutive status snapshots.

#include "haptic/daemon/status_journal.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace haptic::daemon {
namespace {

using Level = JournalLine::Level;

msgs::Fault fault(std::uint32_t code, const char* device, const char* message) {
    msgs::Fault f;
    f.code = code;
    f.device_id.assign(device);
    f.message.assign(message);
    return f;
}

TEST(StatusJournal, TheFirstSnapshotGivesTheStateAndEveryFaultItHolds) {
    msgs::HapticStatus status;
    status.state = msgs::DaemonState::kIdle;
    const auto lines = statusChanges(nullptr, status);
    ASSERT_EQ(lines.size(), 1U);
    EXPECT_EQ(lines[0].text, "state IDLE");
    EXPECT_EQ(lines[0].level, Level::kInfo);
}

TEST(StatusJournal, ALatchedFaultIsOneErrorLineWithCodeDeviceAndMessageThenNothingMore) {
    msgs::HapticStatus rendering;
    rendering.state = msgs::DaemonState::kRendering;
    msgs::HapticStatus faulted = rendering;
    faulted.state = msgs::DaemonState::kFault;
    faulted.faults.push_back(fault(105, "exo", "device measures 2.00 N against 10.00 N"));
    const auto lines = statusChanges(&rendering, faulted);
    ASSERT_EQ(lines.size(), 2U);
    EXPECT_EQ(lines[0].level, Level::kError);
    EXPECT_EQ(lines[0].text, "fault [105] exo: device measures 2.00 N against 10.00 N");
    EXPECT_EQ(lines[1].level, Level::kWarning);
    EXPECT_EQ(lines[1].text, "state RENDERING -> FAULT");
    // The same snapshot again, or the same fault: nothing new to say.
    EXPECT_TRUE(statusChanges(&faulted, faulted).empty());
    // A second fault beside it: only that one.
    msgs::HapticStatus two = faulted;
    two.faults.push_back(fault(110, "", "loop stalled 52.2 ms (limit 50.0 ms)"));
    const auto second = statusChanges(&faulted, two);
    ASSERT_EQ(second.size(), 1U);
    EXPECT_EQ(second[0].text, "fault [110] loop stalled 52.2 ms (limit 50.0 ms)");
}

TEST(StatusJournal, AClearSaysWhichFaultsWentAndTheNewState) {
    msgs::HapticStatus faulted;
    faulted.state = msgs::DaemonState::kFault;
    faulted.faults.push_back(fault(100, "thimble", "heartbeat lost"));
    msgs::HapticStatus idle;
    idle.state = msgs::DaemonState::kIdle;
    const auto lines = statusChanges(&faulted, idle);
    ASSERT_EQ(lines.size(), 2U);
    EXPECT_EQ(lines[0].level, Level::kInfo);
    EXPECT_EQ(lines[0].text, "fault cleared: [100] thimble: heartbeat lost");
    EXPECT_EQ(lines[1].text, "state FAULT -> IDLE");
}

}  // namespace
}  // namespace haptic::daemon
