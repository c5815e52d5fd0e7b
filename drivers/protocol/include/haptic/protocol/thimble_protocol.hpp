#pragma once

// Thimble frames (docs/drivers.md has the table). Angles are i16 in 1e-4 rad.
//   command (host->device, command_id), kind 0: [2-3] [4-5] [6-7] servo targets 1-3,
//     each inside [servos.min, servos.max] from the device YAML
//   state (device->host, state_id), kind 0: [2-3] [4-5] [6-7] measured servo angles 1-3,
//     each inside the servo range widened by kAngleMarginRad
//   heartbeat / fault: see frame_codec.hpp

#include <array>
#include <cstdint>

#include "haptic/config/device.hpp"
#include "haptic/protocol/device_codec.hpp"
#include "haptic/protocol/exoskeleton_protocol.hpp"

namespace haptic::protocol {

struct ThimbleCommand {
    std::array<double, 3> servo_target_rad{};
};

struct ThimbleState {
    std::array<double, 3> servo_angle_rad{};
};

struct ThimbleMessage {
    enum class Type : std::uint8_t {
        kNotForThisDevice,
        kRejected,
        kCommand,
        kState,
        kHeartbeat,
        kFault
    };
    Type type{Type::kNotForThisDevice};
    RejectReason reason{};
    std::uint8_t counter{0};
    ThimbleCommand command;
    ThimbleState state;
    Heartbeat heartbeat;
    FaultReport fault;
};

class ThimbleCodec : public DeviceCodecBase {
  public:
    // Throws std::invalid_argument when the device is not a thimble.
    explicit ThimbleCodec(const config::DeviceConfig& device);

    [[nodiscard]] bool encodeCommand(const ThimbleCommand& command, can::CanFrame& frame) noexcept;
    [[nodiscard]] bool encodeState(const ThimbleState& state, can::CanFrame& frame) noexcept;

    [[nodiscard]] ThimbleMessage decode(const can::CanFrame& frame) noexcept;

  private:
    [[nodiscard]] bool encodeAngles(const std::array<double, 3>& angles, double margin_rad,
                                    FrameRole role, can::CanFrame& frame) noexcept;
    [[nodiscard]] bool decodeAngles(const can::CanFrame& frame, double margin_rad,
                                    std::array<double, 3>& angles) const noexcept;

    double servo_min_rad_;
    double servo_max_rad_;
};

}  // namespace haptic::protocol
