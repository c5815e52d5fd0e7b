// Device feedback that contradicts hapticd's commands, with real processes: iox-roudi,
// hapticd, one hapticemu per device on the UDP CAN bus and the sim input injector (a wall the
// exoskeleton's finger is always inside: the 10 N clamp; a flat object in the thimble's pad).
// The fault is injected into the emulated device (hapticemu's stdin), hapticd must latch 105
// naming that device, and the device's own frames, read on its bus by this test, must show it
// made safe (or, for the other host, what it did). The checks themselves and their
// tolerances: runtime_test's Plausibility.*.

#include "bus_listener.hpp"
#include "device_safety_rig.hpp"
#include "haptic/protocol/frame_codec.hpp"
#include "haptic/tactile/thimble_kinematics.hpp"

namespace haptic::testing {
namespace {

using ::testing::HasSubstr;
using namespace std::chrono_literals;

class PlausibilityProcessTest : public DeviceSafetyTest {
  protected:
    PlausibilityProcessTest()
        : exo_device_(config::loadDeviceConfig(config_.dir / "devices/exoskeleton.yaml")),
          thimble_device_(config::loadDeviceConfig(config_.dir / "devices/thimble.yaml")),
          exo_bus_(exo_device_),
          thimble_bus_(thimble_device_) {
        const tactile::ThimbleKinematics kinematics(thimble_device_.thimble());
        retract_rad_ = kinematics.inverse(kinematics.retractPose()).servo_rad;
    }

    // Enables rendering on the injector's input until the exoskeleton reports itself at
    // more than half its clamp.
    void renderAtTheClamp() {
        injector_ =
            std::make_unique<EmulatorProcess>(std::vector<std::string>{SIM_INPUT_INJECTOR_PATH});
        waitForOutput(*injector_, "ready");
        ASSERT_TRUE(command("enable"));
        waitForStatus("RENDERING", [](const msgs::HapticStatus& s) {
            return s.state == msgs::DaemonState::kRendering;
        });
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
        for (const msgs::Fault& other : status.faults) {
            EXPECT_TRUE(other.code == 105U || (HAPTIC_SANITIZED != 0 && other.code == 110U))
                << "blamed: " << faultsOf(status);
        }
        return std::string(fault->message.view());
    }

    void TearDown() override {
        if (injector_) {
            injector_->stop();
        }
        DeviceSafetyTest::TearDown();
    }

    config::DeviceConfig exo_device_;
    config::DeviceConfig thimble_device_;
    ExoListener exo_bus_;
    ThimbleListener thimble_bus_;
    tactile::ServoAngles retract_rad_{};
    std::unique_ptr<EmulatorProcess> injector_;
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
    // The device's own frames: hapticd's FAULT disabled it.
    (void)exo_bus_.listen(50ms);
    const auto heard = exo_bus_.listen(100ms);
    const auto states = std::count_if(heard.begin(), heard.end(), [](const auto& h) {
        return h.message.type == ExoType::kActuatorState;
    });
    ASSERT_GT(states, 10);
    for (const auto& h : heard) {
        if (h.message.type == ExoType::kActuatorState) {
            EXPECT_TRUE(limp(h.message)) << "force " << h.message.actuator.force_n;
        }
    }
}

// A thimble servo that holds its angle while the others follow: hapticd disables rendering
// (every servo must go to the retract pose), the stuck one stays where it was.
TEST_F(PlausibilityProcessTest, AThimbleServoThatDoesNotFollowItsTargetLatchesItsOwnFault) {
    renderAtTheClamp();
    std::this_thread::sleep_for(500ms);  // the plate settles on the object
    ASSERT_TRUE(thimble_emu_->sendCommand("servo-stuck 2"));
    ASSERT_TRUE(command("disable"));
    const std::string message = implausibleFault("thimble");
    EXPECT_THAT(message, HasSubstr("servo 2 at ")) << message;
    // The device's own frames: servos 1 and 3 reached the retract pose, servo 2 did not.
    const auto heard = thimble_bus_.listen(200ms);
    const auto last = std::find_if(heard.rbegin(), heard.rend(), [](const auto& h) {
        return h.message.type == ThimbleType::kState;
    });
    ASSERT_NE(last, heard.rend()) << "no thimble state frame";
    const auto& angles = last->message.state.servo_angle_rad;
    EXPECT_NEAR(angles[0], retract_rad_[0], 0.02);
    EXPECT_NEAR(angles[2], retract_rad_[2], 0.02);
    EXPECT_GT(std::abs(angles[1] - retract_rad_[1]), 0.1) << "servo 2 was stuck off retract";
}

// A second host on the exoskeleton's bus repeating each of hapticd's commands, two counters
// ahead (a stale bridge or a replaying tool): the device's sequence check takes the other
// host's frames and rejects hapticd's, so it obeys the other host while commands keep coming
// (no command timeout). It even does what hapticd asked, so only its echoed counter, none of
// hapticd's latest, tells.
TEST_F(PlausibilityProcessTest, AnExoskeletonObeyingAnotherHostLatchesItsOwnFault) {
    renderAtTheClamp();
    can::UdpBus intruder(
        can::UdpBusConfig{exo_device_.can.udp_port, exo_device_.can.udp_slots, {}});
    int answered = 0;
    bool faulted = false;
    const auto deadline = std::chrono::steady_clock::now() + 3s;
    while (!faulted && std::chrono::steady_clock::now() < deadline) {
        pollfd fd{intruder.pollFd(), POLLIN, 0};
        (void)::poll(&fd, 1, 1);
        can::CanFrame frame;
        while (intruder.read(frame) == can::IoResult::kOk) {
            if (frame.id != exo_device_.can.command_id || frame.isError()) {
                continue;
            }
            protocol::sealFrame(frame, protocol::frameKind(frame),
                                static_cast<std::uint8_t>((protocol::frameCounter(frame) + 2) %
                                                          protocol::kCounterModulo));
            ASSERT_EQ(intruder.write(frame), can::IoResult::kOk);
            ++answered;
        }
        if (answered % 100 == 99) {
            msgs::HapticStatus status;
            idl::HapticStatus sample;
            faulted = status_reader_.waitAndTake(sample, 0ms) &&
                      msgs::fromIdl(sample, status).ok() &&
                      status.state == msgs::DaemonState::kFault;
        }
    }
    EXPECT_GT(answered, 40) << "the other host answered hapticd for longer than 40 ms";
    const std::string message = implausibleFault("exo");
    EXPECT_THAT(message, HasSubstr("it obeys another host or none")) << message;
    // Once the other host is gone, the device takes hapticd's commands again: disabled.
    const auto heard = exo_bus_.listen(300ms);
    const auto last = std::find_if(heard.rbegin(), heard.rend(), [](const auto& h) {
        return h.message.type == ExoType::kActuatorState;
    });
    ASSERT_NE(last, heard.rend());
    EXPECT_TRUE(limp(last->message)) << "force " << last->message.actuator.force_n;
}

}  // namespace
}  // namespace haptic::testing
