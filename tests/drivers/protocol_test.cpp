// Frame layouts and every reject reason, through the codecs' public API.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "device_files.hpp"
#include "haptic/protocol/exoskeleton_protocol.hpp"
#include "haptic/protocol/thimble_protocol.hpp"

namespace haptic::protocol {
namespace {

using testing::exoskeletonDevice;
using testing::thimbleDevice;
using Type = ExoskeletonMessage::Type;

void reseal(can::CanFrame& frame) {
    frame.data[0] = crc8SaeJ1850(frame.id, &frame.data[1]);
}

TEST(FrameCodec, Crc8IsSaeJ1850) {
    // CRC-8/SAE-J1850 of "123456789" is 0x4B. Our CRC covers the id's two bytes first, so
    // feed "12" as the id and "3456789" as bytes 1-7.
    const std::uint8_t rest[] = {'3', '4', '5', '6', '7', '8', '9'};
    EXPECT_EQ(crc8SaeJ1850(static_cast<std::uint32_t>('1' | ('2' << 8)), rest), 0x4B);
}

TEST(SequenceChecker, AcceptsLossUpToTheGapAndRejectsRepeatsAndJumps) {
    SequenceChecker checker;
    EXPECT_EQ(checker.check(14), SequenceChecker::Result::kInOrder);  // first frame syncs
    EXPECT_EQ(checker.check(15), SequenceChecker::Result::kInOrder);
    EXPECT_EQ(checker.check(0), SequenceChecker::Result::kInOrder);  // wraps
    EXPECT_EQ(checker.check(0), SequenceChecker::Result::kRepeated);
    EXPECT_EQ(checker.check(3), SequenceChecker::Result::kInOrder);  // two lost
    EXPECT_EQ(checker.lostFrames(), 2U);
    EXPECT_EQ(checker.check(12), SequenceChecker::Result::kJump);
    EXPECT_EQ(checker.check(13), SequenceChecker::Result::kInOrder);  // resynchronised
}

TEST(ExoskeletonCodec, CommandRoundTripsWithScalingAndCounter) {
    const auto device = exoskeletonDevice();
    ExoskeletonCodec host(device), exo(device);
    can::CanFrame frame;
    ASSERT_TRUE(host.encodeCommand({12.345, true}, frame));
    EXPECT_EQ(frame.id, device.can.command_id);
    EXPECT_EQ(frame.length, 8);
    EXPECT_EQ(getI16(frame, 2), 1235);  // 0.01 N
    const auto message = exo.decode(frame);
    ASSERT_EQ(message.type, Type::kCommand);
    EXPECT_DOUBLE_EQ(message.command.force_n, 12.35);
    EXPECT_TRUE(message.command.enable);
    EXPECT_EQ(message.counter, 0);
    ASSERT_TRUE(host.encodeCommand({-1.0, false}, frame));
    EXPECT_EQ(exo.decode(frame).counter, 1);
}

TEST(ExoskeletonCodec, StateFramesRoundTrip) {
    const auto device = exoskeletonDevice();
    ExoskeletonCodec host(device), exo(device);
    can::CanFrame frame;
    ASSERT_TRUE(
        exo.encodeActuatorState({0.0123456, -3.21, kExoEnabled | kExoAtStrokeMax, 9}, frame));
    auto message = host.decode(frame);
    ASSERT_EQ(message.type, Type::kActuatorState);
    EXPECT_NEAR(message.actuator.stroke_m, 0.012346, 1e-12);
    EXPECT_NEAR(message.actuator.force_n, -3.21, 1e-12);
    EXPECT_EQ(message.actuator.status, kExoEnabled | kExoAtStrokeMax);
    EXPECT_EQ(message.actuator.command_echo, 9);
    ASSERT_TRUE(exo.encodeEncoders({{0.5, 1.0, -0.05}}, frame));
    message = host.decode(frame);
    ASSERT_EQ(message.type, Type::kEncoders);
    EXPECT_NEAR(message.encoders.joint_rad[1], 1.0, 1e-12);
    EXPECT_NEAR(message.encoders.joint_rad[2], -0.05, 1e-12);
    exo.encodeHeartbeat({DeviceMode::kOperational, 0, 123456}, frame);
    message = host.decode(frame);
    ASSERT_EQ(message.type, Type::kHeartbeat);
    EXPECT_EQ(message.heartbeat.uptime_ms, 123456U);
    exo.encodeFault({DeviceFaultCode::kOvercurrent, true, 2500}, frame);
    message = host.decode(frame);
    ASSERT_EQ(message.type, Type::kFault);
    EXPECT_EQ(message.fault.code, DeviceFaultCode::kOvercurrent);
    EXPECT_EQ(message.fault.detail, 2500U);
    EXPECT_EQ(host.rejects().total(), 0U);
}

TEST(ExoskeletonCodec, EncodeRefusesNanInfAndOutOfRange) {
    const auto device = exoskeletonDevice();
    ExoskeletonCodec host(device);
    can::CanFrame frame;
    EXPECT_FALSE(host.encodeCommand({std::numeric_limits<double>::quiet_NaN(), true}, frame));
    EXPECT_FALSE(host.encodeCommand({std::numeric_limits<double>::infinity(), true}, frame));
    EXPECT_FALSE(
        host.encodeCommand({device.exoskeleton().actuator.max_force_n + 0.1, true}, frame));
    EXPECT_FALSE(host.encodeEncoders({{0.0, 0.0, 3.0}}, frame));  // DIP beyond 80 deg + margin
    EXPECT_EQ(host.encodeRejects(), 4U);
    EXPECT_EQ(host.peekCounter(FrameRole::kCommand), 0);  // nothing was consumed
}

TEST(ExoskeletonCodec, EveryRejectReasonIsCounted) {
    const auto device = exoskeletonDevice();
    ExoskeletonCodec host(device), exo(device);
    can::CanFrame good;
    ASSERT_TRUE(exo.encodeActuatorState({0.01, 1.0, 0, 0}, good));
    auto expectReject = [&](can::CanFrame frame, RejectReason reason) {
        const auto message = host.decode(frame);
        EXPECT_EQ(message.type, Type::kRejected) << toString(reason);
        EXPECT_EQ(message.reason, reason) << toString(reason);
    };
    can::CanFrame frame = good;
    frame.length = 7;
    expectReject(frame, RejectReason::kWrongLength);
    frame = good;
    frame.flags = can::kFlagFd;
    expectReject(frame, RejectReason::kWrongFrameType);
    frame = good;
    frame.data[3] ^= 0x40;
    expectReject(frame, RejectReason::kBadCrc);
    frame = good;
    frame.id = device.can.command_id;  // right payload, wrong id: the CRC catches it
    expectReject(frame, RejectReason::kBadCrc);

    ASSERT_EQ(host.decode(good).type, Type::kActuatorState);
    expectReject(good, RejectReason::kRepeatedCounter);

    frame = good;
    frame.data[1] = static_cast<std::uint8_t>((frame.data[1] & 0xF0) | 9);  // 0 -> 9
    reseal(frame);
    expectReject(frame, RejectReason::kCounterJump);

    frame = good;
    frame.data[1] = static_cast<std::uint8_t>(0x70 | 10);  // kind 7
    reseal(frame);
    expectReject(frame, RejectReason::kUnknownKind);

    frame = good;
    frame.data[1] = 11;
    putU16(frame, 2, 60000);  // 60 mm stroke
    reseal(frame);
    expectReject(frame, RejectReason::kOutOfRange);

    frame = good;
    frame.data[1] = 12;
    frame.data[6] = 0x80;  // undefined status bit
    reseal(frame);
    expectReject(frame, RejectReason::kReservedNotZero);

    const RejectCounters& rejects = host.rejects();
    for (std::size_t i = 0; i < static_cast<std::size_t>(RejectReason::kCount); ++i) {
        EXPECT_GE(rejects.by_reason[i], 1U) << toString(static_cast<RejectReason>(i));
    }
    EXPECT_EQ(rejects.total(), 9U);
}

TEST(ExoskeletonCodec, FramesOfOtherDevicesAreNotOurs) {
    const auto exo_device = exoskeletonDevice();
    const auto thimble_device = thimbleDevice();
    ExoskeletonCodec exo(exo_device);
    ThimbleCodec thimble(thimble_device);
    can::CanFrame frame;
    ASSERT_TRUE(thimble.encodeCommand({{0.1, 0.2, 0.3}}, frame));
    EXPECT_EQ(exo.decode(frame).type, Type::kNotForThisDevice);
    EXPECT_EQ(exo.rejects().total(), 0U);
    EXPECT_THROW(ExoskeletonCodec{thimble_device}, std::invalid_argument);
    EXPECT_THROW(ThimbleCodec{exo_device}, std::invalid_argument);
}

TEST(ThimbleCodec, CommandAndStateRoundTripWithinServoLimits) {
    const auto device = thimbleDevice();
    ThimbleCodec host(device), thimble(device);
    can::CanFrame frame;
    ASSERT_TRUE(host.encodeCommand({{-0.5, 0.0, 1.5}}, frame));
    auto message = thimble.decode(frame);
    ASSERT_EQ(message.type, ThimbleMessage::Type::kCommand);
    EXPECT_NEAR(message.command.servo_target_rad[0], -0.5, 1e-12);
    EXPECT_NEAR(message.command.servo_target_rad[2], 1.5, 1e-12);
    ASSERT_TRUE(thimble.encodeState({{0.1, 0.2, 0.3}}, frame));
    message = host.decode(frame);
    ASSERT_EQ(message.type, ThimbleMessage::Type::kState);
    EXPECT_NEAR(message.state.servo_angle_rad[1], 0.2, 1e-12);

    const double max_rad = device.thimble().servos.max_rad;
    EXPECT_FALSE(host.encodeCommand({{0.0, 0.0, max_rad + 0.01}}, frame));
    EXPECT_FALSE(host.encodeCommand({{0.0, std::nan(""), 0.0}}, frame));
    // A command beyond the range that some sender encoded anyway is refused on receipt.
    frame = blankFrame(device.can.command_id);
    putI16(frame, 2, 30000);  // 3 rad
    sealFrame(frame, 0, 1);
    message = thimble.decode(frame);
    EXPECT_EQ(message.type, ThimbleMessage::Type::kRejected);
    EXPECT_EQ(message.reason, RejectReason::kOutOfRange);
}

}  // namespace
}  // namespace haptic::protocol
