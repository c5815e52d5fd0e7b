#pragma once

// CAN frames in UDP datagrams on loopback, for machines whose kernel has no SocketCAN.
// A "bus" is a block of `slots` consecutive UDP ports starting at `base_port`; each party
// binds the first free port of the block and sends every frame to all other ports of the
// block, so every party sees every frame but its own, as on a real bus. Ports without a
// listener simply drop the datagram (unconnected UDP reports no error).
//
// Wire format (one frame per datagram, little-endian, exactly 12 + length bytes):
//   0  u8[4] magic "HCAN"
//   4  u8    version (1)
//   5  u8    flags (FrameFlags: 1 extended id, 2 FD, 4 BRS, 8 RTR, 16 error frame)
//   6  u8    payload length (0-8 classic, FD lengths up to 64)
//   7  u8    sender slot (index of the sender's port in the block)
//   8  u32   CAN id (11 or 29 bits; for error frames the CAN_ERR_* class bits)
//   12 u8[length] payload
// Datagrams that do not match are counted in rx_dropped and never reach the caller.
// Receive time is CLOCK_MONOTONIC when read() takes the datagram.
//
// Unlike CAN there is no arbitration and no guaranteed order between different senders.
//
// System calls dominate the cost of this bus in the 1 kHz loop (a few µs each in a VM), so a
// write sends its datagram to all other ports with one sendmmsg(), and read() takes up to
// kReceiveBatch datagrams with one recvmmsg() and hands them out one per call. When a batch
// came back short the socket was empty at that moment, so the next read() after the batch is
// served reports kWouldBlock without asking the kernel again: a drain loop ("read until
// kWouldBlock") costs one system call, and frames that arrive during it are read by the next
// drain, exactly as if they had arrived just after it.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "haptic/can/bus.hpp"

namespace haptic::can {

struct UdpBusConfig {
    std::uint16_t base_port{47000};
    std::uint16_t slots{8};  // parties per bus, at most kMaxSlots
    RecoveryPolicy recovery{};
};

class UdpBus final : public CanBus {
  public:
    static constexpr std::uint16_t kMaxSlots = 32;
    static constexpr std::size_t kHeaderSize = 12;
    static constexpr std::uint8_t kVersion = 1;
    static constexpr std::size_t kReceiveBatch = 16;

    // Binds the first free port of the block. Throws std::runtime_error when none is free.
    explicit UdpBus(const UdpBusConfig& config);
    ~UdpBus() override;

    [[nodiscard]] IoResult read(CanFrame& frame) noexcept override;
    [[nodiscard]] IoResult write(const CanFrame& frame) noexcept override;
    [[nodiscard]] int pollFd() const noexcept override { return socket_; }
    [[nodiscard]] bool supportsFd() const noexcept override { return true; }
    [[nodiscard]] std::uint16_t slot() const noexcept { return slot_; }

    // Wire codec, public so that the fuzz target and tests reach it.
    [[nodiscard]] static std::size_t encode(const CanFrame& frame, std::uint8_t sender_slot,
                                            std::uint8_t* out, std::size_t capacity) noexcept;
    [[nodiscard]] static bool decode(const std::uint8_t* datagram, std::size_t size,
                                     CanFrame& frame) noexcept;

  private:
    // One recvmmsg() into pending_: kOk when at least one datagram was taken (malformed ones
    // are counted and dropped here), else kWouldBlock or kError.
    [[nodiscard]] IoResult receiveBatch() noexcept;

    UdpBusConfig config_;
    int socket_{-1};
    std::uint16_t slot_{0};
    // Datagrams taken by the last recvmmsg() and not yet handed out; decoded on arrival.
    std::array<CanFrame, kReceiveBatch> pending_{};
    std::size_t pending_count_{0};
    std::size_t pending_next_{0};
    bool last_batch_was_short_{false};
};

[[nodiscard]] std::string describe(const UdpBusConfig& config);

}  // namespace haptic::can
