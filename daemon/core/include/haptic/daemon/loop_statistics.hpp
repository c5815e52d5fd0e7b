#pragma once

#include <array>
#include <cstdint>

#include "haptic/msgs/messages.hpp"

namespace haptic::daemon {

// Percentiles over a window of samples without storing them: a 1 us histogram up to 5 ms
// plus an exact maximum. Fixed size, no allocation, O(1) per sample, so the RT thread can
// keep it. Values past the last bin count as the last bin and show up in `max`.
class MicrosecondHistogram {
  public:
    static constexpr std::size_t kBins = 5000;

    void add(double microseconds) noexcept;
    void reset() noexcept;
    [[nodiscard]] msgs::Percentiles percentiles() const noexcept;
    [[nodiscard]] std::uint64_t count() const noexcept { return count_; }

  private:
    [[nodiscard]] double quantile(double q) const noexcept;

    std::array<std::uint32_t, kBins> bins_{};
    std::uint64_t count_{0};
    double max_{0.0};
};

// What one tick spent where. The loop measures these with CLOCK_MONOTONIC.
struct TickTiming {
    double wakeup_latency_us{0.0};  // actual wake-up minus the deadline
    double period_us{0.0};          // wake-up minus the previous wake-up
    double read_us{0.0};
    double compute_us{0.0};
    double write_us{0.0};
};

// Windowed loop statistics for haptic/status. An overrun is a tick whose read + compute +
// write ran past the period; its cause is whichever of the three took longest, as
// ros2_control reports it. Counters are lifetime, percentiles are per window.
class LoopStatisticsCollector {
  public:
    explicit LoopStatisticsCollector(double rate_hz) noexcept;

    void add(const TickTiming& timing) noexcept;
    // Fills `out` from the current window and starts a new one.
    void closeWindow(msgs::LoopStatistics& out) noexcept;
    // Fills only the lifetime counters (rate, ticks, overruns), which are live between
    // windows; leaves the percentiles alone.
    void fillCounters(msgs::LoopStatistics& out) const noexcept;
    [[nodiscard]] std::uint64_t windowCount() const noexcept { return period_.count(); }

  private:
    double rate_hz_;
    double period_budget_us_;
    std::uint64_t ticks_{0};
    std::uint64_t overruns_{0};
    std::uint64_t overruns_read_{0};
    std::uint64_t overruns_compute_{0};
    std::uint64_t overruns_write_{0};
    MicrosecondHistogram period_;
    MicrosecondHistogram wakeup_;
    MicrosecondHistogram compute_;
};

}  // namespace haptic::daemon
