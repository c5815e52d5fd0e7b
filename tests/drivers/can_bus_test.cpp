// The bus layer: loopback delivery and injected faults, the bus-state tracker with both
// recovery policies, and the UDP bus between parties on one port block.

#include <arpa/inet.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <linux/can/error.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <vector>

#include "haptic/can/bus_state.hpp"
#include "haptic/can/loopback_bus.hpp"
#include "haptic/can/socketcan_bus.hpp"
#include "haptic/can/udp_bus.hpp"

namespace haptic::can {
namespace {

CanFrame frameWith(std::uint32_t id, std::uint8_t length, std::uint8_t fill) {
    CanFrame frame;
    frame.id = id;
    frame.length = length;
    for (std::uint8_t i = 0; i < length; ++i) {
        frame.data[i] = static_cast<std::uint8_t>(fill + i);
    }
    return frame;
}

TEST(LoopbackBus, DeliversToEveryPeerButNotToTheSender) {
    LoopbackBus a, b, c;
    ASSERT_TRUE(a.connect(b));
    ASSERT_TRUE(a.connect(c));
    a.setTime(42);
    ASSERT_EQ(a.write(frameWith(0x123, 8, 1)), IoResult::kOk);
    CanFrame got;
    ASSERT_EQ(b.read(got), IoResult::kOk);
    EXPECT_EQ(got.id, 0x123U);
    EXPECT_EQ(got.length, 8);
    EXPECT_EQ(got.data[7], 8);
    EXPECT_EQ(got.receive_time_ns, 42);
    EXPECT_EQ(c.read(got), IoResult::kOk);
    EXPECT_EQ(a.read(got), IoResult::kWouldBlock);
    EXPECT_EQ(a.counters().tx_frames, 1U);
    EXPECT_EQ(b.counters().rx_frames, 1U);
}

TEST(LoopbackBus, RefusesMalformedFramesAndFdOnAClassicBus) {
    LoopbackBus classic(false), peer;
    ASSERT_TRUE(classic.connect(peer));
    EXPECT_EQ(classic.write(frameWith(0x800, 8, 0)), IoResult::kInvalid);  // 12-bit id
    EXPECT_EQ(classic.write(frameWith(0x100, 9, 0)), IoResult::kInvalid);
    CanFrame fd = frameWith(0x100, 12, 0);
    fd.flags = kFlagFd;
    EXPECT_EQ(classic.write(fd), IoResult::kInvalid);
    fd.length = 13;  // not an FD length
    EXPECT_EQ(peer.write(fd), IoResult::kInvalid);
    EXPECT_EQ(classic.counters().tx_refused, 3U);
    EXPECT_EQ(peer.pending(), 0U);
}

TEST(LoopbackBus, InjectedBackpressureIsReportedAndCounted) {
    LoopbackBus a, b;
    ASSERT_TRUE(a.connect(b));
    a.injectBackpressure(2);
    EXPECT_EQ(a.write(frameWith(1, 1, 0)), IoResult::kWouldBlock);
    EXPECT_EQ(a.write(frameWith(1, 1, 0)), IoResult::kWouldBlock);
    EXPECT_EQ(a.write(frameWith(1, 1, 0)), IoResult::kOk);
    EXPECT_EQ(a.counters().tx_backpressure, 2U);
    EXPECT_EQ(b.pending(), 1U);
}

TEST(LoopbackBus, QueueOverflowIsCountedNotFatal) {
    LoopbackBus a, b;
    ASSERT_TRUE(a.connect(b));
    for (std::size_t i = 0; i < LoopbackBus::kQueueCapacity + 5; ++i) {
        ASSERT_EQ(a.write(frameWith(1, 1, 0)), IoResult::kOk);
    }
    EXPECT_EQ(b.pending(), LoopbackBus::kQueueCapacity);
    EXPECT_EQ(b.counters().rx_overflows, 5U);
}

TEST(BusStateTracker, FollowsControllerStatesFromErrorFrames) {
    BusStateTracker tracker;
    EXPECT_EQ(tracker.state(), BusState::kErrorActive);
    tracker.onErrorFrame(makeErrorFrame(CAN_ERR_CRTL, CAN_ERR_CRTL_TX_WARNING), 0);
    EXPECT_EQ(tracker.state(), BusState::kErrorWarning);
    tracker.onErrorFrame(makeErrorFrame(CAN_ERR_CRTL, CAN_ERR_CRTL_RX_PASSIVE), 0);
    EXPECT_EQ(tracker.state(), BusState::kErrorPassive);
    tracker.onErrorFrame(
        makeErrorFrame(CAN_ERR_CRTL | CAN_ERR_PROT | CAN_ERR_ACK, CAN_ERR_CRTL_ACTIVE), 0);
    EXPECT_EQ(tracker.state(), BusState::kErrorActive);
    EXPECT_EQ(tracker.protocolErrorCount(), 1U);
    EXPECT_EQ(tracker.ackErrorCount(), 1U);
}

TEST(BusStateTracker, WaitForControllerHoldsWritesUntilRestart) {
    LoopbackBus a, b;
    ASSERT_TRUE(a.connect(b));
    a.setTime(1'000);
    ASSERT_TRUE(a.injectReceive(makeErrorFrame(CAN_ERR_BUSOFF)));
    CanFrame got;
    ASSERT_EQ(a.read(got), IoResult::kOk);
    EXPECT_TRUE(got.isError());
    EXPECT_EQ(a.state(), BusState::kBusOff);
    a.setTime(10'000'000'000);
    EXPECT_EQ(a.write(frameWith(1, 1, 0)), IoResult::kBusOff);
    ASSERT_TRUE(a.injectReceive(makeErrorFrame(CAN_ERR_RESTARTED)));
    ASSERT_EQ(a.read(got), IoResult::kOk);
    EXPECT_EQ(a.state(), BusState::kErrorActive);
    EXPECT_EQ(a.write(frameWith(1, 1, 0)), IoResult::kOk);
    EXPECT_EQ(a.stateTracker().busOffCount(), 1U);
    EXPECT_EQ(a.stateTracker().restartCount(), 1U);
    EXPECT_EQ(a.counters().rx_error_frames, 2U);
}

TEST(BusStateTracker, RetryAfterPolicyReleasesWritesAfterTheDelay) {
    BusStateTracker tracker(
        RecoveryPolicy{RecoveryPolicy::Mode::kRetryAfter, /*retry_after_ns=*/50'000'000});
    tracker.onErrorFrame(makeErrorFrame(CAN_ERR_BUSOFF), 1'000'000'000);
    EXPECT_FALSE(tracker.mayTransmit(1'000'000'000));
    EXPECT_FALSE(tracker.mayTransmit(1'049'999'999));
    EXPECT_TRUE(tracker.mayTransmit(1'050'000'000));
}

TEST(UdpBusWire, EncodesTheDocumentedLayout) {
    CanFrame frame = frameWith(0x1ABCDEF, 3, 0x10);
    frame.flags = kFlagExtendedId;
    std::uint8_t wire[UdpBus::kHeaderSize + kFdMaxLength];
    ASSERT_EQ(UdpBus::encode(frame, 5, wire, sizeof(wire)), 15U);
    const std::uint8_t header[] = {'H',  'C',  'A',  'N',  1,   kFlagExtendedId, 3, 5, 0xEF, 0xCD,
                                   0xAB, 0x01, 0x10, 0x11, 0x12};
    EXPECT_THAT(std::vector<std::uint8_t>(wire, wire + 15), ::testing::ElementsAreArray(header));
    CanFrame back;
    ASSERT_TRUE(UdpBus::decode(wire, 15, back));
    EXPECT_EQ(back.id, frame.id);
    EXPECT_EQ(back.flags, frame.flags);
    EXPECT_EQ(back.length, 3);
    EXPECT_EQ(back.data[2], 0x12);
}

TEST(UdpBusWire, RejectsMalformedDatagrams) {
    CanFrame frame = frameWith(0x100, 8, 0);
    std::uint8_t wire[UdpBus::kHeaderSize + kFdMaxLength];
    const std::size_t size = UdpBus::encode(frame, 0, wire, sizeof(wire));
    CanFrame out;
    EXPECT_FALSE(UdpBus::decode(wire, size - 1, out));  // truncated
    EXPECT_FALSE(UdpBus::decode(wire, 4, out));
    std::uint8_t bad[sizeof(wire)];
    std::copy(wire, wire + size, bad);
    bad[0] = 'X';
    EXPECT_FALSE(UdpBus::decode(bad, size, out));  // magic
    std::copy(wire, wire + size, bad);
    bad[4] = 2;
    EXPECT_FALSE(UdpBus::decode(bad, size, out));  // version
    std::copy(wire, wire + size, bad);
    bad[5] = 0x80;
    EXPECT_FALSE(UdpBus::decode(bad, size, out));  // unknown flag
    std::copy(wire, wire + size, bad);
    bad[9] = 0x08;
    EXPECT_FALSE(UdpBus::decode(bad, size, out));  // 0x800 needs 12 bits
}

// Test port blocks stay below Linux's ephemeral range (32768-60999 by default), where any
// socket bound to port 0 (Fast DDS opens several per participant) could take them first:
// 10000-13999 here, 14000-17999 udp_round_trip_test, 18000-27599 device_safety_test.
UdpBusConfig testBlock(std::uint16_t slots) {
    UdpBusConfig config;
    config.slots = slots;
    config.base_port = static_cast<std::uint16_t>(10000 + (::getpid() % 1000) * 4);
    return config;
}

bool readWithin(UdpBus& bus, CanFrame& frame) {
    for (int i = 0; i < 1000; ++i) {
        if (bus.read(frame) == IoResult::kOk) {
            return true;
        }
        pollfd fd{bus.pollFd(), POLLIN, 0};
        ::poll(&fd, 1, 5);
    }
    return false;
}

TEST(UdpBus, EveryPartySeesEveryOtherPartysFrames) {
    const UdpBusConfig config = testBlock(3);
    UdpBus a(config), b(config), c(config);
    EXPECT_EQ(a.slot(), 0);
    EXPECT_EQ(b.slot(), 1);
    EXPECT_EQ(c.slot(), 2);
    EXPECT_THROW(UdpBus{config}, std::runtime_error);  // block full

    ASSERT_EQ(a.write(frameWith(0x101, 8, 7)), IoResult::kOk);
    CanFrame got;
    ASSERT_TRUE(readWithin(b, got));
    EXPECT_EQ(got.id, 0x101U);
    EXPECT_EQ(got.data[0], 7);
    EXPECT_GT(got.receive_time_ns, 0);
    ASSERT_TRUE(readWithin(c, got));
    CanFrame fd = frameWith(0x181, 64, 0);
    fd.flags = kFlagFd | kFlagBitRateSwitch;
    ASSERT_EQ(c.write(fd), IoResult::kOk);
    ASSERT_TRUE(readWithin(a, got));
    EXPECT_TRUE(got.isFd());
    EXPECT_EQ(got.length, 64);
    EXPECT_EQ(got.data[63], 63);
    ASSERT_TRUE(readWithin(b, got));
    EXPECT_EQ(a.read(got), IoResult::kWouldBlock);  // its own frame never comes back
}

TEST(UdpBus, ADrainReadsMoreFramesThanOneBatchInOrderAndThenReportsEmpty) {
    const UdpBusConfig config = testBlock(2);
    UdpBus reader(config), writer(config);
    constexpr int kFrames = static_cast<int>(UdpBus::kReceiveBatch) * 2 + 5;
    for (int i = 0; i < kFrames; ++i) {
        ASSERT_EQ(writer.write(frameWith(0x100 + i, 8, static_cast<std::uint8_t>(i))),
                  IoResult::kOk);
    }
    std::vector<std::uint32_t> ids;
    CanFrame got;
    for (int round = 0; round < 200 && static_cast<int>(ids.size()) < kFrames; ++round) {
        while (reader.read(got) == IoResult::kOk) {  // one drain, as the drivers do per tick
            ids.push_back(got.id);
        }
        pollfd fd{reader.pollFd(), POLLIN, 0};
        ::poll(&fd, 1, 5);
    }
    ASSERT_EQ(static_cast<int>(ids.size()), kFrames);
    for (int i = 0; i < kFrames; ++i) {
        EXPECT_EQ(ids[i],
                  static_cast<std::uint32_t>(0x100 + i));  // loopback keeps one sender's order
    }
    EXPECT_EQ(reader.counters().rx_frames, static_cast<std::uint64_t>(kFrames));
    EXPECT_EQ(reader.read(got), IoResult::kWouldBlock);
    EXPECT_EQ(reader.read(got), IoResult::kWouldBlock);
    // A frame sent after the bus reported empty is read by the next drain.
    ASSERT_EQ(writer.write(frameWith(0x7FF, 8, 1)), IoResult::kOk);
    ASSERT_TRUE(readWithin(reader, got));
    EXPECT_EQ(got.id, 0x7FFU);
}

TEST(UdpBus, ErrorFramesFromAPeerDriveTheBusState) {
    const UdpBusConfig config = testBlock(2);
    UdpBus driver(config), emulator(config);
    ASSERT_EQ(emulator.write(makeErrorFrame(CAN_ERR_BUSOFF)), IoResult::kOk);
    CanFrame got;
    ASSERT_TRUE(readWithin(driver, got));
    EXPECT_TRUE(got.isError());
    EXPECT_EQ(driver.state(), BusState::kBusOff);
    EXPECT_EQ(driver.write(frameWith(0x101, 8, 0)), IoResult::kBusOff);
}

TEST(UdpBus, ForeignDatagramsOnThePortAreDroppedAndCounted) {
    const UdpBusConfig config = testBlock(2);
    UdpBus bus(config);
    const int sender = ::socket(AF_INET, SOCK_DGRAM, 0);
    ASSERT_GE(sender, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(config.base_port);
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    const char junk[] = "not a frame";
    ASSERT_GT(::sendto(sender, junk, sizeof(junk), 0, reinterpret_cast<sockaddr*>(&address),
                       sizeof(address)),
              0);
    ::close(sender);
    CanFrame got;
    for (int i = 0; i < 200 && bus.counters().rx_dropped == 0; ++i) {
        EXPECT_NE(bus.read(got), IoResult::kOk);
        pollfd fd{bus.pollFd(), POLLIN, 0};
        ::poll(&fd, 1, 5);
    }
    EXPECT_EQ(bus.counters().rx_dropped, 1U);
}

TEST(SocketCanBus, OpeningFailsWithAClearReasonWhenThereIsNoInterface) {
    SocketCanConfig config;
    config.interface = "nosuchcan9";
    try {
        SocketCanBus bus(config);
        FAIL() << "opened a bus on a missing interface";
    } catch (const std::runtime_error& error) {
        const std::string what = error.what();
        EXPECT_THAT(what, ::testing::HasSubstr("socketcan nosuchcan9"));
        if (!SocketCanBus::kernelSupportsCan()) {
            EXPECT_THAT(what, ::testing::HasSubstr("no AF_CAN"));
        }
    }
}

}  // namespace
}  // namespace haptic::can
