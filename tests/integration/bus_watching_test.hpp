#pragma once

// DeviceSafetyTest with this test as one more party on both devices' UDP buses: the devices'
// own frames, decoded as they arrive, are what the process tests judge the devices by.

#include <algorithm>
#include <array>
#include <cmath>

#include "bus_listener.hpp"
#include "device_safety_rig.hpp"
#include "haptic/tactile/thimble_kinematics.hpp"

namespace haptic::testing {

class BusWatchingTest : public DeviceSafetyTest {
  protected:
    BusWatchingTest()
        : exo_device_(config::loadDeviceConfig(config_.dir / "devices/exoskeleton.yaml")),
          thimble_device_(config::loadDeviceConfig(config_.dir / "devices/thimble.yaml")),
          exo_bus_(exo_device_),
          thimble_bus_(thimble_device_) {
        const tactile::ThimbleKinematics kinematics(thimble_device_.thimble());
        retract_rad_ = kinematics.inverse(kinematics.retractPose()).servo_rad;
    }

    // The sim input injector (a wall the exoskeleton's finger is always inside, a flat object
    // in the thimble's pad) feeding hapticd, then `enable` and RENDERING.
    void injectAndEnable() {
        injector_ =
            std::make_unique<EmulatorProcess>(std::vector<std::string>{SIM_INPUT_INJECTOR_PATH});
        waitForOutput(*injector_, "ready");
        ASSERT_TRUE(command("enable"));
        waitForStatus("RENDERING", [](const msgs::HapticStatus& s) {
            return s.state == msgs::DaemonState::kRendering;
        });
    }
    void TearDown() override {
        if (injector_) {
            injector_->stop();
        }
        DeviceSafetyTest::TearDown();
    }

    // IDLE with both devices READY and no fault, and for 200 ms no exoskeleton command that
    // enables the drive: after a restart or a clear, nothing but `enable` re-arms it.
    void expectIdleAndDisabledUntilEnable() {
        waitForStatus("IDLE with both devices READY and no fault", [](const msgs::HapticStatus& s) {
            return s.state == msgs::DaemonState::kIdle && s.faults.empty() &&
                   s.devices.size() == 2 && s.devices[kExo].state == msgs::DeviceRunState::kReady &&
                   s.devices[kThimble].state == msgs::DeviceRunState::kReady;
        });
        const auto idle = exo_bus_.listen(std::chrono::milliseconds(200));
        // The device was heard meanwhile (a silent window would prove nothing).
        EXPECT_GE(
            std::count_if(idle.begin(), idle.end(),
                          [](const auto& h) { return h.message.type == ExoType::kActuatorState; }),
            20);
        EXPECT_FALSE(std::any_of(idle.begin(), idle.end(), [](const auto& h) {
            return enabledWithForce(h.message, 0.0);
        })) << "enabled without an operator";
    }

    // The largest servo angle off the thimble's retract pose (rad).
    double fromRetract(const std::array<double, 3>& angles) const {
        double largest = 0.0;
        for (std::size_t k = 0; k < 3; ++k) {
            largest = std::max(largest, std::abs(angles[k] - retract_rad_[k]));
        }
        return largest;
    }

    config::DeviceConfig exo_device_;
    config::DeviceConfig thimble_device_;
    ExoListener exo_bus_;
    ThimbleListener thimble_bus_;
    std::array<double, 3> retract_rad_{};
    std::unique_ptr<EmulatorProcess> injector_;  // see injectAndEnable()
};

}  // namespace haptic::testing
