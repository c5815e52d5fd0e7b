// The round-trip scenario over the UDP bus between this process and hapticemu.

#include <gtest/gtest.h>
#include <unistd.h>

#include <string>

#include "emulator_process.hpp"
#include "haptic/can/udp_bus.hpp"
#include "haptic/config/device.hpp"
#include "round_trip.hpp"

namespace haptic::testing {
namespace {

constexpr std::uint16_t kSlots = 4;

// Each test process gets its own port block, so parallel ctest runs never share a bus.
can::UdpBusConfig busForThisProcess() {
    can::UdpBusConfig config;
    config.slots = kSlots;
    config.base_port = static_cast<std::uint16_t>(30000 + (::getpid() % 2000) * kSlots);
    return config;
}

std::vector<std::string> emulatorArgs(const std::string& device_file,
                                      const can::UdpBusConfig& bus) {
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
            "lockstep",
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

}  // namespace
}  // namespace haptic::testing
