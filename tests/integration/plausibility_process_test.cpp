// Device feedback that contradicts hapticd's commands, with real processes: iox-roudi,
// hapticd, one hapticemu per device on the UDP CAN bus and the sim input injector (a wall the
// exoskeleton's finger is always inside: the 10 N clamp; a flat object in the thimble's pad).
// The fault is injected into the emulated device (hapticemu's stdin), hapticd must latch 105
// naming that device, and the device's own frames, read on its bus by this test, must show it
// made safe. The checks themselves and their tolerances: runtime_test's Plausibility.*.

#include "bus_watching_test.hpp"

namespace haptic::testing {
namespace {

using ::testing::HasSubstr;
using namespace std::chrono_literals;

class PlausibilityProcessTest : public BusWatchingTest {
  protected:
    // Each test injects a device's misbehaviour while the devices render, and only that may
    // take the force away: sim_timeout_ms 200, not the shipped 20, which the injector (and
    // under the sanitizers a slowed hapticd) can miss, fading the force and the plate out
    // at the moment of the injection.
    PlausibilityProcessTest() {
        replaceLine(config_.dir / "daemon.yaml", "sim_timeout_ms: 20", "sim_timeout_ms: 200");
    }

    // Enables rendering on the injector's input until the exoskeleton reports itself at
    // more than half its clamp.
    void renderAtTheClamp() {
        injectAndEnable();
        if (HasFatalFailure()) {
            return;
        }
        const auto deadline = std::chrono::steady_clock::now() + 10s;
        while (std::chrono::steady_clock::now() < deadline) {
            const auto window = exo_bus_.listen(30ms);
            if (std::any_of(window.begin(), window.end(),
                            [](const auto& h) { return enabledWithForce(h.message, 5.0); })) {
                return;
            }
        }
        FAIL() << "the exoskeleton never reported 5 N";
    }

    // The one 105 fault of `device` hapticd latched (under the sanitizers a stall fault 110
    // may stand beside it); its message.
    std::string implausibleFault(const std::string& device) {
        const auto status = waitForStatus("FAULT", [](const msgs::HapticStatus& s) {
            return s.state == msgs::DaemonState::kFault && !s.faults.empty();
        });
        const auto fault = std::find_if(status.faults.begin(), status.faults.end(),
                                        [](const msgs::Fault& f) { return f.code == 105U; });
        if (fault == status.faults.end()) {
            ADD_FAILURE() << "no 105: " << faultsOf(status);
            return {};
        }
        EXPECT_EQ(fault->device_id.view(), device) << faultsOf(status);
        // The journal says so too: hapticd's non-RT thread logs each fault as it latches.
        const std::string journal_line = "fault [105] " + device + ": ";
        bool journaled = false;
        for (auto deadline = std::chrono::steady_clock::now() + 2s;
             !journaled && std::chrono::steady_clock::now() < deadline;
             std::this_thread::sleep_for(20ms)) {
            journaled = daemon_->stderrText().find(journal_line) != std::string::npos;
        }
        EXPECT_TRUE(journaled) << "no '" << journal_line << "' in hapticd's log:\n"
                               << daemon_->stderrText();
        for (const msgs::Fault& other : status.faults) {
            EXPECT_TRUE(other.code == 105U || (HAPTIC_SANITIZED != 0 && other.code == 110U))
                << "blamed: " << faultsOf(status);
        }
        return std::string(fault->message.view());
    }

    // The exoskeleton's own frames: hapticd's FAULT disables it (within a stall of a sanitized
    // hapticd), and it stays limp.
    void expectLimpFromNowOn() {
        const auto heard = exo_bus_.listen(HAPTIC_SANITIZED != 0 ? 600ms : 200ms);
        const auto first_limp =
            std::find_if(heard.begin(), heard.end(), [](const auto& h) { return limp(h.message); });
        ASSERT_NE(first_limp, heard.end()) << "the exoskeleton never went limp";
        int states = 0;
        for (auto it = first_limp; it != heard.end(); ++it) {
            if (it->message.type == ExoType::kActuatorState) {
                ++states;
                EXPECT_TRUE(limp(it->message)) << "force " << it->message.actuator.force_n;
            }
        }
        EXPECT_GT(states, 10);
    }
};

// The drive delivers a fifth of what it is told (a broken current loop or a slipping screw):
// measured force off the expected one by more than actuator.force_tolerance_n + 20 % for
// longer than the heartbeat timeout.
TEST_F(PlausibilityProcessTest, AnExoskeletonDeliveringTooLittleForceLatchesItsOwnFault) {
    renderAtTheClamp();
    ASSERT_TRUE(exo_emu_->sendCommand("force-percent 20"));
    const std::string message = implausibleFault("exo");
    EXPECT_THAT(message, HasSubstr("device measures ")) << message;
    EXPECT_THAT(message, HasSubstr(" N commanded for ")) << message;
    expectLimpFromNowOn();
}

// A thimble servo that holds its angle while the others follow: hapticd disables rendering
// (every servo must go to the retract pose), the stuck one stays where it was.
TEST_F(PlausibilityProcessTest, AThimbleServoThatDoesNotFollowItsTargetLatchesItsOwnFault) {
    renderAtTheClamp();
    std::this_thread::sleep_for(500ms);  // the plate settles on the object
    // Servo 2 is off its retract angle (the plate presses), so that where it sticks is not
    // within the 5 degree tolerance of where the disable sends it.
    double servo2_off_retract_rad = 0.0;
    const auto pressing_deadline = std::chrono::steady_clock::now() + 5s;
    while (servo2_off_retract_rad <= 0.15 && std::chrono::steady_clock::now() < pressing_deadline) {
        for (const auto& h : thimble_bus_.listen(30ms)) {
            if (h.message.type == ThimbleType::kState) {
                servo2_off_retract_rad =
                    std::abs(h.message.state.servo_angle_rad[1] - retract_rad_[1]);
            }
        }
    }
    ASSERT_GT(servo2_off_retract_rad, 0.15) << "the plate never pressed";
    ASSERT_TRUE(thimble_emu_->sendCommand("servo-stuck 2"));
    ASSERT_TRUE(command("disable"));
    const std::string message = implausibleFault("thimble");
    EXPECT_THAT(message, HasSubstr("servo 2 at ")) << message;
    // The device's own frames: servos 1 and 3 reach the retract pose, servo 2 does not (within
    // 2 s, 5 s under the sanitizers: a sanitized hapticd is slow, and the pad limits may slow a
    // withdrawal that tilts; one ASan run in a CI rehearsal ended its 2 s with both at 1.364
    // rad of 1.571, cause not found: the failure says when the last state frame came).
    std::array<double, 3> angles{};
    bool seen = false;
    int frames = 0;
    auto last_frame_at = std::chrono::steady_clock::now();
    const auto deadline = std::chrono::steady_clock::now() + (HAPTIC_SANITIZED != 0 ? 5s : 2s);
    while (std::chrono::steady_clock::now() < deadline) {
        const auto heard = thimble_bus_.listen(100ms);
        const auto last = std::find_if(heard.rbegin(), heard.rend(), [](const auto& h) {
            return h.message.type == ThimbleType::kState;
        });
        if (last == heard.rend()) {
            continue;
        }
        seen = true;
        ++frames;
        last_frame_at = std::chrono::steady_clock::now();
        angles = last->message.state.servo_angle_rad;
        if (std::abs(angles[0] - retract_rad_[0]) < 0.02 &&
            std::abs(angles[2] - retract_rad_[2]) < 0.02) {
            break;
        }
    }
    ASSERT_TRUE(seen) << "no thimble state frame";
    const auto silent_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                               std::chrono::steady_clock::now() - last_frame_at)
                               .count();
    EXPECT_NEAR(angles[0], retract_rad_[0], 0.02)
        << frames << " listens heard a state frame, the last " << silent_ms << " ms ago";
    EXPECT_NEAR(angles[2], retract_rad_[2], 0.02);
    EXPECT_GT(std::abs(angles[1] - retract_rad_[1]), 0.1) << "servo 2 was stuck off retract";
}

// A device that obeys another host's commands (the other host's counters, not hapticd's):
// hapticemu's `echo-offset 8` makes the exoskeleton echo a counter eight ahead of hapticd's
// while it still does what hapticd asks, so only the echo tells. Eight is half the 4-bit
// counter's range: hapticd takes an echo 0-4 commands behind as the round trip, so an offset
// of 8 looks plausible only on a round trip of 8-12 ticks. With 2, as this test had, every
// tick with a round trip of 2-6 looked plausible and restarted the contradiction's clock; under
// the sanitizers the round trip is 1 (Release: 0), so one late state frame in 250 ms (this
// rig's heartbeat timeout) was enough, and in a CI rehearsal's ASan run the fault never
// latched in 20 s. (A second host on the bus
// racing hapticd frame by frame does the same in runtime_test's
// Plausibility.AnExoskeletonObeyingAnotherHostRaisesItsOwnFault, in lockstep; from a test
// process it would have to win every 1 ms race for 50 ms.)
TEST_F(PlausibilityProcessTest, AnExoskeletonObeyingAnotherHostLatchesItsOwnFault) {
    renderAtTheClamp();
    ASSERT_TRUE(exo_emu_->sendCommand("echo-offset 8"));
    const std::string message = implausibleFault("exo");
    EXPECT_THAT(message, HasSubstr("it obeys another host or none")) << message;
    expectLimpFromNowOn();
}

// A device that reports a fault of its own in its status (here the exoskeleton's drive
// overheating, `fault 2`): hapticd latches 102 naming the device and the code, the device's own
// frames show it limp; `clear` while the device still reports the fault raises it again, and
// only the device's recovery, `clear` and `enable` bring the force back.
TEST_F(PlausibilityProcessTest,
       ADeviceReportingItsOwnFaultLatchesUntilItRecoversAndAnOperatorReArms) {
    renderAtTheClamp();
    ASSERT_TRUE(exo_emu_->sendCommand("fault 2"));
    const auto isDeviceFault = [](const msgs::Fault& f) {
        return f.code == 102U && f.device_id.view() == "exo";
    };
    const auto faulted = [&](const msgs::HapticStatus& s) {
        return s.state == msgs::DaemonState::kFault &&
               std::any_of(s.faults.begin(), s.faults.end(), isDeviceFault);
    };
    const auto status = waitForStatus("FAULT 102 exo", faulted);
    const auto fault = std::find_if(status.faults.begin(), status.faults.end(), isDeviceFault);
    ASSERT_NE(fault, status.faults.end()) << faultsOf(status);
    EXPECT_THAT(std::string(fault->message.view()), HasSubstr("device reports fault 2 ("))
        << faultsOf(status);
    for (const msgs::Fault& other : status.faults) {
        EXPECT_TRUE(isDeviceFault(other) || (HAPTIC_SANITIZED != 0 && other.code == 110U))
            << "blamed: " << faultsOf(status);
    }
    expectLimpFromNowOn();

    // Still overheating: clearing does not hide it. The clear is refused with what stands,
    // hapticd stays in FAULT (judged on a status taken after the clear: one published before
    // would show the old FAULT), and an operator's enable then is refused and moves nothing.
    const std::int64_t cleared_ns = monotonicNs();
    const CommandResult clear = hapticctl({"clear"});
    EXPECT_NE(clear.exit_code, 0) << clear.out;
    EXPECT_THAT(clear.out + clear.err,
                HasSubstr("device 'exo' still shows the cause of fault 102; clear once it has "
                          "gone"));
    waitForStatus("FAULT 102 exo still after clear", [&](const msgs::HapticStatus& s) {
        return s.header.stamp_ns > cleared_ns + 50'000'000 && faulted(s);
    });
    const CommandResult enable = hapticctl({"enable"});
    EXPECT_NE(enable.exit_code, 0)
        << "enable accepted while the device reports its fault: " << enable.out;
    const auto still = exo_bus_.listen(200ms);
    EXPECT_FALSE(std::any_of(still.begin(), still.end(), [](const auto& h) {
        return enabledWithForce(h.message, 0.0);
    })) << "enabled while the device reports its fault";

    // Recovered: the operator clears and enables, and the force returns.
    ASSERT_TRUE(exo_emu_->sendCommand("clear"));
    std::this_thread::sleep_for(100ms);  // the next heartbeat reports no fault
    ASSERT_TRUE(command("clear"));
    expectIdleAndDisabledUntilEnable();
    ASSERT_TRUE(command("enable"));
    bool pushing = false;
    for (auto deadline = std::chrono::steady_clock::now() + 5s;
         !pushing && std::chrono::steady_clock::now() < deadline;) {
        const auto window = exo_bus_.listen(30ms);
        pushing = std::any_of(window.begin(), window.end(),
                              [](const auto& h) { return enabledWithForce(h.message, 1.0); });
    }
    EXPECT_TRUE(pushing) << "no force after the device recovered and the operator re-armed";
}

}  // namespace
}  // namespace haptic::testing
