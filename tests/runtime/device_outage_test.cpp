// A device lost while RENDERING, not through its heartbeat (which would latch a fault) but its
// state: the emulated device keeps its heartbeat and stops its state frames (hapticemu's
// `state stop`). A short gap fades the force out and back in by itself; a device whose state
// stays stale longer than its can.heartbeat_timeout_ms (50 ms shipped) is lost, and its force
// returns only after an operator's `enable`, however long the outage (ARCHITECTURE.md: force
// never comes back by itself after a long outage).

#include <gtest/gtest.h>

#include <cmath>

#include "haptic/runtime/thimble_channel.hpp"
#include "runtime_rig.hpp"

namespace haptic::testing {
namespace {

// Ticks with the sim's contact offered at 100 Hz.
void renderTicks(RuntimeRig& rig, int count) {
    for (int i = 0; i < count; ++i) {
        if (rig.tick_count % 10 == 0) {
            rig.offerContact();
        }
        rig.tick();
    }
}

TEST(DeviceOutage, AShortStateGapFadesTheForceOutAndBackByItself) {
    RuntimeRig rig;
    renderWithContact(rig);
    const double before_n = std::abs(rig.exoForce());
    ASSERT_GT(before_n, 1.0);
    rig.emulatorFault(kExo, "state stop");
    // Stale after 10 ms (can.state_timeout_ms), fading over safety.fade_out_ms (100 ms); not
    // lost before 50 ms.
    renderTicks(rig, 30);
    EXPECT_LT(std::abs(rig.exoForce()), 0.9 * before_n) << "a stale device fades out";
    EXPECT_FALSE(rig.core.awaitingEnable(kExo));
    rig.emulatorFault(kExo, "state start");
    renderTicks(rig, 300);
    EXPECT_FALSE(rig.core.awaitingEnable(kExo));
    EXPECT_GT(std::abs(rig.exoForce()), 1.0) << "back by itself after a short gap";
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kRendering);
}

TEST(DeviceOutage, ADeviceLostLongerThanItsHeartbeatTimeoutWaitsForAnOperatorsEnable) {
    RuntimeRig rig;
    renderWithContact(rig);
    ASSERT_GT(std::abs(rig.exoForce()), 1.0);
    ASSERT_GT(distance(rig.thimbleTargets(), retract(rig)), 0.05) << "the thimble presses";
    rig.emulatorFault(kExo, "state stop");
    rig.emulatorFault(kThimble, "state stop");
    renderTicks(rig, 70);
    EXPECT_TRUE(rig.core.awaitingEnable(kExo));
    EXPECT_TRUE(rig.core.awaitingEnable(kThimble));
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kRendering) << "no fault: the heartbeat lives";
    // The states return, minutes or milliseconds later: nothing comes back by itself.
    rig.emulatorFault(kExo, "state start");
    rig.emulatorFault(kThimble, "state start");
    for (int i = 0; i < 2000; ++i) {
        renderTicks(rig, 1);
        ASSERT_EQ(rig.exoForce(), 0.0) << "tick " << i;
        ASSERT_EQ(rig.core.deviceReport(kExo).run_state, msgs::DeviceRunState::kSafe);
    }
    EXPECT_LT(distance(rig.thimbleTargets(), retract(rig)), 1e-12) << "the thimble retracted";
    EXPECT_TRUE(rig.core.awaitingEnable(kExo));
    EXPECT_TRUE(rig.core.awaitingEnable(kThimble));
    // The operator's enable re-arms both; force fades back in.
    ASSERT_TRUE(rig.command(msgs::CommandKind::kEnable));
    renderTicks(rig, 300);
    EXPECT_FALSE(rig.core.awaitingEnable(kExo));
    EXPECT_GT(std::abs(rig.exoForce()), 1.0);
    EXPECT_GT(distance(rig.thimbleTargets(), retract(rig)), 0.05);
}

// An enable while a device is not heard from (switched off, unplugged) does not arm it for
// later: when it appears, it waits for an enable of its own.
TEST(DeviceOutage, ADeviceFirstHeardAfterTheEnableWaitsForAnotherEnable) {
    RuntimeRig rig;
    rig.emulatorFault(kThimble, "state stop");
    rig.offerContact();
    rig.ticks(20);
    ASSERT_TRUE(rig.command(msgs::CommandKind::kEnable));
    renderTicks(rig, 100);
    EXPECT_TRUE(rig.core.awaitingEnable(kThimble));
    EXPECT_FALSE(rig.core.awaitingEnable(kExo));
    rig.emulatorFault(kThimble, "state start");
    renderTicks(rig, 500);
    EXPECT_LT(distance(rig.thimbleTargets(), retract(rig)), 1e-12) << "still retracted";
    EXPECT_GT(std::abs(rig.exoForce()), 1.0) << "the device heard all along renders";
    ASSERT_TRUE(rig.command(msgs::CommandKind::kEnable));
    renderTicks(rig, 300);
    EXPECT_GT(distance(rig.thimbleTargets(), retract(rig)), 0.05);
}

}  // namespace
}  // namespace haptic::testing
