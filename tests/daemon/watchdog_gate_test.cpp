#include "haptic/daemon/watchdog_gate.hpp"

#include <gtest/gtest.h>

namespace haptic::daemon {
namespace {

constexpr std::int64_t kMs = 1'000'000;

TEST(WatchdogGate, PingsEveryIntervalWhileTheLoopTicks) {
    WatchdogGate gate(500 * kMs, 1000.0);
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
    WatchdogGate gate(500 * kMs, 1000.0);
    EXPECT_TRUE(gate.pingDue(0, 42));
    EXPECT_FALSE(gate.pingDue(500 * kMs, 42)) << "the RT loop did not tick";
    EXPECT_FALSE(gate.pingDue(1000 * kMs, 42));
    EXPECT_TRUE(gate.pingDue(1500 * kMs, 42 + 500)) << "ticking again resumes the pings";
}

TEST(WatchdogGate, NoPingBeforeTheFirstTick) {
    WatchdogGate gate(500 * kMs, 1000.0);
    EXPECT_FALSE(gate.pingDue(0, 0));
    EXPECT_FALSE(gate.pingDue(500 * kMs, 0));
    EXPECT_TRUE(gate.pingDue(1000 * kMs, 300));
}

TEST(WatchdogGate, ALoopFarBelowItsRateGetsNoPings) {
    WatchdogGate gate(500 * kMs, 1000.0);
    EXPECT_TRUE(gate.pingDue(0, 1));
    EXPECT_FALSE(gate.pingDue(500 * kMs, 1 + 100)) << "100 Hz where 1 kHz is due";
    EXPECT_FALSE(gate.pingDue(1000 * kMs, 101 + 249)) << "just under half the rate";
    EXPECT_TRUE(gate.pingDue(1500 * kMs, 350 + 250)) << "half the rate passes";
}

}  // namespace
}  // namespace haptic::daemon
