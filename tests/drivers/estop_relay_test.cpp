// The E-stop relay: its status frame, hapticd's monitor of it and hapticemu's emulation.

#include <gtest/gtest.h>

#include <string>

#include "haptic/can/loopback_bus.hpp"
#include "haptic/devices/estop_relay_monitor.hpp"
#include "haptic/emu/estop_relay_emulator.hpp"
#include "haptic/protocol/estop_relay_protocol.hpp"

namespace haptic {
namespace {

using devices::EstopInput;
using devices::EstopRelayMonitor;
using protocol::EstopButton;
using protocol::RejectReason;

constexpr std::uint32_t kId = 0x0E0;
constexpr std::int64_t kMs = 1'000'000;

can::CanFrame status(EstopButton button, std::uint8_t counter) {
    can::CanFrame frame;
    protocol::encodeEstopStatus(kId, button, counter, frame);
    return frame;
}

TEST(EstopRelayProtocol, AStatusDecodesAndEveryCorruptionIsRejectedByReason) {
    protocol::EstopRelayDecoder decoder(kId);
    EstopButton button = EstopButton::kReleased;
    ASSERT_TRUE(decoder.decode(status(EstopButton::kPressed, 0), button));
    EXPECT_EQ(button, EstopButton::kPressed);
    ASSERT_TRUE(decoder.decode(status(EstopButton::kReleased, 1), button));
    EXPECT_EQ(button, EstopButton::kReleased);

    // The same counter again: a stuck transmitter repeating its last frame.
    EXPECT_FALSE(decoder.decode(status(EstopButton::kReleased, 1), button));
    EXPECT_EQ(decoder.lastReject(), RejectReason::kRepeatedCounter);

    can::CanFrame flipped = status(EstopButton::kReleased, 2);
    flipped.data[2] ^= 0x01;  // "pressed" in the payload, CRC of "released"
    EXPECT_FALSE(decoder.decode(flipped, button));
    EXPECT_EQ(decoder.lastReject(), RejectReason::kBadCrc);

    // A state whose complement does not match, sealed with a valid CRC.
    can::CanFrame single = status(EstopButton::kReleased, 3);
    single.data[3] = 0x00;
    protocol::sealFrame(single, 0, 3);
    EXPECT_FALSE(decoder.decode(single, button));
    EXPECT_EQ(decoder.lastReject(), RejectReason::kOutOfRange);

    can::CanFrame reserved = status(EstopButton::kReleased, 4);
    reserved.data[7] = 1;
    protocol::sealFrame(reserved, 0, 4);
    EXPECT_FALSE(decoder.decode(reserved, button));
    EXPECT_EQ(decoder.lastReject(), RejectReason::kReservedNotZero);

    can::CanFrame short_frame = status(EstopButton::kReleased, 5);
    short_frame.length = 4;
    EXPECT_FALSE(decoder.decode(short_frame, button));
    EXPECT_EQ(decoder.lastReject(), RejectReason::kWrongLength);
    EXPECT_EQ(decoder.rejects().total(), 5U);
    EXPECT_EQ(button, EstopButton::kReleased) << "no rejected frame changed the button";
}

// A short press whose pressed and released statuses are both read in one poll (the loop late
// by a relay period) is reported once, at the next evaluate(); it was lost to the release.
TEST(EstopRelayMonitor, APressAndAReleaseReadInOnePollAreStillAPress) {
    EstopRelayMonitor monitor(kId, 30 * kMs);
    EXPECT_TRUE(monitor.handleFrame(status(EstopButton::kReleased, 0), 0));
    EXPECT_EQ(monitor.evaluate(0), EstopInput::kReleased);
    EXPECT_TRUE(monitor.handleFrame(status(EstopButton::kPressed, 1), 10 * kMs));
    EXPECT_TRUE(monitor.handleFrame(status(EstopButton::kReleased, 2), 20 * kMs));
    EXPECT_EQ(monitor.evaluate(20 * kMs), EstopInput::kPressed);
    EXPECT_EQ(monitor.evaluate(21 * kMs), EstopInput::kReleased) << "reported once";
}

TEST(EstopRelayMonitor, ReleasedWhileHeardPressedUntilReleasedSilentAfterTheTimeout) {
    EstopRelayMonitor monitor(kId, 30 * kMs);
    EXPECT_EQ(monitor.evaluate(0), EstopInput::kAwaitingFirstStatus);
    EXPECT_EQ(monitor.evaluate(30 * kMs), EstopInput::kAwaitingFirstStatus);
    EXPECT_EQ(monitor.evaluate(31 * kMs), EstopInput::kSilent) << "never heard after start";

    EXPECT_TRUE(monitor.handleFrame(status(EstopButton::kReleased, 0), 32 * kMs));
    EXPECT_EQ(monitor.evaluate(32 * kMs), EstopInput::kReleased);
    EXPECT_TRUE(monitor.handleFrame(status(EstopButton::kPressed, 1), 42 * kMs));
    EXPECT_EQ(monitor.evaluate(42 * kMs), EstopInput::kPressed);
    // Frames that are rejected change nothing, but they are the relay's id.
    can::CanFrame corrupt = status(EstopButton::kReleased, 2);
    corrupt.data[0] ^= 0xFF;
    EXPECT_TRUE(monitor.handleFrame(corrupt, 52 * kMs));
    EXPECT_EQ(monitor.evaluate(52 * kMs), EstopInput::kPressed);
    EXPECT_TRUE(monitor.handleFrame(status(EstopButton::kReleased, 3), 62 * kMs));
    EXPECT_EQ(monitor.evaluate(62 * kMs), EstopInput::kReleased);
    EXPECT_EQ(monitor.evaluate(92 * kMs), EstopInput::kReleased);
    EXPECT_EQ(monitor.evaluate(93 * kMs), EstopInput::kSilent) << "released, then nothing";

    can::CanFrame other = status(EstopButton::kPressed, 4);
    other.id = 0x181;
    EXPECT_FALSE(monitor.handleFrame(other, 94 * kMs)) << "another id is not the relay's";
}

TEST(EstopRelayEmulator, SendsEveryTenMsAndObeysItsCommands) {
    can::LoopbackBus relay_side;
    can::LoopbackBus host_side;
    ASSERT_TRUE(relay_side.connect(host_side));
    emu::EstopRelayEmulator relay(kId);
    EstopRelayMonitor monitor(kId, 30 * kMs);
    auto run = [&](std::int64_t from_ms, std::int64_t to_ms) {
        for (std::int64_t t = from_ms; t < to_ms; ++t) {
            relay.tick(relay_side, t * kMs);
            can::CanFrame frame;
            while (host_side.read(frame) == can::IoResult::kOk) {
                EXPECT_TRUE(monitor.handleFrame(frame, t * kMs));
            }
        }
        return monitor.evaluate(to_ms * kMs);
    };
    EXPECT_EQ(run(0, 100), EstopInput::kReleased);
    EXPECT_EQ(relay.framesSent(), 10U);
    std::string error;
    ASSERT_TRUE(relay.command("press", error));
    EXPECT_EQ(run(100, 111), EstopInput::kPressed);
    ASSERT_TRUE(relay.command("release", error));
    EXPECT_EQ(run(111, 122), EstopInput::kReleased);
    ASSERT_TRUE(relay.command("silence", error));
    EXPECT_EQ(run(122, 200), EstopInput::kSilent);
    ASSERT_TRUE(relay.command("resume", error));
    EXPECT_EQ(run(200, 211), EstopInput::kReleased);
    ASSERT_TRUE(relay.command("corrupt 10", error));
    EXPECT_EQ(run(211, 300), EstopInput::kSilent) << "only corrupt frames: silent";
    EXPECT_EQ(monitor.decoder().rejects().of(RejectReason::kBadCrc), 8U);
    EXPECT_FALSE(relay.command("push", error));
    EXPECT_NE(error.find("press"), std::string::npos) << error;
    EXPECT_FALSE(relay.command("corrupt x", error));
}

}  // namespace
}  // namespace haptic
