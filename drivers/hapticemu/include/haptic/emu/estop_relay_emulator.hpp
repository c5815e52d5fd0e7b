#pragma once

// The E-stop relay on the emulated bus (hapticemu --estop-relay ID): its status frame every
// 10 ms, as the relay's heartbeat, with the button state an operator sets by text command
// (hapticemu's stdin, "estop " and then):
//   press | release   the button
//   silence | resume  stop sending (a cut wire, a dead relay) and start again
//   corrupt N         flip a payload bit in each of the next N frames (breaks the CRC)

#include <cstdint>
#include <string>
#include <string_view>

#include "haptic/can/bus.hpp"
#include "haptic/protocol/estop_relay_protocol.hpp"

namespace haptic::emu {

class EstopRelayEmulator {
  public:
    static constexpr std::int64_t kPeriodNs = 10'000'000;

    explicit EstopRelayEmulator(std::uint32_t status_id) noexcept : status_id_(status_id) {}

    // Sends the status when one is due.
    void tick(can::CanBus& bus, std::int64_t now_ns) noexcept;
    // Applies one command (without the "estop " prefix). False with `error` set if unknown.
    bool command(std::string_view line, std::string& error);

    [[nodiscard]] bool pressed() const noexcept {
        return button_ == protocol::EstopButton::kPressed;
    }
    [[nodiscard]] std::uint64_t framesSent() const noexcept { return sent_; }

  private:
    std::uint32_t status_id_;
    protocol::EstopButton button_{protocol::EstopButton::kReleased};
    bool silent_{false};
    int corrupt_next_{0};
    std::uint8_t counter_{0};
    std::int64_t next_ns_{-1};
    std::uint64_t sent_{0};
};

}  // namespace haptic::emu
