#pragma once

// hapticctl record/plot: telemetry as CSV (one row per device per tick) and the gnuplot
// script that turns such a file into a PNG of commanded forces and loop timing.

#include <cstdint>
#include <string>

#include "haptic/msgs/messages.hpp"

namespace haptic::ctl {

std::string telemetryCsvHeader();
// `origin_ns`: the stamp shown as t = 0 (the first recorded sample).
std::string telemetryCsvRow(const msgs::TelemetrySample& sample, std::int64_t origin_ns);

// A gnuplot script reading `csv_path` and writing `png_path`.
std::string telemetryPlotScript(const std::string& csv_path, const std::string& png_path);

}  // namespace haptic::ctl
