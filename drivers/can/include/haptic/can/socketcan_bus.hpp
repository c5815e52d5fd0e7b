#pragma once

// Raw CAN_RAW socket on a SocketCAN interface (can0, vcan0, ...), non-blocking.
// - Receive filters: only the listed ids reach read(); an empty list receives everything.
// - Error frames are enabled (all classes) and update the bus state, so a driver sees
//   warning / passive / bus-off as the controller reports them.
// - EAGAIN/ENOBUFS on write is back-pressure (the qdisc or the controller queue is full):
//   write() returns kWouldBlock and counts it, the caller decides whether to drop or retry.
// - Frames the kernel dropped because we read too slowly are counted (SO_RXQ_OVFL).
// - Bus-off: writes are refused per RecoveryPolicy until the controller reports a restart.
//   Restarting the controller itself is the interface's job (`ip link set can0 type can
//   restart-ms 100`); we never need CAP_NET_ADMIN.

#include <cstdint>
#include <string>
#include <vector>

#include "haptic/can/bus.hpp"

namespace haptic::can {

struct SocketCanConfig {
    std::string interface;                   // e.g. "can0"
    bool fd{false};                          // enable CAN FD frames (interface MTU 72)
    std::vector<std::uint32_t> receive_ids;  // standard 11-bit ids; empty: everything
    RecoveryPolicy recovery{};
};

class SocketCanBus final : public CanBus {
  public:
    // Throws std::runtime_error with the interface name and the OS reason (for example
    // "kernel has no CAN support" when socket(AF_CAN) fails with EAFNOSUPPORT).
    explicit SocketCanBus(const SocketCanConfig& config);
    ~SocketCanBus() override;

    [[nodiscard]] IoResult read(CanFrame& frame) noexcept override;
    [[nodiscard]] IoResult write(const CanFrame& frame) noexcept override;
    [[nodiscard]] int pollFd() const noexcept override { return socket_; }
    [[nodiscard]] bool supportsFd() const noexcept override { return fd_; }

    // Whether this kernel can open a CAN_RAW socket at all (false: no AF_CAN).
    [[nodiscard]] static bool kernelSupportsCan() noexcept;

  private:
    int socket_{-1};
    bool fd_{false};
    std::uint32_t last_overflow_count_{0};
};

}  // namespace haptic::can
