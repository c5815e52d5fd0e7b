#include "haptic/protocol/exoskeleton_protocol.hpp"

#include <stdexcept>

namespace haptic::protocol {
namespace {

constexpr std::uint8_t kKindActuator = 0;
constexpr std::uint8_t kKindEncoders = 1;

}  // namespace

ExoskeletonCodec::ExoskeletonCodec(const config::DeviceConfig& device)
    : DeviceCodecBase(device.can),
      max_force_n_(device.isExoskeleton() ? device.exoskeleton().actuator.max_force_n : 0.0),
      stroke_min_m_(device.isExoskeleton() ? device.exoskeleton().actuator.stroke_min_m : 0.0),
      stroke_max_m_(device.isExoskeleton() ? device.exoskeleton().actuator.stroke_max_m : 0.0),
      joint_limits_rad_(device.isExoskeleton() ? device.exoskeleton().finger.joint_limits_rad
                                               : std::array<config::Interval, 3>{}) {
    if (!device.isExoskeleton()) {
        throw std::invalid_argument("exoskeleton codec: device '" + device.name +
                                    "' is not an exoskeleton");
    }
}

bool ExoskeletonCodec::encodeCommand(const ExoskeletonCommand& command,
                                     can::CanFrame& frame) noexcept {
    frame = blankFrame(id(FrameRole::kCommand));
    std::int16_t force = 0;
    if (!quantize(command.force_n, -max_force_n_, max_force_n_, kForceScaleN, force)) {
        countEncodeReject();
        frame.length = 0;
        return false;
    }
    putI16(frame, 2, force);
    frame.data[4] = command.enable ? 1 : 0;
    sealFrame(frame, 0, nextCounter(FrameRole::kCommand));
    return true;
}

bool ExoskeletonCodec::encodeActuatorState(const ExoskeletonActuatorState& state,
                                           can::CanFrame& frame) noexcept {
    frame = blankFrame(id(FrameRole::kState));
    std::uint16_t stroke = 0;
    std::int16_t force = 0;
    const double force_limit = max_force_n_ * (1.0 + kForceMarginFraction);
    if (!quantize(state.stroke_m, stroke_min_m_ - kStrokeMarginM, stroke_max_m_ + kStrokeMarginM,
                  kStrokeScaleM, stroke) ||
        !quantize(state.force_n, -force_limit, force_limit, kForceScaleN, force) ||
        (state.status & ~kExoStatusMask) != 0 || state.command_echo > 0x0F) {
        countEncodeReject();
        frame.length = 0;
        return false;
    }
    putU16(frame, 2, stroke);
    putI16(frame, 4, force);
    frame.data[6] = state.status;
    frame.data[7] = state.command_echo;
    sealFrame(frame, kKindActuator, nextCounter(FrameRole::kState));
    return true;
}

bool ExoskeletonCodec::encodeEncoders(const ExoskeletonEncoders& encoders,
                                      can::CanFrame& frame) noexcept {
    frame = blankFrame(id(FrameRole::kState));
    for (int joint = 0; joint < 3; ++joint) {
        std::int16_t angle = 0;
        const config::Interval& limits = joint_limits_rad_[static_cast<std::size_t>(joint)];
        if (!quantize(encoders.joint_rad[static_cast<std::size_t>(joint)],
                      limits.min - kAngleMarginRad, limits.max + kAngleMarginRad, kAngleScaleRad,
                      angle)) {
            countEncodeReject();
            frame.length = 0;
            return false;
        }
        putI16(frame, 2 + 2 * joint, angle);
    }
    sealFrame(frame, kKindEncoders, nextCounter(FrameRole::kState));
    return true;
}

ExoskeletonMessage ExoskeletonCodec::decode(const can::CanFrame& frame) noexcept {
    using Type = ExoskeletonMessage::Type;
    return decodeFrame<ExoskeletonMessage>(frame, [&](FrameRole role, std::uint8_t kind,
                                                      ExoskeletonMessage& message,
                                                      RejectReason& reason) {
        if (role == FrameRole::kCommand) {
            if (kind != 0) {
                reason = RejectReason::kUnknownKind;
                return false;
            }
            if ((frame.data[4] & ~1U) != 0 || frame.data[5] != 0 || frame.data[6] != 0 ||
                frame.data[7] != 0) {
                reason = RejectReason::kReservedNotZero;
                return false;
            }
            message.command.force_n = getI16(frame, 2) * kForceScaleN;
            message.command.enable = (frame.data[4] & 1U) != 0;
            message.type = Type::kCommand;
            // Half a quantisation step of slack: the sender rounded a value inside the limit.
            return message.command.force_n >= -max_force_n_ - kForceScaleN &&
                   message.command.force_n <= max_force_n_ + kForceScaleN;
        }
        if (kind == kKindActuator) {
            if ((frame.data[6] & ~kExoStatusMask) != 0 || (frame.data[7] & 0xF0) != 0) {
                reason = RejectReason::kReservedNotZero;
                return false;
            }
            const double force_limit = max_force_n_ * (1.0 + kForceMarginFraction);
            message.actuator.stroke_m = getU16(frame, 2) * kStrokeScaleM;
            message.actuator.force_n = getI16(frame, 4) * kForceScaleN;
            message.actuator.status = frame.data[6];
            message.actuator.command_echo = frame.data[7];
            message.type = Type::kActuatorState;
            return message.actuator.stroke_m >= stroke_min_m_ - kStrokeMarginM - kStrokeScaleM &&
                   message.actuator.stroke_m <= stroke_max_m_ + kStrokeMarginM + kStrokeScaleM &&
                   message.actuator.force_n >= -force_limit - kForceScaleN &&
                   message.actuator.force_n <= force_limit + kForceScaleN;
        }
        if (kind == kKindEncoders) {
            bool ok = true;
            for (std::size_t joint = 0; joint < 3; ++joint) {
                const double angle =
                    getI16(frame, 2 + 2 * static_cast<int>(joint)) * kAngleScaleRad;
                message.encoders.joint_rad[joint] = angle;
                ok = ok &&
                     angle >= joint_limits_rad_[joint].min - kAngleMarginRad - kAngleScaleRad &&
                     angle <= joint_limits_rad_[joint].max + kAngleMarginRad + kAngleScaleRad;
            }
            message.type = Type::kEncoders;
            return ok;
        }
        reason = RejectReason::kUnknownKind;
        return false;
    });
}

}  // namespace haptic::protocol
