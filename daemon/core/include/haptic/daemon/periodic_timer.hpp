#pragma once

#include <cstdint>
#include <ctime>
#include <string>

#include "haptic/process/cpu_latency.hpp"

namespace haptic::daemon {

// Production refuses to run without real-time scheduling; tests and the demo on a VM opt out
// explicitly (libfranka's kEnforce/kIgnore).
enum class RealtimePolicy { kEnforce, kIgnore };

struct RealtimeSettings {
    RealtimePolicy policy{RealtimePolicy::kEnforce};
    int priority{80};      // SCHED_FIFO priority
    int cpu_affinity{-1};  // core index, or -1 for none
    // The CPUs' wake-up latency to hold (process::CpuLatencyRequest), or -1 for none.
    int cpu_latency_us{-1};
};

struct RealtimeSetupResult {
    bool ok{true};
    std::string report;  // what was applied, or with kIgnore, what was skipped and why
    // Held for as long as the caller keeps it: the request ends with this object.
    process::CpuLatencyRequest cpu_latency;
};

// Applies mlockall, SCHED_FIFO and CPU affinity to the calling thread and makes the CPU
// latency request. With kEnforce any failure is returned as an error (the caller exits); with
// kIgnore failures are reported but the loop runs anyway.
RealtimeSetupResult applyRealtimeSettings(const RealtimeSettings& settings);

// Absolute-time periodic wake-ups on CLOCK_MONOTONIC. Sleeping to an absolute deadline does
// not accumulate drift the way a relative sleep does.
class PeriodicTimer {
  public:
    explicit PeriodicTimer(std::int64_t period_ns) noexcept;

    // Sets the first deadline one period from now.
    void start() noexcept;
    // Sleeps until the next deadline and returns the wake-up latency in ns (>= 0). If the
    // loop fell more than one period behind, the missed deadlines are skipped rather than
    // run back to back, and counted.
    std::int64_t waitNext() noexcept;

    [[nodiscard]] std::int64_t periodNs() const noexcept { return period_ns_; }
    [[nodiscard]] std::uint64_t skippedDeadlines() const noexcept { return skipped_; }
    [[nodiscard]] std::int64_t deadlineNs() const noexcept;

  private:
    std::int64_t period_ns_;
    timespec deadline_{};
    std::uint64_t skipped_{0};
};

}  // namespace haptic::daemon
