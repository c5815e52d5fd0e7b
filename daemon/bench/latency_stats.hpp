#pragma once

// Percentiles for the loop latency benchmark: from raw samples (the daemon's telemetry, the
// sim-link probe) and from cyclictest's histogram (-h), so both sides use one definition.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace haptic::bench {

struct LatencySummary {
    std::uint64_t count{0};
    double p50{0.0};
    double p99{0.0};
    double p999{0.0};
    double max{0.0};
    // Samples beyond the histogram's range (cyclictest only); a percentile that falls among
    // them is reported as the range's upper bound, i.e. a lower bound of the true value.
    std::uint64_t overflows{0};
};

// Nearest-rank percentiles (the smallest value with at least q of the samples at or below
// it). Sorts `samples_us`. An empty input gives an all-zero summary.
LatencySummary summarize(std::vector<double>& samples_us);

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
