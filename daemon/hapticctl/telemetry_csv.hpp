#pragma once

// hapticctl record/plot: telemetry as CSV (one row per device per tick) and the gnuplot
// script that turns such a file into a PNG of commanded forces and loop timing.

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "haptic/msgs/messages.hpp"

namespace haptic::ctl {

std::string telemetryCsvHeader();
// The '#' lines before the header: who recorded, when (UTC wall clock of the first sample),
// the monotonic stamp shown as time_s = 0 (`origin_ns`: logs of other processes on the host,
// such as hapticemu --felt-log, line up with it), which hapticd with which configuration (from
// its status; nullptr: none received), and the name of each device index. Readers skip '#'
// lines (gnuplot does too).
std::string telemetryCsvProvenance(std::string_view hapticctl_version, std::int64_t wall_clock_ns,
                                   std::int64_t origin_ns, const msgs::HapticStatus* status);
inline constexpr std::string_view kOriginLinePrefix = "# time_s 0 is CLOCK_MONOTONIC ns ";
// `origin_ns`: the stamp shown as t = 0 (the first recorded sample).
std::string telemetryCsvRow(const msgs::TelemetrySample& sample, std::int64_t origin_ns);

// A gnuplot script reading `csv_path` and writing `png_path`.
// `exo_clamp_n`: the exoskeleton's force clamp; its panel shows twice that either way (the
// sim's reference can spike far beyond it on contact impacts). `thimble_max_force_n`: the
// thimble's pad force limit; its pad-force axis shows twice that.
// `felt`: the virtual user's felt log (hapticemu --felt-log) with the recording's origin_ns:
// the thimble panel then shows the felt pad force too, over the recording's time span
// [0, end_s] (the log usually spans more: it starts with the emulator).
struct FeltLogPlot {
    std::string path;
    std::int64_t origin_ns{0};
    double end_s{0.0};
    // Complete data lines after the header: the plot reads no further (a log still being
    // written can end inside a line, which gnuplot's strcol() fails on).
    std::size_t complete_rows{0};
    std::vector<std::string> devices;  // the log's thimbles in the recording, one line each
};
std::string telemetryPlotScript(const std::string& csv_path, const std::string& png_path,
                                double exo_clamp_n = 10.0, double thimble_max_force_n = 1.5,
                                const FeltLogPlot* felt = nullptr);

// Samples missing from a recording: hapticd sends every `step`-th tick
// (loop.telemetry_decimation), so per device a larger step between consecutive ticks is samples
// hapticd dropped or DDS lost.
class TickGapCounter {
  public:
    explicit TickGapCounter(std::uint64_t step) : step_(step > 0 ? step : 1) {}
    void add(std::uint16_t device, std::uint64_t tick) {
        if (const auto it = last_.find(device); it != last_.end() && tick > it->second + step_) {
            missing_ += (tick - it->second) / step_ - 1;
        }
        last_[device] = tick;
    }
    [[nodiscard]] std::uint64_t missing() const noexcept { return missing_; }

  private:
    std::uint64_t step_;
    std::map<std::uint16_t, std::uint64_t> last_;
    std::uint64_t missing_{0};
};

}  // namespace haptic::ctl
