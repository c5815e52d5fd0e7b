// Tests on a real kernel CAN stack (vcan0). Run through guest/socketcan_guest.sh, which
// provides vcan0 on a lab PC or inside a qemu guest. Run by hand without vcan0, every test
// fails with the reason: a missing CAN stack must never look like a pass.

#include <gtest/gtest.h>
#include <poll.h>

#include <cstdlib>
#include <string>

#include "emulator_process.hpp"
#include "haptic/can/socketcan_bus.hpp"
#include "haptic/config/device.hpp"
#include "round_trip.hpp"

namespace haptic::testing {
namespace {

std::string interfaceName() {
    const char* name = std::getenv("HAPTIC_VCAN");
    return name != nullptr ? name : "vcan0";
}

std::string deviceFile(const std::string& name) {
    return std::string(HAPTIC_CONFIG_DIR) + "/devices/" + name;
}

can::SocketCanConfig busConfig(const config::DeviceConfig& device, bool fd = false) {
    can::SocketCanConfig config;
    config.interface = interfaceName();
    config.fd = fd;
    // The host side listens to what the device sends.
    config.receive_ids = {device.can.state_id, device.can.heartbeat_id, device.can.fault_id};
    return config;
}

bool readWithin(can::CanBus& bus, can::CanFrame& frame) {
    for (int i = 0; i < 200; ++i) {
        if (bus.read(frame) == can::IoResult::kOk) {
            return true;
        }
        pollfd fd{bus.pollFd(), POLLIN, 0};
        ::poll(&fd, 1, 10);
    }
    return false;
}

class SocketCan : public ::testing::Test {
  protected:
    void SetUp() override {
        ASSERT_TRUE(can::SocketCanBus::kernelSupportsCan())
            << "this kernel has no AF_CAN: run me through tests/drivers/guest/socketcan_guest.sh";
    }
};

TEST_F(SocketCan, ExoskeletonDriverAgainstHapticemuProcess) {
    const auto device = config::loadDeviceConfig(deviceFile("exoskeleton.yaml"));
    can::SocketCanBus bus(busConfig(device));
    EmulatorProcess emulator({HAPTICEMU_PATH, "-d", deviceFile("exoskeleton.yaml"), "--bus",
                              "socketcan", "--interface", interfaceName(), "--mode", "lockstep",
                              "--log-level", "warn"});
    runExoskeletonScenario(bus, device, emulator, kRoundTrips);
    EXPECT_EQ(emulator.stop(), 0) << emulator.output();
    EXPECT_EQ(bus.counters().io_errors, 0U);
}

TEST_F(SocketCan, ThimbleDriverAgainstHapticemuProcess) {
    const auto device = config::loadDeviceConfig(deviceFile("thimble.yaml"));
    can::SocketCanBus bus(busConfig(device));
    EmulatorProcess emulator({HAPTICEMU_PATH, "-d", deviceFile("thimble.yaml"), "--bus",
                              "socketcan", "--interface", interfaceName(), "--mode", "lockstep",
                              "--log-level", "warn"});
    runThimbleScenario(bus, device, emulator, kRoundTrips);
    EXPECT_EQ(emulator.stop(), 0) << emulator.output();
}

TEST_F(SocketCan, ReceiveFiltersPassOnlyTheListedIds) {
    can::SocketCanConfig listener_config;
    listener_config.interface = interfaceName();
    listener_config.receive_ids = {0x181};
    can::SocketCanBus listener(listener_config);
    can::SocketCanConfig sender_config;
    sender_config.interface = interfaceName();
    can::SocketCanBus sender(sender_config);
    can::CanFrame frame;
    frame.length = 2;
    frame.id = 0x182;
    ASSERT_EQ(sender.write(frame), can::IoResult::kOk);
    frame.id = 0x181;
    frame.data[1] = 0x5A;
    ASSERT_EQ(sender.write(frame), can::IoResult::kOk);
    can::CanFrame got;
    ASSERT_TRUE(readWithin(listener, got));
    EXPECT_EQ(got.id, 0x181U);
    EXPECT_EQ(got.data[1], 0x5A);
    EXPECT_GT(got.receive_time_ns, 0);
    EXPECT_EQ(listener.read(got), can::IoResult::kWouldBlock);  // 0x182 was filtered out
}

TEST_F(SocketCan, FdAndExtendedFramesPassWhenEnabled) {
    can::SocketCanConfig config;
    config.interface = interfaceName();
    config.fd = true;
    can::SocketCanBus a(config), b(config);
    can::CanFrame frame;
    frame.id = 0x1234567;
    frame.flags = can::kFlagFd | can::kFlagExtendedId | can::kFlagBitRateSwitch;
    frame.length = 64;
    frame.data[63] = 0xA5;
    ASSERT_EQ(a.write(frame), can::IoResult::kOk);
    can::CanFrame got;
    ASSERT_TRUE(readWithin(b, got));
    EXPECT_TRUE(got.isFd());
    EXPECT_TRUE(got.isExtended());
    EXPECT_EQ(got.id, 0x1234567U);
    EXPECT_EQ(got.length, 64);
    EXPECT_EQ(got.data[63], 0xA5);

    can::SocketCanConfig classic_config;
    classic_config.interface = interfaceName();
    can::SocketCanBus classic(classic_config);
    EXPECT_EQ(classic.write(frame), can::IoResult::kInvalid);  // FD not enabled on this socket
}

TEST_F(SocketCan, UnknownInterfaceIsAClearError) {
    can::SocketCanConfig config;
    config.interface = "nosuchcan7";
    EXPECT_THROW(can::SocketCanBus{config}, std::runtime_error);
}

}  // namespace
}  // namespace haptic::testing
