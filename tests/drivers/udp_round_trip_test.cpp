// The round-trip scenario over the UDP bus between this process and hapticemu.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <unistd.h>

#include <string>

#include "emulator_process.hpp"
#include "haptic/can/udp_bus.hpp"
#include "haptic/common/clock.hpp"
#include "haptic/config/device.hpp"
#include "haptic/devices/exoskeleton_driver.hpp"
#include "round_trip.hpp"

namespace haptic::testing {
namespace {

constexpr std::uint16_t kSlots = 4;

// Each test process gets its own port block, so parallel ctest runs never share a bus, and
// below the ephemeral port range (see can_bus_test.cpp's testBlock).
can::UdpBusConfig busForThisProcess() {
    can::UdpBusConfig config;
    config.slots = kSlots;
    config.base_port = static_cast<std::uint16_t>(14000 + (::getpid() % 1000) * kSlots);
    return config;
}

std::vector<std::string> emulatorArgs(const std::string& device_file, const can::UdpBusConfig& bus,
                                      const std::string& mode = "lockstep") {
    return {HAPTICEMU_PATH,
            "-d",
            std::string(HAPTIC_CONFIG_DIR) + "/devices/" + device_file,
            "--bus",
            "udp",
            "--udp-port",
            std::to_string(bus.base_port),
            "--udp-slots",
            std::to_string(bus.slots),
            "--mode",
            mode,
            "--log-level",
            "warn"};
}

TEST(UdpRoundTrip, ExoskeletonDriverAgainstHapticemuProcess) {
    const auto device =
        config::loadDeviceConfig(std::string(HAPTIC_CONFIG_DIR) + "/devices/exoskeleton.yaml");
    const can::UdpBusConfig bus_config = busForThisProcess();
    can::UdpBus bus(bus_config);  // binds first, so the emulator takes another slot
    EmulatorProcess emulator(emulatorArgs("exoskeleton.yaml", bus_config));
    runExoskeletonScenario(bus, device, emulator, kRoundTrips);
    EXPECT_EQ(emulator.stop(), 0) << emulator.output();
}

TEST(UdpRoundTrip, ThimbleDriverAgainstHapticemuProcess) {
    const auto device =
        config::loadDeviceConfig(std::string(HAPTIC_CONFIG_DIR) + "/devices/thimble.yaml");
    const can::UdpBusConfig bus_config = busForThisProcess();
    can::UdpBus bus(bus_config);
    EmulatorProcess emulator(emulatorArgs("thimble.yaml", bus_config));
    runThimbleScenario(bus, device, emulator, kRoundTrips);
    EXPECT_EQ(emulator.stop(), 0) << emulator.output();
}

// Runs the driver's 1 kHz-ish loop against the streaming emulator until `done` holds.
template <typename Done>
bool loopUntil(can::UdpBus& bus, devices::ExoskeletonDriver& driver, Done done,
               protocol::ExoskeletonCommand command = {2.0, true}) {
    const std::int64_t deadline = common::monotonicNowNs() + 5'000'000'000;
    while (common::monotonicNowNs() < deadline) {
        pollfd fd{bus.pollFd(), POLLIN, 0};
        ::poll(&fd, 1, 1);
        const std::int64_t now = common::monotonicNowNs();
        driver.poll(now);
        const std::uint32_t faults = driver.faults(now);
        (void)driver.sendCommand(command);
        if (done(faults)) {
            return true;
        }
    }
    return false;
}

TEST(UdpEmulator, StreamsStateAndAppliesFaultCommandsFromStdin) {
    const auto device =
        config::loadDeviceConfig(std::string(HAPTIC_CONFIG_DIR) + "/devices/exoskeleton.yaml");
    const can::UdpBusConfig bus_config = busForThisProcess();
    can::UdpBus bus(bus_config);
    EmulatorProcess emulator(emulatorArgs("exoskeleton.yaml", bus_config, "stream"));
    devices::ExoskeletonDriver driver(device, bus);
    ASSERT_TRUE(loopUntil(bus, driver, [](std::uint32_t faults) { return faults == 0; }))
        << emulator.output();
    ASSERT_TRUE(loopUntil(bus, driver, [&](std::uint32_t) {
        return driver.state().actuator.force_n > 1.9;  // the lag has settled on the command
    }));

    ASSERT_TRUE(emulator.sendCommand("corrupt 3"));
    EXPECT_TRUE(loopUntil(bus, driver, [&](std::uint32_t) {
        return driver.codec().rejects().of(protocol::RejectReason::kBadCrc) == 3;
    }));
    ASSERT_TRUE(emulator.sendCommand("fault 2"));
    EXPECT_TRUE(loopUntil(bus, driver, [&](std::uint32_t faults) {
        return (faults & devices::kDeviceFault) != 0 &&
               driver.state().last_fault.code == protocol::DeviceFaultCode::kOvertemperature;
    }));
    ASSERT_TRUE(emulator.sendCommand("busoff"));
    EXPECT_TRUE(loopUntil(bus, driver, [](std::uint32_t faults) {
        return (faults & devices::kBusOff) != 0 && (faults & devices::kStateStale) != 0;
    }));
    // The state goes stale (can.state_timeout_ms) about when the device's watchdog
    // (can.command_timeout_ms, as long) fires: hold the bus off for three of those more, well
    // inside the driver's 100 ms before it retries writes, so the device has surely timed out
    // (a clear right away raced its watchdog and, under load, sometimes won).
    const std::int64_t watchdog_passed =
        common::monotonicNowNs() + 3 * std::int64_t{device.can.command_timeout_ms} * 1'000'000;
    ASSERT_TRUE(loopUntil(
        bus, driver, [&](std::uint32_t) { return common::monotonicNowNs() >= watchdog_passed; }));
    ASSERT_TRUE(emulator.sendCommand("clear"));
    // Bus-off kept our commands off the bus for longer than can.command_timeout_ms, so the
    // device went safe on its own (fault 4) and ignores force until a disable acknowledges it.
    EXPECT_TRUE(loopUntil(bus, driver, [&](std::uint32_t faults) {
        return (faults & devices::kDeviceFault) != 0 &&
               driver.state().heartbeat.active_fault ==
                   static_cast<std::uint8_t>(protocol::DeviceFaultCode::kCommandTimeout);
    }));
    EXPECT_TRUE(
        loopUntil(bus, driver, [](std::uint32_t faults) { return faults == 0; }, {0.0, false}));
    EXPECT_TRUE(loopUntil(bus, driver, [&](std::uint32_t) {
        return driver.state().actuator.force_n > 1.9;  // enabled again, rendering again
    }));
    ASSERT_TRUE(emulator.sendCommand("no such fault"));
    EXPECT_TRUE(loopUntil(bus, driver, [&](std::uint32_t) {
        return emulator.output().find("error: unknown fault command 'no such fault'") !=
               std::string::npos;
    }));
    EXPECT_EQ(emulator.stop(), 0);
}

}  // namespace
}  // namespace haptic::testing
