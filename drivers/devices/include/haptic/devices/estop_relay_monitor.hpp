#pragma once

// The E-stop relay on a device's bus as hapticd's RT thread supervises it: the last valid
// status and how long ago it came. No I/O and no allocation; times are CLOCK_MONOTONIC ns
// passed in by the caller, so tests drive it without waiting.

#include <cstdint>

#include "haptic/can/frame.hpp"
#include "haptic/protocol/estop_relay_protocol.hpp"

namespace haptic::devices {

enum class EstopInput : std::uint8_t {
    kAwaitingFirstStatus,  // nothing valid heard yet, within the timeout of the first evaluate()
    kReleased,             // a valid status within the timeout says released
    kPressed,              // the last valid status says pressed
    kSilent,               // no valid status for the timeout (since the first evaluate() if none)
};

class EstopRelayMonitor {
  public:
    EstopRelayMonitor(std::uint32_t status_id, std::int64_t timeout_ns) noexcept
        : decoder_(status_id), timeout_ns_(timeout_ns) {}

    // True when the frame carries the relay's id, valid or rejected.
    bool handleFrame(const can::CanFrame& frame, std::int64_t now_ns) noexcept;
    // The input as of now. A pressed status holds until a valid released one follows; silence
    // wins over a released status older than the timeout.
    EstopInput evaluate(std::int64_t now_ns) noexcept;

    [[nodiscard]] std::uint32_t statusId() const noexcept { return decoder_.id(); }
    [[nodiscard]] std::int64_t timeoutNs() const noexcept { return timeout_ns_; }
    // When the last valid status came, -1 if never.
    [[nodiscard]] std::int64_t lastStatusNs() const noexcept { return last_status_ns_; }
    [[nodiscard]] const protocol::EstopRelayDecoder& decoder() const noexcept { return decoder_; }

  private:
    protocol::EstopRelayDecoder decoder_;
    std::int64_t timeout_ns_;
    std::int64_t first_evaluate_ns_{-1};
    std::int64_t last_status_ns_{-1};
    protocol::EstopButton button_{protocol::EstopButton::kPressed};
    bool pressed_since_evaluate_{false};  // a pressed status read since the last evaluate()
};

}  // namespace haptic::devices
