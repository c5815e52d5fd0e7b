#pragma once

#include <algorithm>
#include <cmath>

namespace haptic::common {

template <std::size_t kBinCount>
void FixedBinHistogram<kBinCount>::add(double value) noexcept {
    if (!std::isfinite(value)) {
        return;
    }
    const double clamped = std::max(0.0, value);
    const auto bin = std::min<std::size_t>(static_cast<std::size_t>(clamped), kBins - 1);
    ++bins_[bin];
    ++count_;
    max_ = std::max(max_, clamped);
}

template <std::size_t kBinCount>
void FixedBinHistogram<kBinCount>::reset() noexcept {
    bins_.fill(0);
    count_ = 0;
    max_ = 0.0;
}

template <std::size_t kBinCount>
double FixedBinHistogram<kBinCount>::quantile(double q) const noexcept {
    if (count_ == 0) {
        return 0.0;
    }
    const std::optional<std::size_t> bin = nearestRankBin(bins_, count_, q);
    // The last bin also holds everything beyond it: only the exact max is honest there.
    if (!bin || *bin + 1 == kBins) {
        return max_;
    }
    return std::min(static_cast<double>(*bin + 1), max_);
}

}  // namespace haptic::common
