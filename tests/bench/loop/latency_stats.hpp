#pragma once

// Percentiles for the loop latency benchmark: from raw samples (the daemon's telemetry, the
// sim-link probe) and from cyclictest's histogram (-h), both by the project's one rank rule.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "haptic/common/statistics.hpp"

namespace haptic::bench {

// Percentiles by the project's one rank rule (haptic/common/statistics.hpp).
using LatencySummary = common::PercentileSummary;
using common::summarize;

// cyclictest's histogram (-h <range>): counts[us] for 0 <= us < range, and the samples
// beyond the range. Kept rather than summarised so the rounds of one run can be added up.
struct LatencyHistogram {
    std::vector<std::uint64_t> counts;
    std::uint64_t overflows{0};
    double max{0.0};
};

// Parses the output of `cyclictest -q -h <range>` for one measurement thread: the
// "<latency_us> <count>" rows, "# Max Latencies:" and "# Histogram Overflows:". Returns
// nullopt and sets `error` if the output has no histogram.
std::optional<LatencyHistogram> parseCyclictestOutput(const std::string& output,
                                                      std::string& error);

// Adds `round` into `total` (both from the same -h range, or the shorter one is extended).
void merge(LatencyHistogram& total, const LatencyHistogram& round);

// Nearest-rank percentiles of the histogram; one that falls among the overflows is the
// range's upper bound.
LatencySummary summarize(const LatencyHistogram& histogram);

}  // namespace haptic::bench
