#pragma once

// One CAN frame as every bus implementation hands it over: classic (0-8 bytes) or FD (up to
// 64 bytes), with the receive time. Error frames carry the kernel's error-frame layout
// (linux/can/error.h) so that one state tracker serves SocketCAN and the UDP bus.

#include <array>
#include <cstdint>

namespace haptic::can {

inline constexpr std::uint8_t kClassicMaxLength = 8;
inline constexpr std::uint8_t kFdMaxLength = 64;
inline constexpr std::uint32_t kStandardIdMask = 0x7FFU;
inline constexpr std::uint32_t kExtendedIdMask = 0x1FFFFFFFU;

enum FrameFlags : std::uint8_t {
    kFlagExtendedId = 1U << 0,  // 29-bit id
    kFlagFd = 1U << 1,          // CAN FD frame
    kFlagBitRateSwitch = 1U << 2,
    kFlagRemote = 1U << 3,  // RTR (classic only)
    kFlagError = 1U << 4,   // error frame: id holds CAN_ERR_* class bits, data the details
};

struct CanFrame {
    std::uint32_t id{0};  // without flag bits
    std::uint8_t length{0};
    std::uint8_t flags{0};
    std::array<std::uint8_t, kFdMaxLength> data{};
    std::int64_t receive_time_ns{0};  // CLOCK_MONOTONIC when the bus handed it to us

    [[nodiscard]] constexpr bool isFd() const noexcept { return (flags & kFlagFd) != 0; }
    [[nodiscard]] constexpr bool isError() const noexcept { return (flags & kFlagError) != 0; }
    [[nodiscard]] constexpr bool isExtended() const noexcept {
        return (flags & kFlagExtendedId) != 0;
    }
};

// Valid CAN FD payload lengths are 0-8, 12, 16, 20, 24, 32, 48, 64.
[[nodiscard]] constexpr bool isValidFdLength(std::uint8_t length) noexcept {
    return length <= 8 || length == 12 || length == 16 || length == 20 || length == 24 ||
           length == 32 || length == 48 || length == 64;
}

// Structural check shared by every bus: id fits its width, length fits the frame kind.
[[nodiscard]] constexpr bool isWellFormed(const CanFrame& frame) noexcept {
    const std::uint32_t id_mask = frame.isExtended() ? kExtendedIdMask : kStandardIdMask;
    if (!frame.isError() && (frame.id & ~id_mask) != 0) {
        return false;
    }
    if (frame.isFd()) {
        return (frame.flags & kFlagRemote) == 0 && isValidFdLength(frame.length);
    }
    return frame.length <= kClassicMaxLength && (frame.flags & kFlagBitRateSwitch) == 0;
}

}  // namespace haptic::can
