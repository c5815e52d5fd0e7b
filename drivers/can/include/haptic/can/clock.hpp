#pragma once

#include <cstdint>
#include <ctime>

namespace haptic::can {

// CLOCK_MONOTONIC in nanoseconds: the time base of receive stamps and driver timeouts.
[[nodiscard]] inline std::int64_t monotonicNowNs() noexcept {
    timespec now{};
    clock_gettime(CLOCK_MONOTONIC, &now);
    return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

}  // namespace haptic::can
