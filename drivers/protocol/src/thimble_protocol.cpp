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
    ThimbleMessage message;
    FrameRole role{};
    if (frame.isError() || frame.isExtended() || !roleOf(frame.id, role)) {
        return message;
    }
    message.type = Type::kRejected;
    RejectReason reason = RejectReason::kOutOfRange;
    if (!admit(frame, role, reason)) {
        message.reason = reason;
        return message;
    }
    reason = RejectReason::kOutOfRange;
    message.counter = frameCounter(frame);
    const std::uint8_t kind = frameKind(frame);
    bool ok = false;
    switch (role) {
        case FrameRole::kCommand:
            if (kind != 0) {
                reason = RejectReason::kUnknownKind;
                break;
            }
            ok = decodeAngles(frame, 0.0, message.command.servo_target_rad);
            message.type = Type::kCommand;
            break;
        case FrameRole::kState:
            if (kind != 0) {
                reason = RejectReason::kUnknownKind;
                break;
            }
            ok = decodeAngles(frame, kAngleMarginRad, message.state.servo_angle_rad);
            message.type = Type::kState;
            break;
        case FrameRole::kHeartbeat:
            ok = decodeHeartbeatPayload(frame, message.heartbeat, reason);
            message.type = Type::kHeartbeat;
            break;
        case FrameRole::kFault:
            ok = decodeFaultPayload(frame, message.fault, reason);
            message.type = Type::kFault;
            break;
    }
    if (!ok) {
        reject(reason);
        message.type = Type::kRejected;
        message.reason = reason;
    }
    return message;
}

}  // namespace haptic::protocol
