#pragma once

// In-process bus for unit tests: frames written on one LoopbackBus appear on every bus
// connected to it. Single-threaded by design (no locks); fixed-size queues, so it does not
// allocate after construction. Tests can inject received frames (error frames included)
// and transmit back-pressure, which a virtual CAN interface can never produce.

#include <array>
#include <cstddef>
#include <cstdint>

#include "haptic/can/bus.hpp"

namespace haptic::can {

class LoopbackBus final : public CanBus {
  public:
    static constexpr std::size_t kQueueCapacity = 512;
    static constexpr std::size_t kMaxPeers = 8;

    explicit LoopbackBus(bool fd_capable = true) noexcept : fd_capable_(fd_capable) {}

    // Connects both ways. Returns false when either side has kMaxPeers already.
    bool connect(LoopbackBus& other) noexcept;

    [[nodiscard]] IoResult read(CanFrame& frame) noexcept override;
    [[nodiscard]] IoResult write(const CanFrame& frame) noexcept override;
    [[nodiscard]] int pollFd() const noexcept override { return -1; }
    [[nodiscard]] bool supportsFd() const noexcept override { return fd_capable_; }

    // Queues a frame as if it had arrived from the wire (error frames included).
    bool injectReceive(const CanFrame& frame) noexcept;
    // The next `count` writes report back-pressure, as ENOBUFS would.
    void injectBackpressure(std::uint32_t count) noexcept { backpressure_left_ = count; }
    // Time used for receive stamps and the bus-off policy; tests drive it.
    void setTime(std::int64_t now_ns) noexcept { now_ns_ = now_ns; }
    [[nodiscard]] std::size_t pending() const noexcept { return size_; }

  private:
    bool enqueue(const CanFrame& frame) noexcept;

    bool fd_capable_;
    std::array<CanFrame, kQueueCapacity> queue_{};
    std::size_t head_{0};
    std::size_t size_{0};
    std::array<LoopbackBus*, kMaxPeers> peers_{};
    std::size_t peer_count_{0};
    std::uint32_t backpressure_left_{0};
    std::int64_t now_ns_{0};
};

}  // namespace haptic::can
