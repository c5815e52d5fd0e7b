#pragma once

// Controller state from error frames, with a recovery policy for bus-off. It reads the
// kernel's error-frame layout (linux/can/error.h), which SocketCAN delivers and which the UDP
// bus carries unchanged, so the same code and tests cover both. vcan never produces error
// frames, so the tests inject them.

#include <cstdint>

#include "haptic/can/frame.hpp"

namespace haptic::can {

// The status shows it as msgs::BusState (haptic/msgs/names.hpp names it); the driver has no
// text of its own.
enum class BusState : std::uint8_t { kErrorActive, kErrorWarning, kErrorPassive, kBusOff };

struct RecoveryPolicy {
    enum class Mode : std::uint8_t {
        // Writes stay refused until the controller reports "restarted" (the kernel's
        // restart-ms, or an operator's `ip link set canX type can restart`).
        kWaitForController,
        // Writes are retried once `retry_after_ns` has passed since bus-off; a real restart
        // still has to come from the controller, this only stops the driver from giving up.
        kRetryAfter,
    };
    Mode mode{Mode::kWaitForController};
    std::int64_t retry_after_ns{100'000'000};
};

class BusStateTracker {
  public:
    BusStateTracker() = default;
    explicit BusStateTracker(RecoveryPolicy policy) noexcept : policy_(policy) {}

    void setPolicy(RecoveryPolicy policy) noexcept { policy_ = policy; }
    // Feeds one error frame (frame.isError()). now_ns: CLOCK_MONOTONIC.
    void onErrorFrame(const CanFrame& frame, std::int64_t now_ns) noexcept;
    // Whether a write may go out now (false while bus-off under the policy).
    [[nodiscard]] bool mayTransmit(std::int64_t now_ns) const noexcept;

    [[nodiscard]] BusState state() const noexcept { return state_; }
    [[nodiscard]] std::uint64_t busOffCount() const noexcept { return bus_off_count_; }
    [[nodiscard]] std::uint64_t restartCount() const noexcept { return restart_count_; }
    [[nodiscard]] std::uint64_t protocolErrorCount() const noexcept { return protocol_errors_; }
    [[nodiscard]] std::uint64_t ackErrorCount() const noexcept { return ack_errors_; }

  private:
    RecoveryPolicy policy_{};
    BusState state_{BusState::kErrorActive};
    std::int64_t bus_off_since_ns_{0};
    std::uint64_t bus_off_count_{0};
    std::uint64_t restart_count_{0};
    std::uint64_t protocol_errors_{0};
    std::uint64_t ack_errors_{0};
};

// Builds the error frame a controller would report; for tests and the emulator's bus-off
// fault. `controller_bits` are CAN_ERR_CRTL_* values for data[1].
[[nodiscard]] CanFrame makeErrorFrame(std::uint32_t class_bits,
                                      std::uint8_t controller_bits = 0) noexcept;

}  // namespace haptic::can
