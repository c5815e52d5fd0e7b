#pragma once

#include <array>
#include <cstdint>

#include "haptic/common/statistics.hpp"
#include "haptic/msgs/messages.hpp"

namespace haptic::daemon {

// Percentiles over a window of loop samples without storing them: the project's RT histogram
// (1 us bins up to 5 ms plus an exact maximum), so the RT thread can keep it.
using MicrosecondHistogram = common::FixedBinHistogram<5000>;

// p50, p99 and max of a window, as haptic/status carries them.
[[nodiscard]] msgs::Percentiles percentilesOf(const MicrosecondHistogram& histogram) noexcept;

// What one tick spent where. The loop measures these with CLOCK_MONOTONIC.
struct TickTiming {
    double wakeup_latency_us{0.0};  // actual wake-up minus the deadline
    double period_us{0.0};          // wake-up minus the previous wake-up
    double read_us{0.0};
    double compute_us{0.0};
    double write_us{0.0};
};

// Windowed loop statistics for haptic/status. "Tick work" is the whole tick, read + compute +
// write; "compute" is only its middle phase. An overrun is a tick whose work ran past the period;
// its cause is whichever of the three took longest, as ros2_control reports it. Counters are
// lifetime, percentiles are per window.
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
    MicrosecondHistogram tick_work_;
};

}  // namespace haptic::daemon
