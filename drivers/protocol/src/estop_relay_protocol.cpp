#include "haptic/protocol/estop_relay_protocol.hpp"

namespace haptic::protocol {

void encodeEstopStatus(std::uint32_t id, EstopButton button, std::uint8_t counter,
                       can::CanFrame& frame) noexcept {
    frame = blankFrame(id);
    frame.data[2] = static_cast<std::uint8_t>(button);
    frame.data[3] = static_cast<std::uint8_t>(~frame.data[2]);
    sealFrame(frame, 0, counter);
}

namespace {

// Why a frame of the relay's id is not a valid status, kCount when it is (counter aside).
RejectReason payloadReject(const can::CanFrame& frame) noexcept {
    RejectReason reason = RejectReason::kCount;
    if (!checkFrame(frame, reason)) {
        return reason;
    }
    if (frameKind(frame) != 0) {
        return RejectReason::kUnknownKind;
    }
    const std::uint8_t state = frame.data[2];
    if ((state != static_cast<std::uint8_t>(EstopButton::kReleased) &&
         state != static_cast<std::uint8_t>(EstopButton::kPressed)) ||
        frame.data[3] != static_cast<std::uint8_t>(~state)) {
        return RejectReason::kOutOfRange;
    }
    if ((frame.data[4] | frame.data[5] | frame.data[6] | frame.data[7]) != 0) {
        return RejectReason::kReservedNotZero;
    }
    return RejectReason::kCount;
}

}  // namespace

bool EstopRelayDecoder::decode(const can::CanFrame& frame, EstopButton& button) noexcept {
    RejectReason reason = payloadReject(frame);
    if (reason == RejectReason::kCount) {
        switch (sequence_.check(frameCounter(frame))) {
            case SequenceChecker::Result::kRepeated:
                reason = RejectReason::kRepeatedCounter;
                break;
            case SequenceChecker::Result::kJump:
                reason = RejectReason::kCounterJump;
                break;
            case SequenceChecker::Result::kInOrder:
                button = static_cast<EstopButton>(frame.data[2]);
                return true;
        }
    }
    rejects_.count(reason);
    last_reject_ = reason;
    return false;
}

}  // namespace haptic::protocol
