#include "haptic/can/bus_state.hpp"

#include <linux/can/error.h>

namespace haptic::can {

void BusStateTracker::onErrorFrame(const CanFrame& frame, std::int64_t now_ns) noexcept {
    if (!frame.isError()) {
        return;
    }
    const std::uint32_t class_bits = frame.id;
    if ((class_bits & CAN_ERR_PROT) != 0) {
        ++protocol_errors_;
    }
    if ((class_bits & CAN_ERR_ACK) != 0) {
        ++ack_errors_;
    }
    if ((class_bits & CAN_ERR_BUSOFF) != 0) {
        if (state_ != BusState::kBusOff) {
            ++bus_off_count_;
            bus_off_since_ns_ = now_ns;
        }
        state_ = BusState::kBusOff;
        return;
    }
    if ((class_bits & CAN_ERR_RESTARTED) != 0) {
        ++restart_count_;
        state_ = BusState::kErrorActive;
    }
    if ((class_bits & CAN_ERR_CRTL) != 0 && frame.length >= 2) {
        const std::uint8_t controller = frame.data[1];
        if ((controller & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) != 0) {
            state_ = BusState::kErrorPassive;
        } else if ((controller & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) != 0) {
            state_ = BusState::kErrorWarning;
        } else if ((controller & CAN_ERR_CRTL_ACTIVE) != 0) {
            state_ = BusState::kErrorActive;
        }
    }
}

bool BusStateTracker::mayTransmit(std::int64_t now_ns) const noexcept {
    if (state_ != BusState::kBusOff) {
        return true;
    }
    return policy_.mode == RecoveryPolicy::Mode::kRetryAfter &&
           now_ns - bus_off_since_ns_ >= policy_.retry_after_ns;
}

CanFrame makeErrorFrame(std::uint32_t class_bits, std::uint8_t controller_bits) noexcept {
    CanFrame frame;
    frame.flags = kFlagError;
    frame.id = class_bits;
    frame.length = CAN_ERR_DLC;
    frame.data[1] = controller_bits;
    return frame;
}

}  // namespace haptic::can
