#pragma once

// Per-device bookkeeping shared by the exoskeleton and thimble codecs: the four ids from the
// device YAML, a transmit counter and a receive sequence check per id, and the reject
// counters. One codec instance per side of the link (host or device); it is not thread-safe.

#include <array>
#include <cstdint>

#include "haptic/config/device.hpp"
#include "haptic/protocol/frame_codec.hpp"

namespace haptic::protocol {

enum class FrameRole : std::uint8_t { kCommand = 0, kState = 1, kHeartbeat = 2, kFault = 3 };

// Margins applied to *measured* values before they count as out of range: sensors overshoot
// a little near the limits, a value far outside means a broken frame or sensor.
inline constexpr double kStrokeMarginM = 0.001;
inline constexpr double kForceMarginFraction = 0.1;
inline constexpr double kAngleMarginRad = 0.0872664626;  // 5 degrees

class DeviceCodecBase {
  public:
    explicit DeviceCodecBase(const config::CanConfig& can) noexcept;

    [[nodiscard]] const RejectCounters& rejects() const noexcept { return rejects_; }
    [[nodiscard]] std::uint64_t lostFrames() const noexcept;
    [[nodiscard]] std::uint64_t encodeRejects() const noexcept { return encode_rejects_; }
    // After a timeout the peer may have restarted: accept its next counter as is.
    void resetSequences() noexcept;
    [[nodiscard]] std::uint32_t id(FrameRole role) const noexcept {
        return ids_[static_cast<std::size_t>(role)];
    }
    // Which role an id has for this device, or false when the id is not ours.
    [[nodiscard]] bool roleOf(std::uint32_t id, FrameRole& role) const noexcept;

    // Heartbeat and fault frames have the same layout on every device (frame_codec.hpp).
    void encodeHeartbeat(const Heartbeat& heartbeat, can::CanFrame& frame) noexcept;
    void encodeFault(const FaultReport& fault, can::CanFrame& frame) noexcept;

    // The counter the next frame of this role will carry.
    [[nodiscard]] std::uint8_t peekCounter(FrameRole role) const noexcept {
        return tx_counters_[static_cast<std::size_t>(role)];
    }

  protected:
    [[nodiscard]] std::uint8_t nextCounter(FrameRole role) noexcept;
    // Structure, CRC and sequence; counts the reason on failure.
    [[nodiscard]] bool admit(const can::CanFrame& frame, FrameRole role,
                             RejectReason& reason) noexcept;
    void reject(RejectReason reason) noexcept { rejects_.count(reason); }
    void countEncodeReject() noexcept { ++encode_rejects_; }

    // What every device's decode() does around its own payloads: a frame that is not ours
    // stays kNotForThisDevice; admit() (structure, CRC, sequence); heartbeat and fault
    // payloads (one layout for all devices); then `decode_payload(role, kind, message,
    // reason)` for command and state frames, which sets message.type and returns whether the
    // values are acceptable. A failed payload is counted and the message marked kRejected.
    template <typename Message, typename PayloadDecoder>
    [[nodiscard]] Message decodeFrame(const can::CanFrame& frame,
                                      PayloadDecoder&& decode_payload) noexcept {
        using Type = typename Message::Type;
        Message message;
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
        bool ok = false;
        switch (role) {
            case FrameRole::kCommand:
            case FrameRole::kState:
                ok = decode_payload(role, frameKind(frame), message, reason);
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

  private:
    std::array<std::uint32_t, 4> ids_{};
    std::array<std::uint8_t, 4> tx_counters_{};
    std::array<SequenceChecker, 4> rx_sequence_{};
    RejectCounters rejects_{};
    std::uint64_t encode_rejects_{0};
};

}  // namespace haptic::protocol
