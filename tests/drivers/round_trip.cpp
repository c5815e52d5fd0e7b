#include "round_trip.hpp"

#include <gtest/gtest.h>
#include <poll.h>

#include <cmath>
#include <string>

#include "haptic/common/clock.hpp"
#include "haptic/devices/exoskeleton_driver.hpp"
#include "haptic/devices/thimble_driver.hpp"
#include "haptic/emu/device_models.hpp"
#include "haptic/protocol/exoskeleton_protocol.hpp"
#include "haptic/protocol/thimble_protocol.hpp"

namespace haptic::testing {
namespace {

using common::monotonicNowNs;
constexpr std::int64_t kWaitLimitNs = 5'000'000'000;  // a lost reply, not a slow one
// The emulator's first heartbeat includes its process start, which under ASan inside the
// TCG guest of the SocketCAN test, on a loaded CI machine, has taken more than 5 s.
constexpr std::int64_t kStartupLimitNs = 60'000'000'000;
constexpr double kTickS = 0.001;

// "kBadCrc 1, ..." of a codec's rejected frames, for a failure message.
template <typename Codec>
std::string rejectsByReason(const Codec& codec) {
    std::string text;
    for (std::size_t i = 0; i < static_cast<std::size_t>(protocol::RejectReason::kCount); ++i) {
        const auto reason = static_cast<protocol::RejectReason>(i);
        if (const std::uint64_t n = codec.rejects().of(reason); n > 0) {
            text += std::string(protocol::toString(reason)) + " " + std::to_string(n) + "; ";
        }
    }
    return text;
}

// Polls the bus (blocking in poll(2) up to 1 ms at a time) until `done` or the limit.
template <typename Driver, typename Done>
bool pumpUntil(can::CanBus& bus, Driver& driver, Done done, std::int64_t limit_ns = kWaitLimitNs) {
    const std::int64_t deadline = monotonicNowNs() + limit_ns;
    while (!done()) {
        if (monotonicNowNs() > deadline) {
            return false;
        }
        pollfd fd{bus.pollFd(), POLLIN, 0};
        ::poll(&fd, 1, 1);
        driver.poll(monotonicNowNs());
    }
    return true;
}

// Keeps commanding at about 1 kHz while waiting for `fault` to be raised or cleared.
template <typename Driver, typename Send>
bool commandUntilFault(can::CanBus& bus, Driver& driver, Send send, std::uint32_t fault,
                       bool raised) {
    const std::int64_t deadline = monotonicNowNs() + kWaitLimitNs;
    while (monotonicNowNs() < deadline) {
        send();
        pollfd fd{bus.pollFd(), POLLIN, 0};
        ::poll(&fd, 1, 1);
        const std::int64_t now = monotonicNowNs();
        driver.poll(now);
        if (((driver.faults(now) & fault) != 0) == raised) {
            return true;
        }
    }
    return false;
}

}  // namespace

void runExoskeletonScenario(can::CanBus& bus, const config::DeviceConfig& device,
                            EmulatorProcess& emulator, int round_trips) {
    devices::ExoskeletonDriver driver(device, bus);
    ASSERT_TRUE(pumpUntil(
        bus, driver, [&] { return driver.link().lastHeartbeatNs() != 0; }, kStartupLimitNs))
        << "no heartbeat from hapticemu:\n"
        << emulator.output();

    // The reference: the same model and codecs, fed the commands as the device decodes them.
    emu::ExoskeletonModel model(device);
    protocol::ExoskeletonCodec device_side(device);
    protocol::ExoskeletonCodec expected_encoder(device);
    protocol::ExoskeletonCodec expected_decoder(device);
    const double max_force_n = device.exoskeleton().actuator.max_force_n;

    for (int i = 0; i < round_trips; ++i) {
        protocol::ExoskeletonCommand command;
        command.force_n = 0.9 * max_force_n * std::sin(0.013 * i);
        command.enable = (i % 500) < 450;  // disabled windows exercise the status bit
        const std::uint8_t counter = device_side.peekCounter(protocol::FrameRole::kCommand);
        can::CanFrame sent;
        ASSERT_TRUE(device_side.encodeCommand(command, sent));
        const auto as_received = expected_decoder.decode(sent);
        ASSERT_EQ(as_received.type, protocol::ExoskeletonMessage::Type::kCommand);

        const std::uint64_t before = driver.state().encoder_updates;
        ASSERT_EQ(driver.sendCommand(command), can::IoResult::kOk) << "round trip " << i;
        ASSERT_EQ(driver.lastCommandCounter(), counter);
        ASSERT_TRUE(pumpUntil(bus, driver,
                              [&] {
                                  return driver.state().encoder_updates == before + 1 &&
                                         driver.state().actuator_updates == before + 1;
                              }))
            << "no state for round trip " << i;

        model.step(kTickS, as_received.command.force_n, as_received.command.enable);
        protocol::ExoskeletonActuatorState actuator;
        actuator.stroke_m = model.strokeM();
        actuator.force_n = model.forceN();
        actuator.status =
            static_cast<std::uint8_t>((model.enabled() ? protocol::kExoEnabled : 0) |
                                      (model.atStrokeMin() ? protocol::kExoAtStrokeMin : 0) |
                                      (model.atStrokeMax() ? protocol::kExoAtStrokeMax : 0));
        actuator.command_echo = counter;
        protocol::ExoskeletonEncoders encoders;
        encoders.joint_rad = model.jointRad();
        can::CanFrame expected_frame;
        ASSERT_TRUE(expected_encoder.encodeActuatorState(actuator, expected_frame));
        const auto expected_actuator = expected_decoder.decode(expected_frame).actuator;
        ASSERT_TRUE(expected_encoder.encodeEncoders(encoders, expected_frame));
        const auto expected_encoders = expected_decoder.decode(expected_frame).encoders;

        const devices::ExoskeletonState& state = driver.state();
        ASSERT_EQ(state.actuator.stroke_m, expected_actuator.stroke_m) << "round trip " << i;
        ASSERT_EQ(state.actuator.force_n, expected_actuator.force_n) << "round trip " << i;
        ASSERT_EQ(state.actuator.status, expected_actuator.status) << "round trip " << i;
        ASSERT_EQ(state.actuator.command_echo, counter) << "round trip " << i;
        ASSERT_EQ(state.encoders.joint_rad, expected_encoders.joint_rad) << "round trip " << i;
    }
    EXPECT_EQ(driver.codec().rejects().total(), 0U) << rejectsByReason(driver.codec());
    EXPECT_EQ(driver.codec().lostFrames(), 0U);
    EXPECT_EQ(driver.state().actuator_updates, static_cast<std::uint64_t>(round_trips));
    EXPECT_EQ(driver.faults(monotonicNowNs()) & devices::kHeartbeatLost, 0U);

    // A stopped heartbeat must be reported while state keeps flowing.
    protocol::ExoskeletonCommand hold;
    hold.enable = true;
    auto send = [&] { (void)driver.sendCommand(hold); };
    ASSERT_TRUE(emulator.sendCommand("heartbeat stop"));
    ASSERT_TRUE(commandUntilFault(bus, driver, send, devices::kHeartbeatLost, true))
        << "the driver did not report the stopped heartbeat";
    // State keeps flowing meanwhile: the next answered command shows it fresh while the
    // heartbeat is still lost. (Judged on an answer, not at an arbitrary instant: in the TCG
    // guest under ASan one round trip can take longer than state_timeout_ms.)
    ASSERT_TRUE(commandUntilFault(bus, driver, send, devices::kStateStale, false))
        << "state stopped with the heartbeat";
    EXPECT_NE(driver.faults(monotonicNowNs()) & devices::kHeartbeatLost, 0U);
    EXPECT_EQ(driver.link().heartbeatLossCount(), 1U);
    ASSERT_TRUE(emulator.sendCommand("heartbeat start"));
    ASSERT_TRUE(commandUntilFault(bus, driver, send, devices::kHeartbeatLost, false))
        << "the heartbeat fault did not clear after the heartbeat resumed";
    EXPECT_EQ(driver.codec().rejects().total(), 0U) << rejectsByReason(driver.codec());
}

void runThimbleScenario(can::CanBus& bus, const config::DeviceConfig& device,
                        EmulatorProcess& emulator, int round_trips) {
    devices::ThimbleDriver driver(device, bus);
    ASSERT_TRUE(pumpUntil(
        bus, driver, [&] { return driver.link().lastHeartbeatNs() != 0; }, kStartupLimitNs))
        << "no heartbeat from hapticemu:\n"
        << emulator.output();

    emu::ThimbleModel model(device);
    protocol::ThimbleCodec host_side(device);
    protocol::ThimbleCodec expected_encoder(device);
    protocol::ThimbleCodec expected_decoder(device);
    const config::ServoConfig& servos = device.thimble().servos;
    const double mid = 0.5 * (servos.min_rad + servos.max_rad);
    const double half = 0.5 * (servos.max_rad - servos.min_rad);

    for (int i = 0; i < round_trips; ++i) {
        protocol::ThimbleCommand command;
        for (std::size_t s = 0; s < 3; ++s) {
            command.servo_target_rad[s] = mid + 0.95 * half * std::sin(0.011 * i + 2.0 * s);
        }
        can::CanFrame sent;
        ASSERT_TRUE(host_side.encodeCommand(command, sent));
        const auto as_received = expected_decoder.decode(sent);
        ASSERT_EQ(as_received.type, protocol::ThimbleMessage::Type::kCommand);

        const std::uint64_t before = driver.state().state_updates;
        ASSERT_EQ(driver.sendCommand(command), can::IoResult::kOk) << "round trip " << i;
        ASSERT_TRUE(
            pumpUntil(bus, driver, [&] { return driver.state().state_updates == before + 1; }))
            << "no state for round trip " << i;

        model.step(kTickS, as_received.command.servo_target_rad);
        protocol::ThimbleState expected;
        expected.servo_angle_rad = model.angleRad();
        can::CanFrame expected_frame;
        ASSERT_TRUE(expected_encoder.encodeState(expected, expected_frame));
        const auto decoded = expected_decoder.decode(expected_frame);
        ASSERT_EQ(driver.state().servos.servo_angle_rad, decoded.state.servo_angle_rad)
            << "round trip " << i;
    }
    EXPECT_EQ(driver.codec().rejects().total(), 0U) << rejectsByReason(driver.codec());
    EXPECT_EQ(driver.codec().lostFrames(), 0U);

    protocol::ThimbleCommand hold;
    hold.servo_target_rad.fill(mid);
    auto send = [&] { (void)driver.sendCommand(hold); };
    ASSERT_TRUE(emulator.sendCommand("heartbeat stop"));
    ASSERT_TRUE(commandUntilFault(bus, driver, send, devices::kHeartbeatLost, true))
        << "the driver did not report the stopped heartbeat";
    // State keeps flowing meanwhile (judged on an answer, as for the exoskeleton above).
    ASSERT_TRUE(commandUntilFault(bus, driver, send, devices::kStateStale, false))
        << "state stopped with the heartbeat";
    EXPECT_NE(driver.faults(monotonicNowNs()) & devices::kHeartbeatLost, 0U);
    ASSERT_TRUE(emulator.sendCommand("heartbeat start"));
    ASSERT_TRUE(commandUntilFault(bus, driver, send, devices::kHeartbeatLost, false));
    EXPECT_EQ(driver.codec().rejects().total(), 0U) << rejectsByReason(driver.codec());
}

}  // namespace haptic::testing
