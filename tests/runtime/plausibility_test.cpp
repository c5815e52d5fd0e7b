// Device feedback that contradicts the command, or a device that restarted, raises a fault of
// its own that latches and holds the device safe until an operator clears it and enables
// again (#18 item 4). The emulated devices inject the misbehaviour (hapticemu's fault
// commands `reboot` and `stuck-enable on`).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "haptic/protocol/exoskeleton_protocol.hpp"
#include "haptic/runtime/contradiction_timer.hpp"
#include "haptic/runtime/device_channel.hpp"
#include "haptic/runtime/exoskeleton_channel.hpp"
#include "runtime_rig.hpp"

namespace haptic::testing {
namespace {

using ::testing::HasSubstr;

void renderWithForce(RuntimeRig& rig) {
    rig.offerContact();
    rig.ticks(20);
    ASSERT_TRUE(rig.command(msgs::CommandKind::kEnable));
    for (int i = 0; i < 300; ++i) {
        if (i % 10 == 0) {
            rig.offerContact();
        }
        rig.tick();
    }
    ASSERT_EQ(rig.core.state(), msgs::DaemonState::kRendering);
    ASSERT_GT(std::abs(rig.exoForce()), 1.0);
}

// Keeps the sim input fresh for `n` ticks.
void renderTicks(RuntimeRig& rig, int n) {
    for (int i = 0; i < n; ++i) {
        if (i % 10 == 0) {
            rig.offerContact();
        }
        rig.tick();
    }
}

// Keeps the sim input fresh for `n` ticks; returns the largest exoskeleton force commanded.
// (The rig's finger is pushed out of the contact within a few hundred ticks, so the force at
// one tick depends on when rendering began.)
double peakExoForce(RuntimeRig& rig, int n) {
    double peak_n = 0.0;
    for (int i = 0; i < n; ++i) {
        if (i % 10 == 0) {
            rig.offerContact();
        }
        rig.tick();
        peak_n = std::max(peak_n, std::abs(rig.exoForce()));
    }
    return peak_n;
}

// Keeps the sim input fresh until no device shows the cause of a fault any more (`clear` would
// be accepted); returns the ticks that took, or -1 after `limit`.
int renderUntilNothingStands(RuntimeRig& rig, int limit) {
    for (int ticks = 0; ticks < limit; ++ticks) {
        if (rig.core.deviceReport(kExo).standing_fault == 0 &&
            rig.core.deviceReport(kThimble).standing_fault == 0) {
            return ticks;
        }
        if (ticks % 10 == 0) {
            rig.offerContact();
        }
        rig.tick();
    }
    return -1;
}

// The message of the one fault the daemon latched, after checking that it is in FAULT for it
// and who raised it.
std::string onlyFault(RuntimeRig& rig, std::uint32_t code, std::string_view device) {
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kFault);
    EXPECT_EQ(rig.core.stateMachine().faultCount(), 1U);
    if (rig.core.stateMachine().faultCount() == 0) {
        return "";
    }
    const auto& fault = rig.core.stateMachine().fault(0);
    EXPECT_EQ(fault.code, code);
    EXPECT_EQ(fault.device_id.view(), device);
    return std::string(fault.message.view());
}

// The operator's way back: clear lands in IDLE (never straight in RENDERING), and only a new
// enable renders force again.
void clearAndRenderAgain(RuntimeRig& rig) {
    ASSERT_TRUE(rig.command(msgs::CommandKind::kClearFault)) << rig.reply.message.view();
    renderTicks(rig, 5);
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kIdle);
    ASSERT_TRUE(rig.command(msgs::CommandKind::kEnable));
    const double peak_n = peakExoForce(rig, 300);
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kRendering);
    EXPECT_GT(peak_n, 1.0) << "the force came back";
}

constexpr std::int64_t kTickNs = 1'000'000;
constexpr std::int64_t kTimeoutNs = 50 * kTickNs;

// Feeds `ticks` 1 ms ticks, contradicting except on every `plausible_every`-th (0: never
// plausible); returns the tick of the first report, or -1.
int firstReport(runtime::ContradictionTimer& timer, int ticks, int plausible_every,
                std::int64_t& lasted_ns) {
    for (int i = 0; i < ticks; ++i) {
        const bool plausible = plausible_every > 0 && i % plausible_every == plausible_every - 1;
        lasted_ns = timer.update(!plausible, i * kTickNs, kTimeoutNs);
        if (lasted_ns > 0) {
            return i;
        }
    }
    return -1;
}

// A contradiction on every frame is reported once it has lasted the timeout, as before.
TEST(ContradictionTimer, AContradictionOnEveryFrameIsReportedAfterTheTimeout) {
    runtime::ContradictionTimer timer;
    std::int64_t lasted_ns = 0;
    EXPECT_EQ(firstReport(timer, 1000, 0, lasted_ns), 51);
    EXPECT_EQ(lasted_ns, 51 * kTickNs);
}

// The first report of a contradiction on all ticks but every `plausible_every`-th comes between
// ticks `first` and `last`, with the time since its first frame.
void expectFirstReportBetween(int plausible_every, int first, int last) {
    runtime::ContradictionTimer timer;
    std::int64_t lasted_ns = 0;
    const int tick = firstReport(timer, 1000, plausible_every, lasted_ns);
    EXPECT_GE(tick, first);
    EXPECT_LE(tick, last);
    EXPECT_EQ(lasted_ns, tick * kTickNs);
}

// One plausible frame in four (a late echo, one frame another host did not send) used to
// restart the clock, so the contradiction was never reported. On 3 frames of 4 the balance
// grows by half a tick a tick: reported after twice the timeout.
TEST(ContradictionTimer, OnePlausibleFrameDoesNotHideAContradictionOnMostFrames) {
    expectFirstReportBetween(4, 100, 104);
}

// Two contradicting ticks in three (p = 2/3): reported after about T / (2p - 1) = 3 T. The
// balance returns to zero after every plausible tick here, so ending the contradiction at zero
// (rather than below it) would restart it for ever and never report it.
TEST(ContradictionTimer, TwoContradictingTicksInThreeAreReportedAfterThreeTimeouts) {
    expectFirstReportBetween(3, 148, 154);
}

// A contradiction on at most half the frames is never reported, however long it goes on
// (a healthy device's transients), and a run of plausible frames as long as the
// contradicting ones ends it.
TEST(ContradictionTimer, AContradictionOnHalfTheFramesOrFewerIsNotReported) {
    runtime::ContradictionTimer timer;
    std::int64_t lasted_ns = 0;
    EXPECT_EQ(firstReport(timer, 100'000, 2, lasted_ns), -1);
    runtime::ContradictionTimer ends;
    std::int64_t now_ns = 0;
    for (int i = 0; i < 40; ++i, now_ns += kTickNs) {
        EXPECT_EQ(ends.update(true, now_ns, kTimeoutNs), 0);
    }
    for (int i = 0; i < 40 && ends.contradicting(); ++i, now_ns += kTickNs) {
        EXPECT_EQ(ends.update(false, now_ns, kTimeoutNs), 0);
    }
    EXPECT_FALSE(ends.contradicting());
    // A new contradiction starts from nothing: the full timeout again.
    for (int i = 0; i < 50; ++i, now_ns += kTickNs) {
        EXPECT_EQ(ends.update(true, now_ns, kTimeoutNs), 0) << i;
    }
}

// A tick that cannot be judged (stale link, the device's own fault) drops what had built up.
TEST(ContradictionTimer, AnUnjudgedTickForgetsTheContradiction) {
    runtime::ContradictionTimer timer;
    for (int i = 0; i < 45; ++i) {
        EXPECT_EQ(timer.update(true, i * kTickNs, kTimeoutNs), 0);
    }
    timer.reset();
    EXPECT_FALSE(timer.contradicting());
    for (int i = 100; i < 150; ++i) {
        EXPECT_EQ(timer.update(true, i * kTickNs, kTimeoutNs), 0) << i;
    }
    EXPECT_GT(timer.update(true, 151 * kTickNs, kTimeoutNs), 0);
}

TEST(Plausibility, ADeviceThatRebootedLatchesAFaultUntilClearAndEnable) {
    RuntimeRig rig;
    renderWithForce(rig);
    rig.emulatorFault(kThimble, "reboot");
    renderTicks(rig, 30);  // the next heartbeat (10 ms period) shows the uptime gone back
    EXPECT_THAT(onlyFault(rig, runtime::kFaultDeviceRebooted, "thimble"),
                HasSubstr("device rebooted (uptime "));
    EXPECT_EQ(rig.exoForce(), 0.0) << "FAULT holds every device safe";

    // Latched though the device now runs normally; clear lands in IDLE, enable renders again.
    renderTicks(rig, 100);
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kFault);
    EXPECT_EQ(rig.core.stateMachine().faultCount(), 1U) << "raised once";
    clearAndRenderAgain(rig);
}

// A drive that ignores the disable keeps pushing the finger: hapticd cannot stop it over the
// bus, but it must say so, latch FAULT and keep commanding the safe state.
TEST(Plausibility, AnExoskeletonStillEnabledAfterADisableRaisesItsOwnFault) {
    RuntimeRig rig;
    renderWithForce(rig);
    rig.emulatorFault(kExo, "stuck-enable on");
    ASSERT_TRUE(rig.command(msgs::CommandKind::kDisable));
    renderTicks(rig, 40);  // can.heartbeat_timeout_ms is 50: not yet
    EXPECT_EQ(rig.core.stateMachine().faultCount(), 0U);
    renderTicks(rig, 30);
    const std::string message = onlyFault(rig, runtime::kFaultImplausibleFeedback, "exo");
    EXPECT_THAT(message, HasSubstr("device reports enabled 5"));  // 50-some ms after disable
    EXPECT_THAT(message, HasSubstr("ms after disable; held safe"));
    EXPECT_EQ(rig.core.deviceReport(kExo).run_state, msgs::DeviceRunState::kFault);
    EXPECT_EQ(rig.exoForce(), 0.0);

    // Repaired (the fault command off): once the contradiction has drained (within the
    // heartbeat timeout), clear and enable bring the rendering back.
    rig.emulatorFault(kExo, "stuck-enable off");
    EXPECT_GE(renderUntilNothingStands(rig, 200), 0) << "the repair never ended the fault";
    clearAndRenderAgain(rig);
}

// After a repair the fault stands until the contradiction has drained (its balance, capped a
// tick above the heartbeat timeout, falls below zero: about one timeout of plausible ticks),
// and then nothing of it is left: an operator who clears and enables at once is judged from
// nothing, though the enable's own round trip contradicts for a few ticks (the drive's
// frames arrive 3 ms late here, as through a USB adapter). When `clear` was accepted on the
// repair's first plausible tick, that round trip was added to the balance the repaired
// fault had left and raised 105 again ("device reports disabled 205 ms after enable").
TEST(Plausibility, AfterARepairTheFaultStandsUntilItsContradictionHasDrainedThenClearsForGood) {
    RuntimeRig rig;
    renderWithForce(rig);
    rig.emulatorFault(kExo, "stuck-enable on");
    ASSERT_TRUE(rig.command(msgs::CommandKind::kDisable));
    renderTicks(rig, 200);  // reported after 50-some ms, then standing at its cap
    onlyFault(rig, runtime::kFaultImplausibleFeedback, "exo");

    rig.emulatorFault(kExo, "stuck-enable off");
    rig.emulatorFault(kExo, "delay 3");
    renderTicks(rig, 10);
    EXPECT_FALSE(rig.command(msgs::CommandKind::kClearFault)) << "cleared while draining";
    EXPECT_THAT(std::string(rig.reply.message.view()), HasSubstr("fault 105"));
    const int drained = renderUntilNothingStands(rig, 200);
    EXPECT_GE(drained, 30) << "the balance drains a tick per tick from the timeout";
    EXPECT_LE(drained, 60);
    ASSERT_TRUE(rig.command(msgs::CommandKind::kClearFault)) << rig.reply.message.view();
    ASSERT_TRUE(rig.command(msgs::CommandKind::kEnable)) << rig.reply.message.view();
    renderTicks(rig, 20);  // the round trip, judged
    rig.emulatorFault(kExo, "delay 0");
    const double peak_n = peakExoForce(rig, 300);
    if (rig.core.stateMachine().faultCount() > 0) {
        ADD_FAILURE() << "raised again: " << rig.core.stateMachine().fault(0).message.view();
    }
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kRendering);
    EXPECT_GT(peak_n, 1.0) << "the force came back";
}

// An intermittent contradiction (the echo another host's on 3 frames of 4) is reported only
// on its contradicting ticks, so its report drops on every plausible one; `clear` is refused
// throughout all the same (tried on every tick), the daemon stays in FAULT with the drive at
// 0 N, and only once the cause has gone and its contradiction drained does `clear` succeed.
TEST(Plausibility, AnIntermittentContradictionCannotBeClearedBetweenItsFrames) {
    RuntimeRig rig;
    renderWithForce(rig);
    int ticks = 0;
    const auto pattern = [&] {
        if (ticks % 10 == 0) {
            rig.offerContact();
        }
        rig.emulatorFault(kExo, ticks % 4 == 3 ? "echo-offset 0" : "echo-offset 8");
        rig.tick();
        ++ticks;
    };
    while (rig.core.state() == msgs::DaemonState::kRendering && ticks < 400) {
        pattern();
    }
    onlyFault(rig, runtime::kFaultImplausibleFeedback, "exo");
    int refused = 0;
    for (int i = 0; i < 300; ++i) {
        pattern();
        if (rig.command(msgs::CommandKind::kClearFault)) {
            ADD_FAILURE() << "cleared " << i << " ticks into the intermittent cause";
            break;
        }
        ++refused;
        ASSERT_EQ(rig.core.state(), msgs::DaemonState::kFault);
        ASSERT_EQ(rig.exoForce(), 0.0);
    }
    EXPECT_EQ(refused, 300);
    rig.emulatorFault(kExo, "echo-offset 0");
    EXPECT_GE(renderUntilNothingStands(rig, 200), 0) << "the cause gone, the fault never ended";
    clearAndRenderAgain(rig);
}

// A drive that delivers half its setpoint (and measures it): the force it reports against the
// commanded force through the actuator's 5 ms lag, beyond actuator.force_tolerance_n + 20 %.
TEST(Plausibility, AForceThatDoesNotFollowTheCommandRaisesItsOwnFault) {
    RuntimeRig rig;
    renderWithForce(rig);
    renderTicks(rig, 500);
    EXPECT_EQ(rig.core.stateMachine().faultCount(), 0U) << "a healthy drive follows";
    rig.emulatorFault(kExo, "force-percent 50");
    renderTicks(rig, 200);
    const std::string message = onlyFault(rig, runtime::kFaultImplausibleFeedback, "exo");
    EXPECT_THAT(message, HasSubstr("device measures "));
    EXPECT_THAT(message, HasSubstr(" N commanded for 5"));
    EXPECT_EQ(rig.exoForce(), 0.0);
}

// actuator.force_tolerance_n is what decides: 50 N of tolerance accepts the half-strength
// drive above.
TEST(Plausibility, TheForceToleranceKeyDecidesWhatIsImplausible) {
    RuntimeRig rig([](std::vector<config::DeviceConfig>& devices) {
        std::get<config::ExoskeletonConfig>(devices[kExo].params).actuator.force_tolerance_n = 50.0;
    });
    renderWithForce(rig);
    rig.emulatorFault(kExo, "force-percent 50");
    renderTicks(rig, 200);
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kRendering);
    EXPECT_EQ(rig.core.stateMachine().faultCount(), 0U);
}

// actuator.lag_time_constant_s is the lag hapticd expects the drive's force to follow its
// command with. A drive as shipped (5 ms) under a file that says 100 ms: while the force ramps
// up (the 500 N/s slew limit), what it measures runs ahead of what hapticd expects by far more
// than the tolerance, and it is judged implausible; the same file with a drive of its own
// 100 ms is plausible.
TEST(Plausibility, TheActuatorLagKeyIsTheLagTheForceIsJudgedBy) {
    const auto slow = [](std::vector<config::DeviceConfig>& devices) {
        std::get<config::ExoskeletonConfig>(devices[kExo].params).actuator.lag_time_constant_s =
            0.1;
    };
    {
        RuntimeRig rig(slow);  // hapticd and the drive agree
        renderWithForce(rig);
        renderTicks(rig, 300);
        EXPECT_EQ(rig.core.stateMachine().faultCount(), 0U);
    }
    RuntimeRig rig(slow);
    const auto shipped_drive =
        config::loadDeviceConfig(std::string(HAPTIC_CONFIG_DIR) + "/devices/exoskeleton.yaml");
    rig.emulators[kExo] = emu::makeEmulator(shipped_drive, rig.target, emu::EmulatorOptions{});
    rig.offerContact();
    rig.ticks(20);
    ASSERT_TRUE(rig.command(msgs::CommandKind::kEnable));
    renderTicks(rig, 400);
    const std::string message = onlyFault(rig, runtime::kFaultImplausibleFeedback, "exo");
    EXPECT_THAT(message, HasSubstr("device measures "));
}

// servos.lag_time_constant_s likewise for the thimble: servos as shipped (30 ms) under a file
// that says 300 ms leave the angles hapticd expects during the retract's large move.
TEST(Plausibility, TheServoLagKeyIsTheLagTheAnglesAreJudgedBy) {
    const auto slow = [](std::vector<config::DeviceConfig>& devices) {
        std::get<config::ThimbleConfig>(devices[kThimble].params).servos.lag_time_constant_s = 0.3;
    };
    const auto renderAndRetract = [](RuntimeRig& rig) {
        rig.offerContact();
        rig.ticks(20);
        ASSERT_TRUE(rig.command(msgs::CommandKind::kEnable));
        renderTicks(rig, 800);
        // Every servo moves now (refused if the rendering already faulted).
        (void)rig.command(msgs::CommandKind::kDisable);
        renderTicks(rig, 800);
    };
    {
        RuntimeRig rig(slow);  // hapticd and the servos agree
        renderAndRetract(rig);
        EXPECT_EQ(rig.core.stateMachine().faultCount(), 0U);
        EXPECT_EQ(rig.core.state(), msgs::DaemonState::kIdle);
    }
    RuntimeRig rig(slow);
    const auto shipped_servos =
        config::loadDeviceConfig(std::string(HAPTIC_CONFIG_DIR) + "/devices/thimble.yaml");
    rig.emulators[kThimble] = emu::makeEmulator(shipped_servos, rig.target, emu::EmulatorOptions{});
    renderAndRetract(rig);
    EXPECT_THAT(onlyFault(rig, runtime::kFaultImplausibleFeedback, "thimble"),
                HasSubstr(" deg expected for "));
}

// A device that falls silent is judged by the link monitor, not on its last state.
TEST(Plausibility, OnlyAFreshContradictionCountsNotAStaleState) {
    RuntimeRig rig;
    renderWithForce(rig);
    // Bus-off silences the device: its last state still says enabled while hapticd commands
    // the safe state, but that is the bus-off fault, not an implausible device.
    rig.emulatorFault(kExo, "busoff");
    renderTicks(rig, 200);
    ASSERT_EQ(rig.core.state(), msgs::DaemonState::kFault);
    for (std::size_t i = 0; i < rig.core.stateMachine().faultCount(); ++i) {
        EXPECT_NE(rig.core.stateMachine().fault(i).code, runtime::kFaultImplausibleFeedback)
            << rig.core.stateMachine().fault(i).message.view();
    }
}

// A thimble servo that stops following its target (hapticemu's `servo-stuck 2`): its measured
// angle leaves the one the servo's lag and rate limit predict by more than
// servos.angle_tolerance_deg (5) for longer than can.heartbeat_timeout_ms; a healthy thimble
// rendering and retracting never does.
TEST(Plausibility, AThimbleServoThatDoesNotFollowItsTargetRaisesItsOwnFault) {
    RuntimeRig rig;
    renderWithForce(rig);
    renderTicks(rig, 500);
    ASSERT_TRUE(rig.command(msgs::CommandKind::kDisable));  // retract: a large move
    renderTicks(rig, 400);
    ASSERT_TRUE(rig.command(msgs::CommandKind::kEnable));
    renderTicks(rig, 400);
    EXPECT_EQ(rig.core.stateMachine().faultCount(), 0U) << "a healthy thimble follows";
    rig.emulatorFault(kThimble, "servo-stuck 2");
    ASSERT_TRUE(rig.command(msgs::CommandKind::kDisable));  // every servo must move now
    renderTicks(rig, 400);
    const std::string message = onlyFault(rig, runtime::kFaultImplausibleFeedback, "thimble");
    EXPECT_THAT(message, HasSubstr("servo 2 at "));
    EXPECT_THAT(message, HasSubstr(" deg expected for 5"));
}

// After a device fault that was raised, cleared by the device and by the operator, the servo
// check runs again: it judges only while the device reports no fault, and the code of the
// fault that had gone must not read as a standing one (it did, for the rest of the run).
TEST(Plausibility, TheServoCheckRunsAgainAfterADeviceFaultHasGone) {
    RuntimeRig rig;
    renderWithForce(rig);
    rig.emulatorFault(kThimble, "fault 2");
    renderTicks(rig, 20);
    EXPECT_THAT(onlyFault(rig, runtime::kFaultDeviceReported, "thimble"), HasSubstr("fault 2"));
    rig.emulatorFault(kThimble, "clear");
    renderTicks(rig, 30);
    ASSERT_TRUE(rig.command(msgs::CommandKind::kClearFault)) << rig.reply.message.view();
    renderTicks(rig, 20);
    ASSERT_EQ(rig.core.state(), msgs::DaemonState::kIdle);
    ASSERT_TRUE(rig.command(msgs::CommandKind::kEnable));
    renderTicks(rig, 400);
    ASSERT_EQ(rig.core.stateMachine().faultCount(), 0U);
    rig.emulatorFault(kThimble, "servo-stuck 2");
    ASSERT_TRUE(rig.command(msgs::CommandKind::kDisable));
    renderTicks(rig, 400);
    EXPECT_THAT(onlyFault(rig, runtime::kFaultImplausibleFeedback, "thimble"),
                HasSubstr("servo 2 at "));
}

// servos.angle_tolerance_deg decides: with 90 degrees the stuck servo above passes.
TEST(Plausibility, TheServoAngleToleranceKeyDecidesWhatIsImplausible) {
    RuntimeRig rig([](std::vector<config::DeviceConfig>& devices) {
        std::get<config::ThimbleConfig>(devices[kThimble].params).servos.angle_tolerance_rad =
            1.5707963;
    });
    renderWithForce(rig);
    rig.emulatorFault(kThimble, "servo-stuck 2");
    ASSERT_TRUE(rig.command(msgs::CommandKind::kDisable));
    renderTicks(rig, 400);
    EXPECT_EQ(rig.core.stateMachine().faultCount(), 0U);
}

// A second host on the exoskeleton's command id, two counters ahead of hapticd: the device's
// sequence check accepts the other host's frames and rejects hapticd's, so it obeys the other
// host while still hearing commands (no command timeout). Its echo, not one of hapticd's
// latest counters, says so.
TEST(Plausibility, AnExoskeletonObeyingAnotherHostRaisesItsOwnFault) {
    RuntimeRig rig;
    renderWithForce(rig);
    can::LoopbackBus other_host;
    ASSERT_TRUE(other_host.connect(rig.target));
    protocol::ExoskeletonCodec codec(rig.devices[kExo]);
    const auto& channel = static_cast<runtime::ExoskeletonChannel&>(rig.runtime.channel(kExo));
    int ticks = 0;
    while (rig.core.state() == msgs::DaemonState::kRendering && ticks < 200) {
        if (ticks % 10 == 0) {
            rig.offerContact();
        }
        rig.tick();
        ++ticks;
        protocol::ExoskeletonCommand push;
        push.enable = true;
        push.force_n = 5.0;
        can::CanFrame frame;
        ASSERT_TRUE(codec.encodeCommand(push, frame));
        protocol::sealFrame(frame, 0,
                            static_cast<std::uint8_t>(channel.driver().lastCommandCounter() + 2));
        ASSERT_EQ(other_host.write(frame), can::IoResult::kOk);
    }
    EXPECT_GE(ticks, 50) << "after can.heartbeat_timeout_ms, not before";
    EXPECT_LE(ticks, 60);
    const std::string message = onlyFault(rig, runtime::kFaultImplausibleFeedback, "exo");
    EXPECT_THAT(message, HasSubstr("it obeys another host or none for 5"));
}

// An echo that is true on one state frame in four and another host's on the other three (the
// emulator's `echo-offset` switched per tick; the drive follows hapticd's force throughout, so
// only the echo says anything is wrong). The true frame used to restart the clock, so the
// contradiction was never reported; on 3 frames of 4 its balance grows by half a tick a tick
// and it is reported after about twice the heartbeat timeout.
TEST(Plausibility, AnEchoThatIsTrueOnOneFrameInFourIsStillReported) {
    RuntimeRig rig;
    renderWithForce(rig);
    int ticks = 0;
    while (rig.core.state() == msgs::DaemonState::kRendering && ticks < 400) {
        if (ticks % 10 == 0) {
            rig.offerContact();
        }
        rig.emulatorFault(kExo, ticks % 4 == 3 ? "echo-offset 0" : "echo-offset 8");
        rig.tick();
        ++ticks;
    }
    EXPECT_GE(ticks, 95) << "not on every frame: the balance grows at half the rate";
    EXPECT_LE(ticks, 115);
    const std::string message = onlyFault(rig, runtime::kFaultImplausibleFeedback, "exo");
    EXPECT_THAT(message, HasSubstr("it obeys another host or none for "));
}

}  // namespace
}  // namespace haptic::testing
