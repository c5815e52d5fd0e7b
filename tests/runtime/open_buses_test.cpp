// can.udp_slots in a device file: the size of the UDP port block hapticd's bus (openBuses)
// joins, so how many parties fit on it besides hapticd; two devices on one block must agree.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "haptic/can/udp_bus.hpp"
#include "haptic/config/device.hpp"
#include "haptic/runtime/device_runtime.hpp"

namespace haptic::runtime {
namespace {

using ::testing::HasSubstr;

// Both shipped devices on one UDP block of their own (per test process: ctest runs in
// parallel), with `slots` ports; below the kernel's ephemeral ports and clear of the blocks of
// can_bus_test (10000-13999), udp_round_trip_test (14000-17999) and device_safety_rig
// (18000-27599).
std::vector<config::DeviceConfig> shippedDevicesOnUdp(std::uint16_t slots) {
    const auto port = static_cast<std::uint16_t>(27700 + (::getpid() % 500) * 8);
    std::vector<config::DeviceConfig> devices;
    for (const char* file : {"exoskeleton.yaml", "thimble.yaml"}) {
        auto device = config::loadDeviceConfig(std::string(HAPTIC_CONFIG_DIR) + "/devices/" + file);
        device.can.transport = config::CanTransport::kUdp;
        device.can.udp_port = port;
        device.can.udp_slots = slots;
        devices.push_back(device);
    }
    return devices;
}

// How many more parties join `config`'s block before it is full.
int partiesThatFit(const can::UdpBusConfig& config) {
    std::vector<std::unique_ptr<can::UdpBus>> parties;
    for (;;) {
        try {
            parties.push_back(std::make_unique<can::UdpBus>(config));
        } catch (const std::runtime_error& error) {
            EXPECT_THAT(error.what(), HasSubstr("are taken"));
            return static_cast<int>(parties.size());
        }
    }
}

TEST(OpenBuses, UdpSlotsSizeTheBlockBothDevicesShare) {
    for (const std::uint16_t slots : {3, 6}) {
        const auto devices = shippedDevicesOnUdp(slots);
        const OpenedBuses buses = openBuses(devices);
        ASSERT_EQ(buses.owned.size(), 1U) << "one block, one bus";
        EXPECT_EQ(buses.per_device[0], buses.per_device[1]);
        EXPECT_EQ(buses.descriptions[0],
                  "udp 127.0.0.1:" + std::to_string(devices[0].can.udp_port) + "+" +
                      std::to_string(slots));
        can::UdpBusConfig block;
        block.base_port = devices[0].can.udp_port;
        block.slots = slots;
        EXPECT_EQ(partiesThatFit(block), slots - 1) << "hapticd holds one port of " << slots;
    }
}

TEST(OpenBuses, TwoDevicesOnOneBlockWithDifferentSlotCountsAreRefused) {
    auto devices = shippedDevicesOnUdp(4);
    devices[1].can.udp_slots = 5;
    try {
        (void)openBuses(devices);
        FAIL() << "opened";
    } catch (const std::runtime_error& error) {
        EXPECT_THAT(error.what(), HasSubstr("thimble.yaml: can.udp_slots 5 differs from 4 of "
                                            "another device on UDP port"));
    }
}

}  // namespace
}  // namespace haptic::runtime
