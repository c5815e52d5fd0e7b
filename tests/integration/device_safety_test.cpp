// End-to-end safety of hapticd with devices attached: the real iox-roudi, hapticd, handsim,
// hapticctl and one `hapticemu` process per device on the UDP CAN bus. The test reads
// haptic/status and haptic/telemetry over DDS itself (stamps are CLOCK_MONOTONIC, the clock it
// kills the sim by) and publishes its own ConstraintSets over iceoryx where it needs exact
// control of the sim input. Shares RouDi's socket with end_to_end_test: same RESOURCE_LOCK.

#include <iostream>

#include "device_safety_rig.hpp"
#include "haptic/msgs/names.hpp"

namespace haptic::testing {
namespace {

using ::testing::HasSubstr;
using namespace std::chrono_literals;

bool targetsNear(const msgs::TelemetrySample& a, const msgs::TelemetrySample& b) {
    for (std::size_t k = 0; k < 3; ++k) {
        if (!(std::abs(a.thimble.servo_angle_cmd_rad[k] - b.thimble.servo_angle_cmd_rad[k]) <
              1e-3)) {
            return false;
        }
    }
    return true;
}

// The sim input injector's steady contact, with sim_timeout_ms 200 here: a stalled injector
// thread on a loaded machine (or a sanitized one) must not fade the output (that is the stale
// input path, tested separately), so only what a test does to hapticd could move it.
class SteadySimInputTest : public DeviceSafetyTest {
  protected:
    SteadySimInputTest() {
        replaceLine(config_.dir / "daemon.yaml", "sim_timeout_ms: 20", "sim_timeout_ms: 200");
    }
};

// Bad messages among good ones.
class BadSimInputTest : public SteadySimInputTest {};

TEST_F(BadSimInputTest, RejectedCountedAndDoesNotChangeTheOutput) {
    // The injector is its own iceoryx process: RouDi signals every registered process when it
    // stops, which must not be this test.
    EmulatorProcess injector({SIM_INPUT_INJECTOR_PATH});
    waitForOutput(injector, "ready");
    const auto thimble_idle = collectTelemetry(kThimble, 100ms);
    ASSERT_FALSE(thimble_idle.empty());

    ASSERT_TRUE(command("enable"));
    waitForStatus("RENDERING", [](const msgs::HapticStatus& s) {
        return s.state == msgs::DaemonState::kRendering;
    });
    // Fade-in (100 ms) and the servo ramp to the contact pose: wait until the targets hold.
    const auto steady_deadline = std::chrono::steady_clock::now() + 15s;
    bool steady = false;
    while (!steady && std::chrono::steady_clock::now() < steady_deadline) {
        const auto window = collectTelemetry(kThimble, 200ms);
        steady = window.size() > 50 &&
                 std::all_of(window.begin(), window.end(), [&](const auto& sample) {
                     return targetsNear(sample, window.front());
                 });
    }
    ASSERT_TRUE(steady) << "the thimble's targets never settled";
    const auto before = waitForStatus("a fresh status", [](const auto&) { return true; });
    ASSERT_EQ(before.state, msgs::DaemonState::kRendering)
        << "before any bad input: " << faultsOf(before) << daemon_->stderrText();
    drainTelemetry();

    ASSERT_TRUE(injector.sendCommand("bad on"));
    // This reader hears a third to a half of the ticks under the sanitizers (181 of 600 in a CI
    // run's SimKilled below), so the phase lasts twice as long there for the same bar.
    const auto thimble = collectTelemetry(kThimble, HAPTIC_SANITIZED != 0 ? 3000ms : 1500ms);
    ASSERT_TRUE(injector.sendCommand("bad off"));
    std::smatch sent_match;
    const std::string out = waitForOutput(injector, "sent ");
    ASSERT_TRUE(std::regex_search(out, sent_match, std::regex(R"(sent (\d+))"))) << out;
    const std::uint64_t sent = std::stoull(sent_match[1]);
    std::this_thread::sleep_for(300ms);  // the last bad messages reach a status snapshot
    const auto after = waitForStatus("a status after the bad phase", [&](const auto& s) {
        return s.header.stamp_ns > monotonicNs() - 100'000'000;
    });
    injector.stop();

    EXPECT_GT(sent, 100U);
    // Every bad message hapticd took is counted. The subscriber keeps only the newest sample
    // (a queue of one, by design for control data), so a tick delayed past the next good
    // message (5 ms) never sees one: allow 2 % of them for a loaded machine under ASan.
    const std::uint64_t rejected = after.sim_link.rejected - before.sim_link.rejected;
    EXPECT_LE(rejected, sent);
    EXPECT_GE(rejected, sent - sent / 50);
    EXPECT_EQ(after.state, msgs::DaemonState::kRendering)
        << "bad input is not a device fault: " << faultsOf(after) << daemon_->stderrText();
    // The thimble's targets depend only on the accepted surfaces: not one bad message may
    // move them. An accepted one would have sent the plate towards the retract pose for the
    // 5 ms until the next good one, a full servo-rate step (400 deg/s: 6.98 mrad) per tick.
    // Re-solving the same good surface from the warm start creeps by far less per solve.
    ASSERT_GT(thimble.size(), 500U) << "thimble samples heard in the bad phase";
    const auto& pressed = thimble.front().thimble.servo_angle_cmd_rad;
    EXPECT_GT(std::abs(pressed[0] - thimble_idle.back().thimble.servo_angle_cmd_rad[0]), 0.05)
        << "the plate is not pressing";
    const double half_step = 0.5 * 400.0 * M_PI / 180.0 * 1e-3;
    for (std::size_t i = 1; i < thimble.size(); ++i) {
        for (std::size_t k = 0; k < 3; ++k) {
            ASSERT_LT(std::abs(thimble[i].thimble.servo_angle_cmd_rad[k] -
                               thimble[i - 1].thimble.servo_angle_cmd_rad[k]),
                      half_step)
                << "tick " << thimble[i].tick << " servo " << k;
            ASSERT_LT(std::abs(thimble[i].thimble.servo_angle_cmd_rad[k] - pressed[k]), 0.01)
                << "tick " << thimble[i].tick << " servo " << k;
        }
    }
    const auto status = hapticctl({"status"});
    ASSERT_EQ(status.exit_code, 0) << status.err;
    EXPECT_THAT(status.out, HasSubstr(std::to_string(after.sim_link.rejected) + " rejected"));
    // By reason, over the real status topic: every way the injector makes a message bad is
    // counted under its own reason, and the reasons add up to the count.
    std::uint64_t by_reason = 0;
    for (std::size_t i = 0; i < msgs::kSimInputRejectionReasons; ++i) {
        by_reason += after.sim_link.rejected_by_reason[i] - before.sim_link.rejected_by_reason[i];
    }
    EXPECT_EQ(by_reason, rejected);
    using Reason = msgs::SimInputRejection;
    for (const Reason reason :
         {Reason::kNonFinite, Reason::kDofMismatch, Reason::kDegenerateConstraint,
          Reason::kCountOverCapacity, Reason::kBadNormal, Reason::kNegativeWeight,
          Reason::kWrongDevice}) {
        const std::size_t i = msgs::reasonIndex(reason);
        EXPECT_GT(after.sim_link.rejected_by_reason[i] - before.sim_link.rejected_by_reason[i], 0U)
            << msgs::toString(reason);
        EXPECT_THAT(status.out, HasSubstr(std::string(msgs::toString(reason)) + " "))
            << "the status screen's 'rejected:' line";
    }
}

std::vector<msgs::TelemetrySample> ofDevice(const std::vector<msgs::TelemetrySample>& samples,
                                            std::size_t device) {
    std::vector<msgs::TelemetrySample> out;
    std::copy_if(samples.begin(), samples.end(), std::back_inserter(out),
                 [&](const auto& sample) { return sample.device_index == device; });
    return out;
}

// Largest distance of a servo target from the retract targets (rad).
double fromRetract(const msgs::TelemetrySample& sample, const msgs::TelemetrySample& retract) {
    double largest = 0.0;
    for (std::size_t k = 0; k < 3; ++k) {
        largest = std::max(largest, std::abs(sample.thimble.servo_angle_cmd_rad[k] -
                                             retract.thimble.servo_angle_cmd_rad[k]));
    }
    return largest;
}

TEST_F(DeviceSafetyTest, SimKilledWhileRenderingFadesTheForceToZeroAndOnlyAnEnableBringsItBack) {
    startSim();
    waitForStatus("sim connected", [](const msgs::HapticStatus& s) {
        return s.sim_link.connected && s.sim_link.received > 20;
    });
    // IDLE holds the thimble at its retract pose: that is where a fade must take it.
    const auto idle = collectTelemetry(kThimble, 100ms);
    ASSERT_FALSE(idle.empty());
    const msgs::TelemetrySample retract = idle.back();
    ASSERT_TRUE(command("enable"));
    waitForStatus("RENDERING", [](const msgs::HapticStatus& s) {
        return s.state == msgs::DaemonState::kRendering;
    });
    // The default scene presses the fingertip now and then: kill the sim while the thimble's
    // plate presses and the exoskeleton pushes (the virtual user's finger meets the object in
    // both at once), so that both fades below start from a force and neither check holds by
    // itself.
    drainTelemetry();
    std::vector<msgs::TelemetrySample> exo;
    std::vector<msgs::TelemetrySample> thimble;
    const auto started = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() - started < 30s) {
        const auto window = collectTelemetry(kAllDevices, 30ms);
        exo = ofDevice(window, kExo);
        thimble = ofDevice(window, kThimble);
        const bool pressing = !thimble.empty() && fromRetract(thimble.back(), retract) > 0.05;
        const bool exo_force =
            !exo.empty() && std::abs(exo.back().exoskeleton.actuator_force_cmd_n) > 0.5;
        if (pressing && exo_force) {
            break;
        }
    }
    ASSERT_FALSE(thimble.empty());
    ASSERT_FALSE(exo.empty());
    ASSERT_GT(fromRetract(thimble.back(), retract), 0.05)
        << "the thimble never pressed with the exoskeleton pushing; faults: "
        << faultsOf(waitForStatus("a status", [](const auto&) { return true; }));
    ASSERT_GT(std::abs(exo.back().exoskeleton.actuator_force_cmd_n), 0.5)
        << "the exoskeleton never pushed with the thimble pressing";
    std::cout << "killing the sim at " << exo.back().exoskeleton.actuator_force_cmd_n
              << " N on the exoskeleton, the plate " << fromRetract(thimble.back(), retract)
              << " rad from retract\n";

    const std::int64_t kill_ns = monotonicNs();
    ::kill(sim_->pid(), SIGKILL);
    // Under the sanitizers this reader gets about half the ticks (299 of ~580 in one CI
    // rehearsal, 181 in another): a longer window there keeps enough of them to check.
    const auto after = collectTelemetry(kAllDevices, HAPTIC_SANITIZED != 0 ? 1000ms : 600ms);
    ASSERT_TRUE(sim_->waitFor(5s).has_value());

    // Every sim message reached hapticd before the kill; the RT thread takes the last one at
    // its next tick (1 ms, plus up to 2 ms wake-up latency on a loaded VM), so from
    // kill + sim_timeout (20 ms) + 3 ms on the output gain is zero.
    const std::int64_t zero_from_ns = kill_ns + 20'000'000 + 3'000'000;
    const auto exo_after = ofDevice(after, kExo);
    std::size_t checked = 0;
    for (std::size_t i = 0; i < exo_after.size(); ++i) {
        const double force = exo_after[i].exoskeleton.actuator_force_cmd_n;
        if (exo_after[i].stamp_ns > zero_from_ns) {
            EXPECT_EQ(force, 0.0) << "tick " << exo_after[i].tick << ", "
                                  << (exo_after[i].stamp_ns - kill_ns) / 1e6
                                  << " ms after the kill";
            ++checked;
        }
        if (i > 0 && exo_after[i].tick == exo_after[i - 1].tick + 1) {
            // Never a step up: at most the rate limit while the finger moves under the fade.
            EXPECT_LE(std::abs(force) - std::abs(exo_after[i - 1].exoskeleton.actuator_force_cmd_n),
                      kMaxStepN)
                << "tick " << exo_after[i].tick;
        }
    }
    // 600 ms of telemetry (1000 ms under the sanitizers), every sample that reached this
    // reader checked.
    const std::size_t enough = HAPTIC_SANITIZED != 0 ? 200U : 400U;
    EXPECT_GT(checked, enough) << "exoskeleton samples checked at zero force after the fade, of "
                               << exo_after.size() << " heard";

    // The thimble: at gain zero the commanded pose is the retract pose, which the servo
    // limiter approaches at exactly servos.max_rate_deg_per_s (400 deg/s: 6.98 mrad per tick)
    // on the servo farthest from it, never moving back towards the pad.
    const double step = 400.0 * M_PI / 180.0 * 1e-3;
    const auto thimble_after = ofDevice(after, kThimble);
    std::size_t ramped = 0;
    for (std::size_t i = 1; i < thimble_after.size(); ++i) {
        if (thimble_after[i - 1].stamp_ns <= zero_from_ns ||
            thimble_after[i].tick != thimble_after[i - 1].tick + 1) {
            continue;
        }
        const double previous = fromRetract(thimble_after[i - 1], retract);
        EXPECT_NEAR(fromRetract(thimble_after[i], retract), std::max(previous - step, 0.0), 1e-6)
            << "tick " << thimble_after[i].tick;
        ++ramped;
    }
    EXPECT_GT(ramped, enough) << "consecutive thimble ticks checked on the ramp, of "
                              << thimble_after.size() << " heard";
    ASSERT_FALSE(thimble_after.empty());
    EXPECT_LT(fromRetract(thimble_after.back(), retract), 1e-9) << "not back at the retract pose";
    waitForStatus("sim link down",
                  [](const msgs::HapticStatus& s) { return !s.sim_link.connected; });
    const auto status = hapticctl({"status"});
    EXPECT_THAT(status.out, HasSubstr("NOT CONNECTED")) << status.err;

    // Re-arm policy: the sim has been gone longer than loop.sim_rearm_after_ms (1 s shipped;
    // 10 s under the sanitizers, whose 4 Hz sim is left out of this part). A sim that comes
    // back brings no force until an operator enables again.
    if (HAPTIC_SANITIZED != 0) {
        return;
    }
    waitForStatus("AWAITING ENABLE", [](const msgs::HapticStatus& s) {
        return !s.devices.empty() && s.devices[0].awaiting_enable;
    });
    EXPECT_THAT(hapticctl({"status"}).out, HasSubstr("AWAITING ENABLE"));
    startSim();
    waitForStatus("sim back", [](const msgs::HapticStatus& s) {
        return s.sim_link.connected && s.state == msgs::DaemonState::kRendering;
    });
    const auto back = collectTelemetry(kAllDevices, 1500ms);
    ASSERT_GT(ofDevice(back, kExo).size(), 100U);
    for (const auto& sample : ofDevice(back, kExo)) {
        EXPECT_EQ(sample.exoskeleton.actuator_force_cmd_n, 0.0) << "force without an enable";
    }
    for (const auto& sample : ofDevice(back, kThimble)) {
        EXPECT_LT(fromRetract(sample, retract), 1e-9) << "the plate moved without an enable";
    }
    ASSERT_TRUE(command("enable"));
    waitForStatus("re-armed", [](const msgs::HapticStatus& s) {
        return !s.devices.empty() && !s.devices[0].awaiting_enable;
    });
    // The default scene presses again within its period: the plate leaves the retract pose.
    bool pressed = false;
    const auto rearmed = std::chrono::steady_clock::now();
    while (!pressed && std::chrono::steady_clock::now() - rearmed < 15s) {
        for (const auto& sample : ofDevice(collectTelemetry(kThimble, 100ms), kThimble)) {
            pressed = pressed || fromRetract(sample, retract) > 0.05;
        }
    }
    EXPECT_TRUE(pressed) << "no rendering after the enable";
}

// Each stop is made while the exoskeleton pushes (the injector's wall), so that its zero force
// afterwards is the stop's doing.
TEST_F(SteadySimInputTest, EstopClearHeartbeatLossAndBusOffShowInStatusWithZeroForce) {
    // The injector is its own iceoryx process (RouDi signals every registered process when it
    // stops, which must not be this test).
    EmulatorProcess injector({SIM_INPUT_INJECTOR_PATH});
    waitForOutput(injector, "ready");
    const auto awaitExoPush = [&](const char* before) {
        bool pushing = false;
        for (const auto deadline = std::chrono::steady_clock::now() + 10s;
             !pushing && std::chrono::steady_clock::now() < deadline;) {
            for (const auto& sample : collectTelemetry(kExo, 50ms)) {
                pushing = pushing || std::abs(sample.exoskeleton.actuator_force_cmd_n) > 1.0;
            }
        }
        ASSERT_TRUE(pushing) << "the exoskeleton never pushed more than 1 N before " << before;
    };
    const auto expectZeroExoForce = [&](const char* when) {
        drainTelemetry();
        // Twice as long under the sanitizers, whose reader hears a third to a half of the ticks.
        const auto samples = collectTelemetry(kExo, HAPTIC_SANITIZED != 0 ? 600ms : 300ms);
        ASSERT_GT(samples.size(), 100U) << when << ": exoskeleton samples heard";
        for (const auto& sample : samples) {
            ASSERT_EQ(sample.exoskeleton.actuator_force_cmd_n, 0.0)
                << when << ", tick " << sample.tick;
        }
    };

    // (e) E-STOP and clear with both devices attached.
    ASSERT_TRUE(command("enable"));
    waitForStatus("RENDERING", [](const msgs::HapticStatus& s) {
        return s.state == msgs::DaemonState::kRendering;
    });
    awaitExoPush("the E-STOP");
    ASSERT_TRUE(command("estop"));
    auto status = waitForStatus(
        "E-STOP", [](const msgs::HapticStatus& s) { return s.state == msgs::DaemonState::kEstop; });
    EXPECT_EQ(status.devices[kExo].state, msgs::DeviceRunState::kSafe);
    expectZeroExoForce("during E-STOP");
    ASSERT_TRUE(command("clear"));
    waitForStatus("IDLE, devices ready", [](const msgs::HapticStatus& s) {
        return s.state == msgs::DaemonState::kIdle &&
               s.devices[1].state == msgs::DeviceRunState::kReady;
    });

    // (b) The thimble's heartbeat stops: FAULT naming the thimble.
    ASSERT_TRUE(command("enable"));
    awaitExoPush("the heartbeat loss");
    ASSERT_TRUE(thimble_emu_->sendCommand("heartbeat stop"));
    status = waitForStatus("FAULT", [](const msgs::HapticStatus& s) {
        return s.state == msgs::DaemonState::kFault && !s.faults.empty();
    });
    ASSERT_EQ(status.faults.size(), 1U);
    EXPECT_EQ(status.faults[0].device_id.view(), "thimble");
    EXPECT_EQ(status.faults[0].code, 100U);
    EXPECT_EQ(status.devices[1].state, msgs::DeviceRunState::kFault);
    auto text = hapticctl({"status"});
    EXPECT_THAT(text.out, HasSubstr("State: FAULT"));
    EXPECT_THAT(text.out, HasSubstr("[100] thimble: heartbeat lost"));
    EXPECT_THAT(text.out, ::testing::ContainsRegex("thimble +thimble +FAULT"));
    expectZeroExoForce("after the heartbeat loss");

    ASSERT_TRUE(thimble_emu_->sendCommand("heartbeat start"));
    std::this_thread::sleep_for(100ms);
    ASSERT_TRUE(command("clear"));
    waitForStatus("IDLE after clear", [](const msgs::HapticStatus& s) {
        return s.state == msgs::DaemonState::kIdle && s.faults.empty() &&
               s.devices[1].state == msgs::DeviceRunState::kReady;
    });

    // (c) Bus-off on the exoskeleton's bus: FAULT naming only the exoskeleton.
    ASSERT_TRUE(command("enable"));
    awaitExoPush("the bus-off");
    ASSERT_TRUE(exo_emu_->sendCommand("busoff"));
    status = waitForStatus("bus-off FAULT", [](const msgs::HapticStatus& s) {
        return s.state == msgs::DaemonState::kFault && !s.faults.empty();
    });
    ASSERT_EQ(status.faults.size(), 1U);
    EXPECT_EQ(status.faults[0].device_id.view(), "exo");
    EXPECT_EQ(status.faults[0].code, 101U);
    EXPECT_EQ(status.devices[kExo].can.bus_state, msgs::BusState::kBusOff);
    text = hapticctl({"status"});
    EXPECT_THAT(text.out, HasSubstr("[101] exo: CAN bus-off"));
    EXPECT_THAT(text.out, ::testing::ContainsRegex("exo +exoskeleton +FAULT +bus bus-off"));
    expectZeroExoForce("after bus-off");
}

}  // namespace
}  // namespace haptic::testing
