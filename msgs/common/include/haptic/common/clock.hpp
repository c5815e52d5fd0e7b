#pragma once

#include <cstdint>
#include <ctime>

namespace haptic::common {

// CLOCK_MONOTONIC in nanoseconds: the one time base of the project. Message stamps, CAN
// receive stamps, driver timeouts and loop deadlines all use it, so stamps taken in different
// processes on one host compare directly. RT-safe: one vDSO call, no allocation, no lock.
[[nodiscard]] inline std::int64_t monotonicNowNs() noexcept {
    timespec now{};
    ::clock_gettime(CLOCK_MONOTONIC, &now);
    return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

}  // namespace haptic::common
