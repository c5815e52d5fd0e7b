#include "haptic/protocol/thimble_protocol.hpp"

#include <stdexcept>

namespace haptic::protocol {

ThimbleCodec::ThimbleCodec(const config::DeviceConfig& device)
    : DeviceCodecBase(device.can),
      servo_min_rad_(device.isThimble() ? device.thimble().servos.min_rad : 0.0),
      servo_max_rad_(device.isThimble() ? device.thimble().servos.max_rad : 0.0) {
    if (!device.isThimble()) {
        throw std::invalid_argument("thimble codec: device '" + device.name + "' is not a thimble");
    }
}

bool ThimbleCodec::encodeAngles(const std::array<double, 3>& angles, double margin_rad,
                                FrameRole role, can::CanFrame& frame) noexcept {
    frame = blankFrame(id(role));
    for (std::size_t servo = 0; servo < 3; ++servo) {
        std::int16_t angle = 0;
        if (!quantize(angles[servo], servo_min_rad_ - margin_rad, servo_max_rad_ + margin_rad,
                      kAngleScaleRad, angle)) {
            countEncodeReject();
            frame.length = 0;
            return false;
        }
        putI16(frame, 2 + 2 * static_cast<int>(servo), angle);
    }
    sealFrame(frame, 0, nextCounter(role));
    return true;
}

bool ThimbleCodec::decodeAngles(const can::CanFrame& frame, double margin_rad,
                                std::array<double, 3>& angles) const noexcept {
    bool ok = true;
    for (std::size_t servo = 0; servo < 3; ++servo) {
        angles[servo] = getI16(frame, 2 + 2 * static_cast<int>(servo)) * kAngleScaleRad;
        // Quantisation may round a limit value by half a step.
        const double tolerance = margin_rad + kAngleScaleRad;
        ok = ok && angles[servo] >= servo_min_rad_ - tolerance &&
             angles[servo] <= servo_max_rad_ + tolerance;
    }
    return ok;
}

bool ThimbleCodec::encodeCommand(const ThimbleCommand& command, can::CanFrame& frame) noexcept {
    return encodeAngles(command.servo_target_rad, 0.0, FrameRole::kCommand, frame);
}

bool ThimbleCodec::encodeState(const ThimbleState& state, can::CanFrame& frame) noexcept {
    return encodeAngles(state.servo_angle_rad, kAngleMarginRad, FrameRole::kState, frame);
}

ThimbleMessage ThimbleCodec::decode(const can::CanFrame& frame) noexcept {
    using Type = ThimbleMessage::Type;
    return decodeFrame<ThimbleMessage>(frame, [&](FrameRole role, std::uint8_t kind,
                                                  ThimbleMessage& message, RejectReason& reason) {
        if (kind != 0) {
            reason = RejectReason::kUnknownKind;
            return false;
        }
        if (role == FrameRole::kCommand) {
            message.type = Type::kCommand;
            return decodeAngles(frame, 0.0, message.command.servo_target_rad);
        }
        message.type = Type::kState;
        return decodeAngles(frame, kAngleMarginRad, message.state.servo_angle_rad);
    });
}

}  // namespace haptic::protocol
