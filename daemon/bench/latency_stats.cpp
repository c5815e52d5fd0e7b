#include "latency_stats.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace haptic::bench {
namespace {

std::size_t rankIndex(double q, std::uint64_t count) {
    const auto rank = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count)));
    return static_cast<std::size_t>(std::max<std::uint64_t>(rank, 1) - 1);
}

}  // namespace

LatencySummary summarize(std::vector<double>& samples_us) {
    LatencySummary summary;
    if (samples_us.empty()) {
        return summary;
    }
    std::sort(samples_us.begin(), samples_us.end());
    summary.count = samples_us.size();
    summary.p50 = samples_us[rankIndex(0.50, summary.count)];
    summary.p99 = samples_us[rankIndex(0.99, summary.count)];
    summary.p999 = samples_us[rankIndex(0.999, summary.count)];
    summary.max = samples_us.back();
    return summary;
}

std::optional<LatencySummary> parseCyclictestHistogram(const std::string& output,
                                                       std::string& error) {
    std::vector<std::pair<double, std::uint64_t>> bins;
    LatencySummary summary;
    bool have_max = false;
    std::istringstream lines(output);
    std::string line;
    while (std::getline(lines, line)) {
        if (line.rfind("# Max Latencies:", 0) == 0) {
            summary.max = std::stod(line.substr(16));
            have_max = true;
        } else if (line.rfind("# Histogram Overflows:", 0) == 0) {
            summary.overflows = std::stoull(line.substr(22));
        } else if (!line.empty() && std::isdigit(static_cast<unsigned char>(line[0])) != 0) {
            std::istringstream row(line);
            double latency_us = 0.0;
            std::uint64_t count = 0;
            if (row >> latency_us >> count) {
                bins.emplace_back(latency_us, count);
            }
        }
    }
    if (bins.empty() || !have_max) {
        error = "no histogram in cyclictest's output (was it run with -q -h <range>?)";
        return std::nullopt;
    }
    std::uint64_t in_range = 0;
    for (const auto& bin : bins) {
        in_range += bin.second;
    }
    summary.count = in_range + summary.overflows;
    const double range_top = bins.back().first + 1.0;
    const auto percentile = [&](double q) {
        const std::size_t wanted = rankIndex(q, summary.count) + 1;
        std::uint64_t seen = 0;
        for (const auto& [latency_us, count] : bins) {
            seen += count;
            if (seen >= wanted) {
                return latency_us;
            }
        }
        return range_top;  // among the overflows
    };
    summary.p50 = percentile(0.50);
    summary.p99 = percentile(0.99);
    summary.p999 = percentile(0.999);
    return summary;
}

}  // namespace haptic::bench
