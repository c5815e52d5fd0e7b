#include "latency_stats.hpp"

#include <algorithm>
#include <sstream>

namespace haptic::bench {

std::optional<LatencyHistogram> parseCyclictestOutput(const std::string& output,
                                                      std::string& error) {
    LatencyHistogram histogram;
    bool have_bins = false;
    bool have_max = false;
    std::istringstream lines(output);
    std::string line;
    while (std::getline(lines, line)) {
        if (line.rfind("# Max Latencies:", 0) == 0) {
            histogram.max = std::stod(line.substr(16));
            have_max = true;
        } else if (line.rfind("# Histogram Overflows:", 0) == 0) {
            histogram.overflows = std::stoull(line.substr(22));
        } else if (!line.empty() && std::isdigit(static_cast<unsigned char>(line[0])) != 0) {
            std::istringstream row(line);
            std::size_t latency_us = 0;
            std::uint64_t count = 0;
            if (row >> latency_us >> count) {
                if (histogram.counts.size() <= latency_us) {
                    histogram.counts.resize(latency_us + 1, 0);
                }
                histogram.counts[latency_us] += count;
                have_bins = true;
            }
        }
    }
    if (!have_bins || !have_max) {
        error = "no histogram in cyclictest's output (was it run with -q -h <range>?)";
        return std::nullopt;
    }
    return histogram;
}

void merge(LatencyHistogram& total, const LatencyHistogram& round) {
    if (total.counts.size() < round.counts.size()) {
        total.counts.resize(round.counts.size(), 0);
    }
    for (std::size_t us = 0; us < round.counts.size(); ++us) {
        total.counts[us] += round.counts[us];
    }
    total.overflows += round.overflows;
    total.max = std::max(total.max, round.max);
}

LatencySummary summarize(const LatencyHistogram& histogram) {
    LatencySummary summary;
    summary.overflows = histogram.overflows;
    summary.max = histogram.max;
    std::uint64_t in_range = 0;
    for (const std::uint64_t count : histogram.counts) {
        in_range += count;
    }
    summary.count = in_range + histogram.overflows;
    if (summary.count == 0) {
        return summary;
    }
    const auto range_top = static_cast<double>(histogram.counts.size());
    const auto percentile = [&](double q) {
        const std::optional<std::size_t> bin =
            common::nearestRankBin(histogram.counts, summary.count, q);
        return bin ? static_cast<double>(*bin) : range_top;  // nullopt: among the overflows
    };
    summary.p50 = percentile(0.50);
    summary.p99 = percentile(0.99);
    summary.p999 = percentile(0.999);
    return summary;
}

}  // namespace haptic::bench
