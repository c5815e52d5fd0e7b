#include "haptic/daemon/loop_statistics.hpp"

#include <algorithm>
#include <cmath>

namespace haptic::daemon {

void MicrosecondHistogram::add(double microseconds) noexcept {
    if (!std::isfinite(microseconds)) {
        return;
    }
    const double clamped = std::max(0.0, microseconds);
    const auto bin = std::min<std::size_t>(static_cast<std::size_t>(clamped), kBins - 1);
    ++bins_[bin];
    ++count_;
    max_ = std::max(max_, clamped);
}

void MicrosecondHistogram::reset() noexcept {
    bins_.fill(0);
    count_ = 0;
    max_ = 0.0;
}

double MicrosecondHistogram::quantile(double q) const noexcept {
    if (count_ == 0) {
        return 0.0;
    }
    // The smallest bin whose cumulative count reaches q * count; report its upper edge, so a
    // percentile never understates a latency, but never beyond the exact maximum.
    const auto target = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count_)));
    std::uint64_t cumulative = 0;
    for (std::size_t bin = 0; bin < kBins; ++bin) {
        cumulative += bins_[bin];
        if (cumulative >= std::max<std::uint64_t>(target, 1)) {
            // The last bin also holds everything beyond it: only the exact max is honest there.
            return bin + 1 == kBins ? max_ : std::min(static_cast<double>(bin + 1), max_);
        }
    }
    return max_;
}

msgs::Percentiles MicrosecondHistogram::percentiles() const noexcept {
    return {quantile(0.50), quantile(0.99), max_};
}

LoopStatisticsCollector::LoopStatisticsCollector(double rate_hz) noexcept
    : rate_hz_(rate_hz), period_budget_us_(1e6 / rate_hz) {}

void LoopStatisticsCollector::add(const TickTiming& timing) noexcept {
    ++ticks_;
    period_.add(timing.period_us);
    wakeup_.add(timing.wakeup_latency_us);
    const double busy_us = timing.read_us + timing.compute_us + timing.write_us;
    compute_.add(busy_us);
    if (busy_us > period_budget_us_) {
        ++overruns_;
        if (timing.read_us >= timing.compute_us && timing.read_us >= timing.write_us) {
            ++overruns_read_;
        } else if (timing.compute_us >= timing.write_us) {
            ++overruns_compute_;
        } else {
            ++overruns_write_;
        }
    }
}

void LoopStatisticsCollector::fillCounters(msgs::LoopStatistics& out) const noexcept {
    out.rate_hz = rate_hz_;
    out.ticks = ticks_;
    out.overruns = overruns_;
    out.overruns_read = overruns_read_;
    out.overruns_compute = overruns_compute_;
    out.overruns_write = overruns_write_;
}

void LoopStatisticsCollector::closeWindow(msgs::LoopStatistics& out) noexcept {
    fillCounters(out);
    out.period_us = period_.percentiles();
    out.wakeup_latency_us = wakeup_.percentiles();
    out.compute_us = compute_.percentiles();
    period_.reset();
    wakeup_.reset();
    compute_.reset();
}

}  // namespace haptic::daemon
