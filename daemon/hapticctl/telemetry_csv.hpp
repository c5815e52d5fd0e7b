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
// `origin_ns`: the stamp shown as t = 0 (the first recorded sample).
std::string telemetryCsvRow(const msgs::TelemetrySample& sample, std::int64_t origin_ns);

// The exoskeleton force commands of a recorded CSV, per device index, in row order. Rows
// that are not exoskeleton rows or do not parse are skipped.
std::map<int, std::vector<double>> exoskeletonForcesFromCsv(std::string_view csv);

// A gnuplot script reading `csv_path` and writing `png_path`.
std::string telemetryPlotScript(const std::string& csv_path, const std::string& png_path);

}  // namespace haptic::ctl
