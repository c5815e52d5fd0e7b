#include "haptic/tactile/servo_limiter.hpp"

#include <algorithm>
#include <cmath>

namespace haptic::tactile {

ServoLimiter::ServoLimiter(const config::ServoConfig& servos,
                           const ServoAngles& initial_rad) noexcept
    : servos_(servos) {
    for (std::size_t i = 0; i < 3; ++i) {
        const double start = std::isfinite(initial_rad[i]) ? initial_rad[i] : servos_.max_rad;
        last_[i] = std::clamp(start, servos_.min_rad, servos_.max_rad);
    }
}

LimitedServoCommand ServoLimiter::step(const ServoAngles& target_rad, double period_s) noexcept {
    LimitedServoCommand out;
    const bool finite = std::isfinite(target_rad[0]) && std::isfinite(target_rad[1]) &&
                        std::isfinite(target_rad[2]) && std::isfinite(period_s) && period_s > 0.0;
    if (!finite) {
        out.servo_rad = last_;
        out.rejected = true;
        return out;
    }
    const double max_step = servos_.max_rate_rad_per_s * period_s;
    for (std::size_t i = 0; i < 3; ++i) {
        const double in_range = std::clamp(target_rad[i], servos_.min_rad, servos_.max_rad);
        out.range_clamped = out.range_clamped || in_range != target_rad[i];
        const double limited = std::clamp(in_range, last_[i] - max_step, last_[i] + max_step);
        out.rate_limited = out.rate_limited || limited != in_range;
        last_[i] = limited;
    }
    out.servo_rad = last_;
    return out;
}

}  // namespace haptic::tactile
