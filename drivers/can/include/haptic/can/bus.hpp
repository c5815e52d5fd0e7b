#pragma once

// The CAN bus interface the drivers use. Every call is non-blocking and noexcept, so the
// 1 kHz loop can call read()/write() directly: no allocation, no locks, no exceptions after
// construction (constructors may throw, they run before the loop starts).
//
// Implementations: SocketCanBus (raw CAN_RAW socket), UdpBus (CAN frames in UDP datagrams on
// loopback, shared by several processes), LoopbackBus (in-process, for unit tests).

#include <cstdint>

#include "haptic/can/bus_state.hpp"
#include "haptic/can/frame.hpp"

namespace haptic::can {

enum class IoResult : std::uint8_t {
    kOk,          // a frame was read / queued for transmission
    kWouldBlock,  // read: nothing pending; write: back-pressure (EAGAIN/ENOBUFS), retry later
    kBusOff,      // write refused: the controller is bus-off and the recovery policy holds it
    kInvalid,     // write refused: the frame is malformed (id width, length, FD on classic bus)
    kError,       // an OS error; counted, the bus stays usable
};

struct BusCounters {
    std::uint64_t rx_frames{0};
    std::uint64_t tx_frames{0};
    std::uint64_t rx_error_frames{0};  // error frames received (controller, bus errors)
    std::uint64_t rx_dropped{0};       // malformed datagrams/frames the bus itself discarded
    std::uint64_t rx_overflows{0};     // frames the OS dropped before we read them
    std::uint64_t tx_backpressure{0};  // write() returned kWouldBlock
    std::uint64_t tx_refused{0};       // kBusOff or kInvalid
    std::uint64_t io_errors{0};        // kError
};

class CanBus {
  public:
    virtual ~CanBus() = default;
    CanBus() = default;
    CanBus(const CanBus&) = delete;
    CanBus& operator=(const CanBus&) = delete;

    // Takes the oldest pending frame. Error frames are returned too (flag kFlagError) after
    // they have updated state().
    [[nodiscard]] virtual IoResult read(CanFrame& frame) noexcept = 0;
    [[nodiscard]] virtual IoResult write(const CanFrame& frame) noexcept = 0;
    // A file descriptor that becomes readable when read() has something, or -1.
    [[nodiscard]] virtual int pollFd() const noexcept = 0;
    [[nodiscard]] virtual bool supportsFd() const noexcept = 0;

    [[nodiscard]] const BusStateTracker& stateTracker() const noexcept { return state_; }
    [[nodiscard]] BusState state() const noexcept { return state_.state(); }
    [[nodiscard]] const BusCounters& counters() const noexcept { return counters_; }

  protected:
    BusStateTracker state_;
    BusCounters counters_;
};

}  // namespace haptic::can
