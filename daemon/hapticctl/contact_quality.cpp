#include "contact_quality.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace haptic::ctl {

ContactQuality contactQuality(std::span<const double> force_n,
                              const ContactQualitySettings& settings) {
    ContactQuality out;
    out.ticks = force_n.size();
    if (force_n.empty()) {
        return out;
    }
    // Centred moving average by prefix sums; the window shrinks at both ends of the run.
    std::vector<double> prefix(force_n.size() + 1, 0.0);
    for (std::size_t i = 0; i < force_n.size(); ++i) {
        prefix[i + 1] = prefix[i] + force_n[i];
    }
    const std::size_t half = settings.smoothing_ticks / 2;
    double sum_abs = 0.0;
    double sum_squared_ripple = 0.0;
    for (std::size_t i = 0; i < force_n.size(); ++i) {
        const double magnitude = std::abs(force_n[i]);
        if (!(magnitude > settings.contact_threshold_n)) {
            continue;
        }
        ++out.contact_ticks;
        sum_abs += magnitude;
        if (magnitude >= settings.clamp_fraction * settings.clamp_n) {
            ++out.clamp_ticks;
        }
        const std::size_t first = i >= half ? i - half : 0;
        const std::size_t last = std::min(force_n.size(), i + half + 1);
        const double average = (prefix[last] - prefix[first]) / static_cast<double>(last - first);
        const double ripple = force_n[i] - average;
        sum_squared_ripple += ripple * ripple;
    }
    if (out.contact_ticks > 0) {
        const auto n = static_cast<double>(out.contact_ticks);
        out.mean_contact_force_n = sum_abs / n;
        out.chatter_rms_n = std::sqrt(sum_squared_ripple / n);
    }
    return out;
}

}  // namespace haptic::ctl
