#include "haptic/common/statistics.hpp"

#include <algorithm>
#include <cmath>

namespace haptic::common {

std::size_t nearestRankIndex(double q, std::size_t n) noexcept {
    const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(n)));
    return std::clamp<std::size_t>(rank, 1, n) - 1;
}

std::optional<std::size_t> nearestRankBin(std::span<const std::uint64_t> counts,
                                          std::uint64_t total, double q) noexcept {
    if (total == 0) {
        return std::nullopt;
    }
    const std::uint64_t wanted = nearestRankIndex(q, total) + 1;
    std::uint64_t seen = 0;
    for (std::size_t bin = 0; bin < counts.size(); ++bin) {
        seen += counts[bin];
        if (seen >= wanted) {
            return bin;
        }
    }
    return std::nullopt;
}

double percentile(std::vector<double>& samples, double q) {
    if (samples.empty()) {
        return 0.0;
    }
    const auto nth =
        samples.begin() + static_cast<std::ptrdiff_t>(nearestRankIndex(q, samples.size()));
    std::nth_element(samples.begin(), nth, samples.end());
    return *nth;
}

PercentileSummary summarize(std::vector<double>& samples) {
    PercentileSummary summary;
    if (samples.empty()) {
        return summary;
    }
    std::sort(samples.begin(), samples.end());
    summary.count = samples.size();
    summary.p50 = samples[nearestRankIndex(0.50, samples.size())];
    summary.p99 = samples[nearestRankIndex(0.99, samples.size())];
    summary.p999 = samples[nearestRankIndex(0.999, samples.size())];
    summary.max = samples.back();
    return summary;
}

}  // namespace haptic::common
