#include "haptic/can/loopback_bus.hpp"

namespace haptic::can {

bool LoopbackBus::connect(LoopbackBus& other) noexcept {
    if (&other == this || peer_count_ == kMaxPeers || other.peer_count_ == kMaxPeers) {
        return false;
    }
    peers_[peer_count_++] = &other;
    other.peers_[other.peer_count_++] = this;
    return true;
}

bool LoopbackBus::enqueue(const CanFrame& frame) noexcept {
    if (size_ == kQueueCapacity) {
        ++counters_.rx_overflows;
        return false;
    }
    CanFrame& slot = queue_[(head_ + size_) % kQueueCapacity];
    slot = frame;
    slot.receive_time_ns = now_ns_;
    ++size_;
    return true;
}

bool LoopbackBus::injectReceive(const CanFrame& frame) noexcept {
    return enqueue(frame);
}

IoResult LoopbackBus::read(CanFrame& frame) noexcept {
    if (size_ == 0) {
        return IoResult::kWouldBlock;
    }
    frame = queue_[head_];
    head_ = (head_ + 1) % kQueueCapacity;
    --size_;
    if (frame.isError()) {
        ++counters_.rx_error_frames;
        state_.onErrorFrame(frame, now_ns_);
    } else {
        ++counters_.rx_frames;
    }
    return IoResult::kOk;
}

// Error frames are delivered to the peers as if their controllers had reported them: that is
// how the emulator's bus-off fault reaches a driver on a bus without a controller.
IoResult LoopbackBus::write(const CanFrame& frame) noexcept {
    if (!isWellFormed(frame) || (frame.isFd() && !fd_capable_)) {
        ++counters_.tx_refused;
        return IoResult::kInvalid;
    }
    if (!state_.mayTransmit(now_ns_)) {
        ++counters_.tx_refused;
        return IoResult::kBusOff;
    }
    if (backpressure_left_ > 0) {
        --backpressure_left_;
        ++counters_.tx_backpressure;
        return IoResult::kWouldBlock;
    }
    for (std::size_t i = 0; i < peer_count_; ++i) {
        peers_[i]->now_ns_ = now_ns_ > peers_[i]->now_ns_ ? now_ns_ : peers_[i]->now_ns_;
        peers_[i]->enqueue(frame);
    }
    ++counters_.tx_frames;
    return IoResult::kOk;
}

}  // namespace haptic::can
