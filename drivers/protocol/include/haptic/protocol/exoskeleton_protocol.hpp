#pragma once

// Exoskeleton frames (docs/drivers.md has the table). Scaling is fixed by the protocol;
// ids and value limits come from the device YAML.
//   command (host->device, command_id), kind 0:
//     [2-3] force setpoint i16, 0.01 N (|F| <= actuator.max_force_n)
//     [4]   bit 0 enable, other bits reserved 0;  [5-7] reserved 0
//   state (device->host, state_id), kind 0 = actuator:
//     [2-3] stroke u16, 1 um;  [4-5] actuator force i16, 0.01 N
//     [6]   status bits (ExoskeletonStatus);  [7] bits 0-3 counter of the last accepted
//           command, bits 4-7 reserved 0
//   state, kind 1 = encoders: [2-3] MCP, [4-5] PIP, [6-7] DIP, i16, 1e-4 rad
//   heartbeat / fault: see frame_codec.hpp

#include <array>
#include <cstdint>

#include "haptic/config/device.hpp"
#include "haptic/protocol/device_codec.hpp"

namespace haptic::protocol {

inline constexpr double kForceScaleN = 0.01;
inline constexpr double kStrokeScaleM = 1e-6;
inline constexpr double kAngleScaleRad = 1e-4;

struct ExoskeletonCommand {
    double force_n{0.0};  // along the actuator, positive pushes the rod out (finger extension)
    bool enable{false};
};

enum ExoskeletonStatus : std::uint8_t {
    kExoEnabled = 1U << 0,
    kExoFaulted = 1U << 1,
    kExoAtStrokeMin = 1U << 2,
    kExoAtStrokeMax = 1U << 3,
};
inline constexpr std::uint8_t kExoStatusMask = 0x0F;

struct ExoskeletonActuatorState {
    double stroke_m{0.0};
    double force_n{0.0};
    std::uint8_t status{0};
    std::uint8_t command_echo{0};  // counter of the last command the device accepted
};

struct ExoskeletonEncoders {
    std::array<double, 3> joint_rad{};  // MCP, PIP, DIP, flexion positive
};

struct ExoskeletonMessage {
    enum class Type : std::uint8_t {
        kNotForThisDevice,
        kRejected,
        kCommand,
        kActuatorState,
        kEncoders,
        kHeartbeat,
        kFault
    };
    Type type{Type::kNotForThisDevice};
    RejectReason reason{};  // valid when kRejected
    std::uint8_t counter{0};
    ExoskeletonCommand command;
    ExoskeletonActuatorState actuator;
    ExoskeletonEncoders encoders;
    Heartbeat heartbeat;
    FaultReport fault;
};

class ExoskeletonCodec : public DeviceCodecBase {
  public:
    // Throws std::invalid_argument when the device is not an exoskeleton.
    explicit ExoskeletonCodec(const config::DeviceConfig& device);

    // Each returns false (and counts an encode reject) for NaN/Inf or out-of-range values;
    // the frame is then left unusable and must not be sent.
    [[nodiscard]] bool encodeCommand(const ExoskeletonCommand& command,
                                     can::CanFrame& frame) noexcept;
    [[nodiscard]] bool encodeActuatorState(const ExoskeletonActuatorState& state,
                                           can::CanFrame& frame) noexcept;
    [[nodiscard]] bool encodeEncoders(const ExoskeletonEncoders& encoders,
                                      can::CanFrame& frame) noexcept;

    // Decodes any frame; frames with other ids come back as kNotForThisDevice.
    [[nodiscard]] ExoskeletonMessage decode(const can::CanFrame& frame) noexcept;

  private:
    double max_force_n_;
    double stroke_min_m_;
    double stroke_max_m_;
    std::array<config::Interval, 3> joint_limits_rad_;
};

}  // namespace haptic::protocol
