#pragma once

// When hapticd may tell systemd's watchdog that it is alive. The non-RT thread asks, but the
// answer depends on the RT loop: a ping is due only when the loop has ticked since the last
// ping. A wedged RT thread (stuck in a driver, starved by a higher-priority task) therefore
// stops the pings, and systemd restarts the daemon after WatchdogSec, even though the
// thread that talks to systemd is still fine. So does a loop that still ticks but far below
// its rate (fewer than half its ticks over the interval): a loop crawling at a few Hz holds
// the finger with stale forces as surely as a stopped one.

#include <cstdint>

namespace haptic::daemon {

class WatchdogGate {
  public:
    // Pings go out at most every `interval_ns` (half of WatchdogSec, as sd_watchdog_enabled(3)
    // recommends).
    WatchdogGate(std::int64_t interval_ns, double rate_hz) noexcept
        : interval_ns_(interval_ns), rate_hz_(rate_hz) {}

    // True when a ping should be sent now, given the RT loop's tick counter.
    [[nodiscard]] bool pingDue(std::int64_t now_ns, std::uint64_t ticks) noexcept {
        if (started_ && now_ns - last_check_ns_ < interval_ns_) {
            return false;
        }
        const double expected = static_cast<double>(now_ns - last_check_ns_) * 1e-9 * rate_hz_;
        const bool ticked =
            !started_ || (ticks > last_ticks_ &&
                          static_cast<double>(ticks - last_ticks_) >= kMinRateFraction * expected);
        started_ = true;
        last_check_ns_ = now_ns;
        last_ticks_ = ticks;
        return ticked && ticks > 0;
    }

  private:
    static constexpr double kMinRateFraction = 0.5;

    std::int64_t interval_ns_;
    double rate_hz_;
    std::int64_t last_check_ns_{0};
    std::uint64_t last_ticks_{0};
    bool started_{false};
};

}  // namespace haptic::daemon
