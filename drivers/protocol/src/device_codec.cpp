#include "haptic/protocol/device_codec.hpp"

namespace haptic::protocol {

DeviceCodecBase::DeviceCodecBase(const config::CanConfig& can) noexcept
    : ids_{can.command_id, can.state_id, can.heartbeat_id, can.fault_id} {}

std::uint64_t DeviceCodecBase::lostFrames() const noexcept {
    std::uint64_t lost = 0;
    for (const SequenceChecker& checker : rx_sequence_) {
        lost += checker.lostFrames();
    }
    return lost;
}

void DeviceCodecBase::resetSequences() noexcept {
    for (SequenceChecker& checker : rx_sequence_) {
        checker.reset();
    }
}

bool DeviceCodecBase::roleOf(std::uint32_t id, FrameRole& role) const noexcept {
    for (std::size_t i = 0; i < ids_.size(); ++i) {
        if (ids_[i] == id) {
            role = static_cast<FrameRole>(i);
            return true;
        }
    }
    return false;
}

std::uint8_t DeviceCodecBase::nextCounter(FrameRole role) noexcept {
    std::uint8_t& counter = tx_counters_[static_cast<std::size_t>(role)];
    const std::uint8_t current = counter;
    counter = static_cast<std::uint8_t>((counter + 1) % kCounterModulo);
    return current;
}

bool DeviceCodecBase::admit(const can::CanFrame& frame, FrameRole role,
                            RejectReason& reason) noexcept {
    if (!checkFrame(frame, reason)) {
        reject(reason);
        return false;
    }
    switch (rx_sequence_[static_cast<std::size_t>(role)].check(frameCounter(frame))) {
        case SequenceChecker::Result::kInOrder:
            return true;
        case SequenceChecker::Result::kRepeated:
            reason = RejectReason::kRepeatedCounter;
            reject(reason);
            return false;
        case SequenceChecker::Result::kJump:
            reason = RejectReason::kCounterJump;
            reject(reason);
            return false;
    }
    return false;
}

void DeviceCodecBase::encodeHeartbeat(const Heartbeat& heartbeat, can::CanFrame& frame) noexcept {
    protocol::encodeHeartbeat(id(FrameRole::kHeartbeat), heartbeat,
                              nextCounter(FrameRole::kHeartbeat), frame);
}

void DeviceCodecBase::encodeFault(const FaultReport& fault, can::CanFrame& frame) noexcept {
    protocol::encodeFault(id(FrameRole::kFault), fault, nextCounter(FrameRole::kFault), frame);
}

}  // namespace haptic::protocol
