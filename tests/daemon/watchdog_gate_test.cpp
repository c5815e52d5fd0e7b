#include "haptic/daemon/watchdog_gate.hpp"

#include <gtest/gtest.h>

namespace haptic::daemon {
namespace {

constexpr std::int64_t kMs = 1'000'000;

TEST(WatchdogGate, PingsEveryIntervalWhileTheLoopTicks) {
    WatchdogGate gate(500 * kMs);
    std::uint64_t ticks = 10;
    EXPECT_TRUE(gate.pingDue(0, ticks));
    ticks += 100;
    EXPECT_FALSE(gate.pingDue(100 * kMs, ticks)) << "not before the interval";
    ticks += 400;
    EXPECT_TRUE(gate.pingDue(500 * kMs, ticks));
    ticks += 500;
    EXPECT_TRUE(gate.pingDue(1000 * kMs, ticks));
}

TEST(WatchdogGate, AStalledLoopGetsNoPingsUntilItTicksAgain) {
    WatchdogGate gate(500 * kMs);
    EXPECT_TRUE(gate.pingDue(0, 42));
    EXPECT_FALSE(gate.pingDue(500 * kMs, 42)) << "the RT loop did not tick";
    EXPECT_FALSE(gate.pingDue(1000 * kMs, 42));
    EXPECT_TRUE(gate.pingDue(1500 * kMs, 43)) << "ticking again resumes the pings";
}

TEST(WatchdogGate, NoPingBeforeTheFirstTick) {
    WatchdogGate gate(500 * kMs);
    EXPECT_FALSE(gate.pingDue(0, 0));
    EXPECT_FALSE(gate.pingDue(500 * kMs, 0));
    EXPECT_TRUE(gate.pingDue(1000 * kMs, 1));
}

}  // namespace
}  // namespace haptic::daemon
