#pragma once

// The project's one definition of a percentile, for the RT loop and for offline reports.
//
// Rank rule (nearest rank): the q-quantile of n samples is the ceil(q * n)-th smallest sample
// (1-based), and the smallest sample when q * n <= 1. It is always a sample that occurred, never
// an interpolation, so a p99 of loop latencies is a latency the loop really had. Every status
// figure, benchmark and report in the project uses this rule (docs/benchmarks.md).

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace haptic::common {

// 0-based index of the q-quantile in n sorted samples (n > 0) by the nearest-rank rule.
[[nodiscard]] std::size_t nearestRankIndex(double q, std::size_t n) noexcept;

// Index of the bin that holds the q-quantile of a histogram whose bins count `total` samples
// in all; nullopt when that sample lies beyond the last bin (total > sum of counts: overflow).
[[nodiscard]] std::optional<std::size_t> nearestRankBin(std::span<const std::uint64_t> counts,
                                                        std::uint64_t total, double q) noexcept;

// Exact q-quantile of `samples` by the nearest-rank rule. Reorders `samples` (nth_element);
// 0 for an empty input. For offline reports and benchmarks, not for the RT thread.
[[nodiscard]] double percentile(std::vector<double>& samples, double q);

// The percentiles every report prints.
struct PercentileSummary {
    std::uint64_t count{0};
    double p50{0.0};
    double p99{0.0};
    double p999{0.0};
    double max{0.0};
    // Samples beyond a histogram's range (histogram input only); a percentile that falls among
    // them is reported as the range's upper bound, i.e. a lower bound of the true value.
    std::uint64_t overflows{0};
};

// Exact summary of `samples` (sorts them). An empty input gives an all-zero summary.
[[nodiscard]] PercentileSummary summarize(std::vector<double>& samples);

// Fixed-bin histogram for the RT thread: bins of one unit (the loop uses microseconds) from 0
// up to kBins, plus an exact maximum. Fixed size, no allocation, O(1) per sample. Values past
// the last bin count in the last bin and show up in `max`. A quantile is reported as the upper
// edge of the bin that holds it (never understating a latency) but never above the maximum.
template <std::size_t kBinCount>
class FixedBinHistogram {
  public:
    static constexpr std::size_t kBins = kBinCount;

    void add(double value) noexcept;
    void reset() noexcept;
    [[nodiscard]] double quantile(double q) const noexcept;
    [[nodiscard]] std::uint64_t count() const noexcept { return count_; }
    [[nodiscard]] double max() const noexcept { return max_; }

  private:
    std::array<std::uint64_t, kBins> bins_{};
    std::uint64_t count_{0};
    double max_{0.0};
};

}  // namespace haptic::common

#include "haptic/common/statistics.inl"
