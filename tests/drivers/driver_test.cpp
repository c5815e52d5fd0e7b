// Drivers against the in-process emulator on a loopback bus, with time driven by the test:
// state flow, heartbeat loss and staleness at the configured timeouts, device faults,
// bus-off, corrupted and dropped frames, back-pressure, and no allocation on the loop path.

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "allocation_counter.hpp"
#include "device_files.hpp"
#include "haptic/can/loopback_bus.hpp"
#include "haptic/devices/exoskeleton_driver.hpp"
#include "haptic/devices/link_monitor.hpp"
#include "haptic/devices/thimble_driver.hpp"
#include "haptic/emu/device_emulator.hpp"
#include "haptic/tactile/thimble_kinematics.hpp"

namespace haptic::devices {
namespace {

using testing::exoskeletonDevice;
using testing::thimbleDevice;
constexpr std::int64_t kMs = 1'000'000;

// Host and device ends of one loopback bus with the emulator on the device end.
struct Rig {
    explicit Rig(const config::DeviceConfig& device, emu::EmulatorMode mode) {
        host.connect(target);
        emu::EmulatorOptions options;
        options.mode = mode;
        emulator = emu::makeEmulator(device, target, options);
    }
    // Moves time forward and lets the emulator do its periodic work and answer commands.
    void advance(std::int64_t dt_ns) {
        now += dt_ns;
        host.setTime(now);
        target.setTime(now);
        can::CanFrame frame;
        while (target.read(frame) == can::IoResult::kOk) {
            emulator->handleFrame(frame, now);
        }
        emulator->tick(now);
    }
    void fault(const char* command) {
        std::string error;
        ASSERT_TRUE(emulator->faults().command(command, error)) << error;
    }

    can::LoopbackBus host;
    can::LoopbackBus target;
    std::unique_ptr<emu::DeviceEmulator> emulator;
    std::int64_t now{1'000 * kMs};
};

// One 1 kHz loop tick of the daemon side.
std::uint32_t tick(Rig& rig, ExoskeletonDriver& driver, double force_n) {
    rig.advance(kMs);
    driver.poll(rig.now);
    const std::uint32_t faults = driver.faults(rig.now);
    (void)driver.sendCommand({force_n, true});
    rig.advance(0);  // the emulator answers within the tick
    driver.poll(rig.now);
    return faults;
}

TEST(ExoskeletonDriver, ReportsNoHeartbeatUntilTheFirstOneArrives) {
    const auto device = exoskeletonDevice();
    Rig rig(device, emu::EmulatorMode::kLockstep);
    ExoskeletonDriver driver(device, rig.host);
    EXPECT_NE(driver.faults(rig.now) & kNoHeartbeatYet, 0U);
    rig.advance(0);  // first heartbeat
    driver.poll(rig.now);
    EXPECT_EQ(driver.faults(rig.now) & kNoHeartbeatYet, 0U);
    EXPECT_NE(driver.faults(rig.now) & kStateStale, 0U);  // no state yet
    tick(rig, driver, 1.0);
    EXPECT_EQ(driver.faults(rig.now), 0U);
    EXPECT_EQ(driver.state().heartbeat.mode, protocol::DeviceMode::kOperational);
}

TEST(ExoskeletonDriver, ForceFollowsTheCommandThroughTheActuatorLag) {
    const auto device = exoskeletonDevice();
    Rig rig(device, emu::EmulatorMode::kLockstep);
    ExoskeletonDriver driver(device, rig.host);
    double previous = 0.0;
    for (int i = 0; i < 100; ++i) {
        ASSERT_EQ(tick(rig, driver, 5.0) & ~kNoHeartbeatYet & ~kStateStale, 0U);
        const double force = driver.state().actuator.force_n;
        ASSERT_GE(force, previous);  // first-order lag: monotone rise
        previous = force;
    }
    EXPECT_NEAR(driver.state().actuator.force_n, 5.0, 0.01);  // 20 time constants
    EXPECT_NE(driver.state().actuator.status & protocol::kExoEnabled, 0);
    EXPECT_EQ(driver.state().actuator_updates, 100U);
    EXPECT_EQ(driver.codec().rejects().total(), 0U);
}

// The link's and the device's timeouts are the device file's can.heartbeat_timeout_ms,
// state_timeout_ms and command_timeout_ms: each test below runs with the shipped values (50,
// 10 and 10 ms) and with others (80, 25 and 20 ms).
config::DeviceConfig exoskeletonWithTimeouts(bool shipped) {
    auto device = exoskeletonDevice();
    if (!shipped) {
        device.can.heartbeat_timeout_ms = 80;
        device.can.state_timeout_ms = 25;
        device.can.command_timeout_ms = 20;
    }
    return device;
}

class ExoskeletonDriverTimeouts : public ::testing::TestWithParam<bool> {};
INSTANTIATE_TEST_SUITE_P(DeviceFile, ExoskeletonDriverTimeouts, ::testing::Values(true, false),
                         [](const auto& info) { return info.param ? "Shipped" : "Changed"; });

TEST_P(ExoskeletonDriverTimeouts, DetectsAStoppedHeartbeatAtTheConfiguredTimeout) {
    const auto device = exoskeletonWithTimeouts(GetParam());
    Rig rig(device, emu::EmulatorMode::kLockstep);
    ExoskeletonDriver driver(device, rig.host);
    for (int i = 0; i < 20; ++i) {
        tick(rig, driver, 0.0);
    }
    rig.fault("heartbeat stop");
    const std::int64_t last_heartbeat = driver.link().lastHeartbeatNs();
    const std::int64_t timeout_ns = device.can.heartbeat_timeout_ms * kMs;
    while (rig.now + kMs - last_heartbeat <= timeout_ns) {
        ASSERT_EQ(tick(rig, driver, 0.0) & kHeartbeatLost, 0U) << "raised early";
    }
    ASSERT_EQ(rig.now - last_heartbeat, timeout_ns);
    EXPECT_NE(tick(rig, driver, 0.0) & kHeartbeatLost, 0U);  // one tick past the timeout
    EXPECT_EQ(driver.faults(rig.now) & kStateStale, 0U);     // state still flows
    rig.fault("heartbeat start");
    for (int i = 0; i < 12; ++i) {
        tick(rig, driver, 0.0);
    }
    EXPECT_EQ(driver.faults(rig.now), 0U);
    EXPECT_EQ(driver.link().heartbeatLossCount(), 1U);
}

TEST_P(ExoskeletonDriverTimeouts, DetectsStaleStateWhenTheDeviceStopsAnswering) {
    const auto device = exoskeletonWithTimeouts(GetParam());
    Rig rig(device, emu::EmulatorMode::kLockstep);
    ExoskeletonDriver driver(device, rig.host);
    tick(rig, driver, 0.0);
    ASSERT_EQ(driver.faults(rig.now), 0U);
    // Lockstep: without commands there are no state frames; heartbeats keep coming.
    for (int i = 0; i < device.can.state_timeout_ms; ++i) {
        rig.advance(kMs);
        driver.poll(rig.now);
        ASSERT_EQ(driver.faults(rig.now), 0U) << "stale after " << i + 1 << " ms";
    }
    rig.advance(kMs);
    driver.poll(rig.now);
    EXPECT_EQ(driver.faults(rig.now), static_cast<std::uint32_t>(kStateStale));
    EXPECT_EQ(driver.link().staleCount(), 1U);
}

// The device's own watchdog, as the real device runs it: stream mode (model on the clock,
// state every tick). Silence past can.command_timeout_ms disables it at 0 N with fault 4; a
// host that resumes with force is ignored until it commands the safe state.
TEST_P(ExoskeletonDriverTimeouts, CommandTimeoutDisablesTheDeviceUntilADisableAcknowledgesIt) {
    const auto device = exoskeletonWithTimeouts(GetParam());
    Rig rig(device, emu::EmulatorMode::kStream);
    ExoskeletonDriver driver(device, rig.host);
    for (int i = 0; i < 50; ++i) {
        tick(rig, driver, 5.0);
    }
    ASSERT_NEAR(driver.state().actuator.force_n, 5.0, 0.2);
    // Silence: enabled with force up to the timeout, limp one tick after it.
    for (int i = 0; i < device.can.command_timeout_ms; ++i) {
        rig.advance(kMs);
        driver.poll(rig.now);
        ASSERT_NE(driver.state().actuator.status & protocol::kExoEnabled, 0U) << i + 1 << " ms";
        ASSERT_FALSE(rig.emulator->commandTimedOut()) << i + 1 << " ms";
    }
    rig.advance(kMs);
    rig.advance(kMs);  // the state frame of the tick after the one that tripped
    driver.poll(rig.now);
    EXPECT_TRUE(rig.emulator->commandTimedOut());
    EXPECT_EQ(driver.state().actuator.force_n, 0.0);
    EXPECT_EQ(driver.state().actuator.status & protocol::kExoEnabled, 0U);
    EXPECT_NE(driver.state().actuator.status & protocol::kExoFaulted, 0U);
    EXPECT_TRUE(driver.state().last_fault.active);
    EXPECT_EQ(driver.state().last_fault.code, protocol::DeviceFaultCode::kCommandTimeout);
    EXPECT_NE(driver.faults(rig.now) & kDeviceFault, 0U);
    // The host wakes up and resumes its force: refused, the device stays limp and faulted.
    for (int i = 0; i < 30; ++i) {
        tick(rig, driver, 5.0);
        ASSERT_EQ(driver.state().actuator.force_n, 0.0) << "tick " << i;
    }
    EXPECT_EQ(driver.state().heartbeat.mode, protocol::DeviceMode::kFault);
    EXPECT_EQ(driver.state().heartbeat.active_fault, 4U);
    // A disable acknowledges: the fault clears, the device stays disabled.
    rig.advance(kMs);
    ASSERT_EQ(driver.sendCommand({0.0, false}), can::IoResult::kOk);
    rig.advance(0);
    driver.poll(rig.now);
    EXPECT_FALSE(rig.emulator->commandTimedOut());
    EXPECT_FALSE(driver.state().last_fault.active);
    // Enabled again by the host, it renders again.
    for (int i = 0; i < 50; ++i) {
        tick(rig, driver, 5.0);
    }
    EXPECT_NEAR(driver.state().actuator.force_n, 5.0, 0.2);
    EXPECT_EQ(rig.emulator->commandTimeouts(), 1U);
}

TEST(ExoskeletonDriver, ReportsDeviceFaultsAndTheirClearing) {
    const auto device = exoskeletonDevice();
    Rig rig(device, emu::EmulatorMode::kLockstep);
    ExoskeletonDriver driver(device, rig.host);
    tick(rig, driver, 2.0);
    rig.fault("fault 1");
    tick(rig, driver, 2.0);
    EXPECT_NE(driver.faults(rig.now) & kDeviceFault, 0U);
    EXPECT_EQ(driver.state().last_fault.code, protocol::DeviceFaultCode::kOvercurrent);
    EXPECT_TRUE(driver.state().last_fault.active);
    EXPECT_NE(driver.state().actuator.status & protocol::kExoFaulted, 0);
    rig.fault("fault 0");
    for (int i = 0; i < 12; ++i) {  // until the next heartbeat says operational
        tick(rig, driver, 2.0);
    }
    EXPECT_EQ(driver.faults(rig.now) & kDeviceFault, 0U);
}

// What was in flight when the device faulted or restarted does not re-arm it: after an
// injected fault clears, or a reboot, enabled commands leave the drive limp until a disable.
TEST(ExoskeletonDriver, AfterAFaultClearsOrARebootOnlyADisableReArmsTheDrive) {
    const auto device = exoskeletonDevice();
    for (const char* event : {"fault 1", "reboot"}) {
        SCOPED_TRACE(event);
        Rig rig(device, emu::EmulatorMode::kStream);
        ExoskeletonDriver driver(device, rig.host);
        for (int i = 0; i < 50; ++i) {
            tick(rig, driver, 5.0);
        }
        ASSERT_NEAR(driver.state().actuator.force_n, 5.0, 0.2);
        rig.fault(event);
        if (std::string(event) == "fault 1") {
            for (int i = 0; i < 5; ++i) {
                tick(rig, driver, 5.0);
            }
            rig.fault("fault 0");
        }
        // The host keeps sending the force it had: refused, the drive stays disabled.
        for (int i = 0; i < 50; ++i) {
            tick(rig, driver, 5.0);
            ASSERT_EQ(driver.state().actuator.status & protocol::kExoEnabled, 0U) << "tick " << i;
        }
        EXPECT_EQ(driver.state().actuator.force_n, 0.0);
        EXPECT_TRUE(rig.emulator->awaitingSafeCommand());
        // A disable re-arms it; then an enable renders again.
        rig.advance(kMs);
        ASSERT_EQ(driver.sendCommand({0.0, false}), can::IoResult::kOk);
        rig.advance(0);
        EXPECT_FALSE(rig.emulator->awaitingSafeCommand());
        for (int i = 0; i < 50; ++i) {
            tick(rig, driver, 5.0);
        }
        EXPECT_NEAR(driver.state().actuator.force_n, 5.0, 0.2);
    }
}

TEST(ExoskeletonDriver, BusOffRefusesCommandsUntilTheControllerRecovers) {
    const auto device = exoskeletonDevice();
    Rig rig(device, emu::EmulatorMode::kLockstep);
    ExoskeletonDriver driver(device, rig.host);
    tick(rig, driver, 0.0);
    rig.fault("busoff");
    rig.advance(kMs);
    driver.poll(rig.now);
    EXPECT_NE(driver.faults(rig.now) & kBusOff, 0U);
    EXPECT_EQ(driver.sendCommand({0.0, true}), can::IoResult::kBusOff);
    EXPECT_NE(driver.faults(rig.now) & kTransmitFailed, 0U);
    rig.fault("recover");
    rig.advance(kMs);
    driver.poll(rig.now);
    EXPECT_EQ(driver.faults(rig.now) & kBusOff, 0U);
    EXPECT_EQ(driver.sendCommand({0.0, true}), can::IoResult::kOk);
}

TEST(ExoskeletonDriver, CountsCorruptedAndLostFramesAndKeepsGoing) {
    const auto device = exoskeletonDevice();
    Rig rig(device, emu::EmulatorMode::kLockstep);
    ExoskeletonDriver driver(device, rig.host);
    tick(rig, driver, 0.0);
    rig.fault("corrupt 2");  // the next actuator and encoder frames
    tick(rig, driver, 0.0);
    EXPECT_EQ(driver.codec().rejects().of(protocol::RejectReason::kBadCrc), 2U);
    tick(rig, driver, 0.0);
    EXPECT_EQ(driver.codec().lostFrames(), 2U);  // the corrupted pair shows up as a gap
    rig.fault("drop 2");
    tick(rig, driver, 0.0);
    tick(rig, driver, 0.0);
    EXPECT_EQ(driver.codec().lostFrames(), 4U);
    EXPECT_EQ(driver.codec().rejects().of(protocol::RejectReason::kCounterJump), 0U);
    EXPECT_EQ(driver.faults(rig.now), 0U);
    // More than kMaxCounterGap missing in a row is a sequence break: rejected, resynchronised.
    rig.fault("drop 6");
    for (int i = 0; i < 4; ++i) {
        tick(rig, driver, 0.0);
    }
    EXPECT_EQ(driver.codec().rejects().of(protocol::RejectReason::kCounterJump), 1U);
}

TEST(ExoskeletonDriver, BackpressureIsReportedNotFatal) {
    const auto device = exoskeletonDevice();
    Rig rig(device, emu::EmulatorMode::kLockstep);
    ExoskeletonDriver driver(device, rig.host);
    tick(rig, driver, 0.0);
    rig.host.injectBackpressure(1);
    EXPECT_EQ(driver.sendCommand({1.0, true}), can::IoResult::kWouldBlock);
    EXPECT_NE(driver.faults(rig.now) & kTransmitFailed, 0U);
    EXPECT_EQ(driver.sendCommand({1.0, true}), can::IoResult::kOk);
    EXPECT_EQ(driver.faults(rig.now) & kTransmitFailed, 0U);
}

TEST(ExoskeletonDriver, RefusesNanCommandsWithoutSending) {
    const auto device = exoskeletonDevice();
    Rig rig(device, emu::EmulatorMode::kLockstep);
    ExoskeletonDriver driver(device, rig.host);
    EXPECT_EQ(driver.sendCommand({std::nan(""), true}), can::IoResult::kInvalid);
    EXPECT_EQ(rig.target.pending(), 0U);
    EXPECT_EQ(driver.codec().encodeRejects(), 1U);
}

TEST(ThimbleDriver, ServosFollowTargetsAtTheRateLimitAndHeartbeatLossIsDetected) {
    const auto device = thimbleDevice();
    Rig rig(device, emu::EmulatorMode::kLockstep);
    ThimbleDriver driver(device, rig.host);
    const double rate = device.thimble().servos.max_rate_rad_per_s;
    // From the retract pose the device powers on at, towards the pad.
    const tactile::ThimbleKinematics kinematics(device.thimble());
    const auto retract = kinematics.inverse(kinematics.retractPose());
    ASSERT_TRUE(retract.ok());
    protocol::ThimbleCommand command{{0.6, 0.6, 0.6}};
    double previous = retract.servo_rad[0];
    for (int i = 0; i < 20; ++i) {
        rig.advance(kMs);
        driver.poll(rig.now);
        ASSERT_EQ(driver.sendCommand(command), can::IoResult::kOk);
        rig.advance(0);
        driver.poll(rig.now);
        const double angle = driver.state().servos.servo_angle_rad[0];
        ASSERT_LE(previous - angle, rate * 1e-3 + 1e-4) << "faster than the rate limit";
        ASSERT_LT(angle, previous);
        previous = angle;
    }
    EXPECT_EQ(driver.faults(rig.now), 0U);
    rig.fault("heartbeat stop");
    for (int i = 0; i < device.can.heartbeat_timeout_ms + 10; ++i) {
        rig.advance(kMs);
        (void)driver.sendCommand(command);
        rig.advance(0);
        driver.poll(rig.now);
    }
    EXPECT_EQ(driver.faults(rig.now), static_cast<std::uint32_t>(kHeartbeatLost));
    EXPECT_EQ(driver.codec().rejects().total(), 0U);
}

TEST(ThimbleDriver, CommandTimeoutRetractsThePlateUntilTheRetractPoseAcknowledgesIt) {
    const auto device = thimbleDevice();
    Rig rig(device, emu::EmulatorMode::kStream);
    ThimbleDriver driver(device, rig.host);
    const tactile::ThimbleKinematics kinematics(device.thimble());
    const auto retract = kinematics.inverse(kinematics.retractPose());
    ASSERT_TRUE(retract.ok());
    const protocol::ThimbleCommand press{{1.2, 1.2, 1.2}};
    const auto send = [&](const protocol::ThimbleCommand& command) {
        rig.advance(kMs);
        driver.poll(rig.now);
        ASSERT_EQ(driver.sendCommand(command), can::IoResult::kOk);
        rig.advance(0);
        driver.poll(rig.now);
    };
    for (int i = 0; i < 500; ++i) {
        send(press);
    }
    ASSERT_NEAR(driver.state().servos.servo_angle_rad[0], 1.2, 1e-3);
    for (int i = 0; i < device.can.command_timeout_ms + 1; ++i) {
        rig.advance(kMs);
    }
    ASSERT_TRUE(rig.emulator->commandTimedOut());
    // Press commands are ignored: the servos run to the retract pose at their rate limit.
    for (int i = 0; i < 500; ++i) {
        send(press);
    }
    driver.poll(rig.now);
    for (std::size_t k = 0; k < 3; ++k) {
        EXPECT_NEAR(driver.state().servos.servo_angle_rad[k], retract.servo_rad[k], 2e-4);
    }
    EXPECT_TRUE(driver.state().last_fault.active);
    EXPECT_EQ(driver.state().last_fault.code, protocol::DeviceFaultCode::kCommandTimeout);
    // Commanding the retract pose acknowledges; the plate follows commands again.
    send(protocol::ThimbleCommand{retract.servo_rad});
    EXPECT_FALSE(rig.emulator->commandTimedOut());
    EXPECT_FALSE(driver.state().last_fault.active);
    for (int i = 0; i < 500; ++i) {
        send(press);
    }
    EXPECT_NEAR(driver.state().servos.servo_angle_rad[0], 1.2, 1e-3);
}

TEST(Drivers, ShareOneBusThroughHandleFrame) {
    const auto exo_device = exoskeletonDevice();
    const auto thimble_device = thimbleDevice();
    can::LoopbackBus host, exo_end, thimble_end;
    host.connect(exo_end);
    host.connect(thimble_end);
    exo_end.connect(thimble_end);
    emu::EmulatorOptions options;
    options.mode = emu::EmulatorMode::kStream;
    auto exo = emu::makeEmulator(exo_device, exo_end, options);
    auto thimble = emu::makeEmulator(thimble_device, thimble_end, options);
    ExoskeletonDriver exo_driver(exo_device, host);
    ThimbleDriver thimble_driver(thimble_device, host);
    std::int64_t now = 5'000 * kMs;
    for (int i = 0; i < 30; ++i) {
        now += kMs;
        for (can::LoopbackBus* bus : {&host, &exo_end, &thimble_end}) {
            bus->setTime(now);
        }
        exo->tick(now);
        thimble->tick(now);
        can::CanFrame frame;
        while (exo_end.read(frame) == can::IoResult::kOk) {
            exo->handleFrame(frame, now);
        }
        while (thimble_end.read(frame) == can::IoResult::kOk) {
            thimble->handleFrame(frame, now);
        }
        while (host.read(frame) == can::IoResult::kOk) {
            const bool claimed =
                exo_driver.handleFrame(frame, now) || thimble_driver.handleFrame(frame, now);
            ASSERT_TRUE(claimed) << "frame 0x" << std::hex << frame.id << " unclaimed";
        }
        (void)exo_driver.sendCommand({1.0, true});
        (void)thimble_driver.sendCommand({{0.5, 0.5, 0.5}});
    }
    EXPECT_EQ(exo_driver.faults(now), 0U);
    EXPECT_EQ(thimble_driver.faults(now), 0U);
    EXPECT_EQ(exo_driver.codec().rejects().total(), 0U);
    EXPECT_EQ(thimble_driver.codec().rejects().total(), 0U);
    EXPECT_GT(exo->commandsAccepted(), 25U);
    EXPECT_GT(thimble->commandsAccepted(), 25U);
}

TEST(Drivers, LoopPathDoesNotAllocate) {
    const auto exo_device = exoskeletonDevice();
    const auto thimble_device = thimbleDevice();
    Rig exo_rig(exo_device, emu::EmulatorMode::kStream);
    Rig thimble_rig(thimble_device, emu::EmulatorMode::kStream);
    ExoskeletonDriver exo(exo_device, exo_rig.host);
    ThimbleDriver thimble(thimble_device, thimble_rig.host);
    exo_rig.fault("drop-every 7");  // exercise the reject and loss paths too
    thimble_rig.fault("corrupt 1000");
    std::uint64_t allocations = 0;
    {
        haptic::testing::ScopedAllocationCounter counter;
        for (int i = 0; i < 5000; ++i) {
            exo_rig.advance(kMs);
            thimble_rig.advance(kMs);
            exo.poll(exo_rig.now);
            thimble.poll(thimble_rig.now);
            (void)exo.faults(exo_rig.now);
            (void)thimble.faults(thimble_rig.now);
            (void)exo.sendCommand({std::sin(i * 0.01), true});
            (void)thimble.sendCommand({{0.3, 0.4, 0.5}});
            (void)exo.sendCommand({std::nan(""), true});
        }
        allocations = counter.allocations();
    }
    EXPECT_EQ(allocations, 0U);
    EXPECT_GT(exo.state().actuator_updates, 4000U);
    EXPECT_GT(exo.codec().lostFrames(), 0U);
    EXPECT_GT(thimble.codec().rejects().of(protocol::RejectReason::kBadCrc), 900U);
}

// Uptime judged against the host's clock: a u32 wrap after 49 days is not a restart, a
// restart is one whatever the uptime was (also in the last days before a wrap).
TEST(LinkMonitor, AnUptimeThatGoesBackIsARestartAWrapIsNot) {
    const auto device = exoskeletonDevice();
    constexpr std::int64_t kMsNs = 1'000'000;
    auto heartbeat = [](std::uint32_t uptime_ms) {
        protocol::Heartbeat h;
        h.uptime_ms = uptime_ms;
        return h;
    };
    LinkMonitor wrapping(device.can);
    wrapping.onHeartbeat(heartbeat(0xFFFFFFF0U), 0);
    wrapping.onHeartbeat(heartbeat(0x00000004U), 20 * kMsNs);  // 20 ms later, wrapped
    EXPECT_EQ(wrapping.rebootCount(), 0U);
    EXPECT_EQ(wrapping.faults(20 * kMsNs, can::BusState::kErrorActive) & kDeviceRebooted, 0U);

    LinkMonitor restarting(device.can);
    restarting.onHeartbeat(heartbeat(0xFFFF0000U), 0);  // days before a wrap
    restarting.onHeartbeat(heartbeat(3), 20 * kMsNs);
    EXPECT_EQ(restarting.rebootCount(), 1U);
    EXPECT_EQ(restarting.uptimeBeforeRebootMs(), 0xFFFF0000U);
    EXPECT_EQ(restarting.uptimeAfterRebootMs(), 3U);
    // Reported once: the daemon latches it.
    EXPECT_NE(restarting.faults(20 * kMsNs, can::BusState::kErrorActive) & kDeviceRebooted, 0U);
    EXPECT_EQ(restarting.faults(21 * kMsNs, can::BusState::kErrorActive) & kDeviceRebooted, 0U);

    LinkMonitor running(device.can);
    for (std::uint32_t t = 0; t < 100; ++t) {
        running.onHeartbeat(heartbeat(5000 + 10 * t), static_cast<std::int64_t>(10 * t) * kMsNs);
    }
    EXPECT_EQ(running.rebootCount(), 0U);
}

// A fault frame followed in the same poll by a heartbeat that names no fault (sent before the
// device faulted) is reported once, not lost to the heartbeat; a fault that lasts stays.
TEST(LinkMonitor, AFaultFrameIsNotLostToAHeartbeatReadInTheSamePoll) {
    const auto device = exoskeletonDevice();
    constexpr std::int64_t kMsNs = 1'000'000;
    LinkMonitor link(device.can);
    protocol::Heartbeat healthy;
    healthy.uptime_ms = 100;
    link.onHeartbeat(healthy, 0);
    EXPECT_EQ(link.faults(0, can::BusState::kErrorActive) & kDeviceFault, 0U);
    protocol::FaultReport fault;
    fault.active = true;
    fault.code = protocol::DeviceFaultCode::kOvercurrent;
    link.onFaultReport(fault);
    healthy.uptime_ms = 101;
    link.onHeartbeat(healthy, 1 * kMsNs);
    EXPECT_NE(link.faults(1 * kMsNs, can::BusState::kErrorActive) & kDeviceFault, 0U);
    EXPECT_EQ(link.lastFaultCode(), 1U) << "what it was, for the fault's message";
    EXPECT_EQ(link.faults(2 * kMsNs, can::BusState::kErrorActive) & kDeviceFault, 0U)
        << "reported once: the daemon latches it";
    link.onFaultReport(fault);
    EXPECT_NE(link.faults(3 * kMsNs, can::BusState::kErrorActive) & kDeviceFault, 0U);
    EXPECT_NE(link.faults(4 * kMsNs, can::BusState::kErrorActive) & kDeviceFault, 0U)
        << "a standing fault stays";
}

}  // namespace
}  // namespace haptic::devices
