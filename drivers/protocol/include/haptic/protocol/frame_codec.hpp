#pragma once

// Pieces shared by the exoskeleton and thimble protocols (layouts in docs/drivers.md).
// Every device frame is a classic 8-byte frame:
//   byte 0   CRC-8/SAE-J1850 over the 11-bit id (2 bytes, little-endian) and bytes 1-7
//   byte 1   bits 0-3 alive counter (per id, +1 per frame), bits 4-7 frame kind
//   byte 2-7 payload, little-endian
// The CRC includes the id so that a frame routed to the wrong id is rejected too; the counter
// catches repeated (stuck) and lost frames, as AUTOSAR E2E profile 1 does.

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "haptic/can/frame.hpp"

namespace haptic::protocol {

inline constexpr std::uint8_t kFrameLength = 8;
inline constexpr std::uint8_t kCounterModulo = 16;
// More than this many frames lost in a row counts as a sequence break, not as loss.
inline constexpr std::uint8_t kMaxCounterGap = 4;

enum class RejectReason : std::uint8_t {
    kWrongLength,      // not exactly 8 bytes
    kWrongFrameType,   // FD, remote, extended-id or error frame on a device id
    kBadCrc,           // byte 0 does not match
    kUnknownKind,      // kind nibble not defined for this id
    kRepeatedCounter,  // same counter as the previous frame: stuck sender or duplicate
    kCounterJump,      // more than kMaxCounterGap frames missing; resynchronised
    kOutOfRange,       // a value outside the configured device limits
    kReservedNotZero,  // reserved bits or bytes set
    kCount
};

[[nodiscard]] const char* toString(RejectReason reason) noexcept;

struct RejectCounters {
    std::array<std::uint64_t, static_cast<std::size_t>(RejectReason::kCount)> by_reason{};
    void count(RejectReason reason) noexcept { ++by_reason[static_cast<std::size_t>(reason)]; }
    [[nodiscard]] std::uint64_t of(RejectReason reason) const noexcept {
        return by_reason[static_cast<std::size_t>(reason)];
    }
    [[nodiscard]] std::uint64_t total() const noexcept;
};

[[nodiscard]] std::uint8_t crc8SaeJ1850(std::uint32_t id,
                                        const std::uint8_t* bytes_1_to_7) noexcept;

// Tracks one id's alive counter.
class SequenceChecker {
  public:
    enum class Result : std::uint8_t { kInOrder, kRepeated, kJump };
    // First frame (or after reset) is accepted as is. Lost frames (gap 2..kMaxCounterGap) are
    // accepted and counted.
    Result check(std::uint8_t counter) noexcept;
    void reset() noexcept { synced_ = false; }
    [[nodiscard]] std::uint64_t lostFrames() const noexcept { return lost_; }

  private:
    bool synced_{false};
    std::uint8_t last_{0};
    std::uint64_t lost_{0};
};

// Writes byte 1 and byte 0 (CRC) of a frame whose payload bytes 2-7 are set.
void sealFrame(can::CanFrame& frame, std::uint8_t kind, std::uint8_t counter) noexcept;

// Checks structure and CRC. Returns false and sets `reason` on failure.
[[nodiscard]] bool checkFrame(const can::CanFrame& frame, RejectReason& reason) noexcept;

[[nodiscard]] inline std::uint8_t frameKind(const can::CanFrame& frame) noexcept {
    return static_cast<std::uint8_t>(frame.data[1] >> 4);
}
[[nodiscard]] inline std::uint8_t frameCounter(const can::CanFrame& frame) noexcept {
    return static_cast<std::uint8_t>(frame.data[1] & 0x0F);
}

inline void putU16(can::CanFrame& frame, int offset, std::uint16_t value) noexcept {
    frame.data[offset] = static_cast<std::uint8_t>(value & 0xFF);
    frame.data[offset + 1] = static_cast<std::uint8_t>(value >> 8);
}
inline void putI16(can::CanFrame& frame, int offset, std::int16_t value) noexcept {
    putU16(frame, offset, static_cast<std::uint16_t>(value));
}
inline void putU32(can::CanFrame& frame, int offset, std::uint32_t value) noexcept {
    for (int i = 0; i < 4; ++i) {
        frame.data[offset + i] = static_cast<std::uint8_t>(value >> (8 * i));
    }
}
[[nodiscard]] inline std::uint16_t getU16(const can::CanFrame& frame, int offset) noexcept {
    return static_cast<std::uint16_t>(frame.data[offset] | (frame.data[offset + 1] << 8));
}
[[nodiscard]] inline std::int16_t getI16(const can::CanFrame& frame, int offset) noexcept {
    return static_cast<std::int16_t>(getU16(frame, offset));
}
[[nodiscard]] inline std::uint32_t getU32(const can::CanFrame& frame, int offset) noexcept {
    std::uint32_t value = 0;
    for (int i = 0; i < 4; ++i) {
        value |= static_cast<std::uint32_t>(frame.data[offset + i]) << (8 * i);
    }
    return value;
}

// value / scale rounded to the nearest integer, if finite and inside [lo, hi] and the integer
// range of T. Returns false for NaN/Inf or out of range.
template <typename T>
[[nodiscard]] bool quantize(double value, double lo, double hi, double scale, T& out) noexcept {
    if (!std::isfinite(value) || value < lo || value > hi) {
        return false;
    }
    const double steps = std::round(value / scale);
    if (steps < static_cast<double>(std::numeric_limits<T>::min()) ||
        steps > static_cast<double>(std::numeric_limits<T>::max())) {
        return false;
    }
    out = static_cast<T>(steps);
    return true;
}

// Device lifecycle as reported in the heartbeat.
enum class DeviceMode : std::uint8_t { kBooting = 0, kOperational = 1, kFault = 2 };

struct Heartbeat {
    DeviceMode mode{DeviceMode::kBooting};
    std::uint8_t active_fault{0};  // DeviceFaultCode, 0 when none
    std::uint32_t uptime_ms{0};
};

enum class DeviceFaultCode : std::uint8_t {
    kNone = 0,
    kOvercurrent = 1,
    kOvertemperature = 2,
    kPositionLimit = 3,
    kCommandTimeout = 4,  // the device saw no command for its own timeout and went limp
    kEncoder = 5,
    kInternal = 6,
};
inline constexpr std::uint8_t kMaxDeviceFaultCode = 6;

struct FaultReport {
    DeviceFaultCode code{DeviceFaultCode::kNone};
    bool active{false};
    std::uint32_t detail{0};  // code-specific (e.g. measured current in mA)
};

// Heartbeat and fault frames have the same layout on both devices:
//   heartbeat kind 0: [2] DeviceMode, [3] active DeviceFaultCode, [4-7] uptime ms u32
//   fault     kind 0: [2] DeviceFaultCode (1-6), [3] 1 active / 0 cleared, [4-7] detail u32
void encodeHeartbeat(std::uint32_t id, const Heartbeat& heartbeat, std::uint8_t counter,
                     can::CanFrame& frame) noexcept;
void encodeFault(std::uint32_t id, const FaultReport& fault, std::uint8_t counter,
                 can::CanFrame& frame) noexcept;
// Payload checks only; structure/CRC/sequence are the caller's.
[[nodiscard]] bool decodeHeartbeatPayload(const can::CanFrame& frame, Heartbeat& out,
                                          RejectReason& reason) noexcept;
[[nodiscard]] bool decodeFaultPayload(const can::CanFrame& frame, FaultReport& out,
                                      RejectReason& reason) noexcept;

// Starts an 8-byte standard frame with zero payload.
[[nodiscard]] inline can::CanFrame blankFrame(std::uint32_t id) noexcept {
    can::CanFrame frame;
    frame.id = id;
    frame.length = kFrameLength;
    return frame;
}

}  // namespace haptic::protocol
