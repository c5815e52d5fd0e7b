#include "haptic/daemon/loop_statistics.hpp"

namespace haptic::daemon {

msgs::Percentiles percentilesOf(const MicrosecondHistogram& histogram) noexcept {
    return {histogram.quantile(0.50), histogram.quantile(0.99), histogram.max()};
}

LoopStatisticsCollector::LoopStatisticsCollector(double rate_hz) noexcept
    : rate_hz_(rate_hz), period_budget_us_(1e6 / rate_hz) {}

void LoopStatisticsCollector::add(const TickTiming& timing) noexcept {
    ++ticks_;
    period_.add(timing.period_us);
    wakeup_.add(timing.wakeup_latency_us);
    const double tick_work_us = timing.read_us + timing.compute_us + timing.write_us;
    tick_work_.add(tick_work_us);
    if (tick_work_us > period_budget_us_) {
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
    out.period_us = percentilesOf(period_);
    out.wakeup_latency_us = percentilesOf(wakeup_);
    out.tick_work_us = percentilesOf(tick_work_);
    period_.reset();
    wakeup_.reset();
    tick_work_.reset();
}

}  // namespace haptic::daemon
