#pragma once

// The E-stop relay's status frame (docs/drivers.md, "E-stop relay"). A safety relay on one of
// the devices' CAN buses sends it every 10 ms, as the heartbeat of the E-stop circuit:
//   byte 0   CRC-8/SAE-J1850 over the id and bytes 1-7 (frame_codec.hpp)
//   byte 1   bits 0-3 alive counter, bits 4-7 kind 0
//   byte 2   0x00 released (the circuit is closed: the devices may be powered), 0x01 pressed
//   byte 3   the bitwise complement of byte 2, as safety protocols send a safety value twice
//   byte 4-7 reserved, 0
// Anything else is rejected and does not count as the relay being heard: a relay that sends
// only rejected frames is silent, and silent is treated as pressed.

#include <cstdint>

#include "haptic/can/frame.hpp"
#include "haptic/protocol/frame_codec.hpp"

namespace haptic::protocol {

enum class EstopButton : std::uint8_t { kReleased = 0x00, kPressed = 0x01 };

void encodeEstopStatus(std::uint32_t id, EstopButton button, std::uint8_t counter,
                       can::CanFrame& frame) noexcept;

// Decodes the relay's status frames of one id: structure, CRC, alive counter, payload.
class EstopRelayDecoder {
  public:
    explicit EstopRelayDecoder(std::uint32_t id) noexcept : id_(id) {}

    [[nodiscard]] std::uint32_t id() const noexcept { return id_; }
    // True and `button` set for a valid frame of this id; false (counted by reason) for a
    // rejected one. A counter jump resynchronises and rejects that one frame.
    bool decode(const can::CanFrame& frame, EstopButton& button) noexcept;
    [[nodiscard]] const RejectCounters& rejects() const noexcept { return rejects_; }
    [[nodiscard]] RejectReason lastReject() const noexcept { return last_reject_; }

  private:
    std::uint32_t id_;
    SequenceChecker sequence_;
    RejectCounters rejects_;
    RejectReason last_reject_{RejectReason::kCount};
};

}  // namespace haptic::protocol
