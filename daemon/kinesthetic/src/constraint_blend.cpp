#include "haptic/kinesthetic/constraint_blend.hpp"

#include <algorithm>
#include <cmath>

namespace haptic::kinesthetic {

namespace {

// Weight of a new arrival interval in the running mean: a few frames settle it, one late frame
// does not stretch the ramp much.
constexpr double kIntervalWeight = 0.2;

bool equal(std::span<const msgs::LinearConstraint> a, const ConstraintBlend::Constraints& b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.used().begin());
}

void assign(ConstraintBlend::Constraints& to, std::span<const msgs::LinearConstraint> from) {
    to.clear();
    for (const auto& constraint : from) {
        to.push_back(constraint);
    }
}

}  // namespace

void ConstraintBlend::reset() noexcept {
    has_target_ = false;
    target_.clear();
    blended_.clear();
    ticks_since_arrival_ = 0;
    mean_interval_ticks_ = 0.0;
    ramp_ticks_ = 1;
    ramp_step_ = 0;
}

bool ConstraintBlend::sameStructure(std::span<const msgs::LinearConstraint> newest) const noexcept {
    if (newest.size() != blended_.size()) {
        return false;
    }
    for (std::size_t j = 0; j < newest.size(); ++j) {
        // A contact that moved to another phalanx (other joints) is a new contact.
        if (newest[j].contact.joints != blended_[j].contact.joints) {
            return false;
        }
        const auto& a = newest[j].a;
        const auto& b = blended_[j].a;
        double dot = 0.0;
        double a_squared = 0.0;
        double b_squared = 0.0;
        for (std::size_t i = 0; i < a.size(); ++i) {
            dot += a[i] * b[i];
            a_squared += a[i] * a[i];
            b_squared += b[i] * b[i];
        }
        if (!(dot > kSameNormalCosine * std::sqrt(a_squared * b_squared))) {
            return false;
        }
    }
    return true;
}

std::span<const msgs::LinearConstraint> ConstraintBlend::update(
    std::span<const msgs::LinearConstraint> newest) noexcept {
    newest = newest.first(std::min(newest.size(), Constraints::kCapacity));
    ++ticks_since_arrival_;
    if (!has_target_ || !equal(newest, target_)) {
        if (has_target_) {
            const auto interval = static_cast<double>(ticks_since_arrival_);
            mean_interval_ticks_ =
                mean_interval_ticks_ > 0.0
                    ? mean_interval_ticks_ + kIntervalWeight * (interval - mean_interval_ticks_)
                    : interval;
        }
        ticks_since_arrival_ = 0;
        ramp_ticks_ =
            std::clamp(static_cast<int>(std::lround(mean_interval_ticks_)), 1, kMaxRampTicks);
        if (has_target_ && sameStructure(newest)) {
            from_ = blended_;
            ramp_step_ = 0;
        } else {
            assign(from_, newest);
            ramp_step_ = ramp_ticks_;
        }
        assign(target_, newest);
        has_target_ = true;
    }
    if (ramp_step_ < ramp_ticks_) {
        ++ramp_step_;
    }
    const double s = static_cast<double>(ramp_step_) / static_cast<double>(ramp_ticks_);
    blended_.clear();
    for (std::size_t j = 0; j < target_.size(); ++j) {
        msgs::LinearConstraint c = target_[j];
        const msgs::LinearConstraint& start = from_[j];
        for (std::size_t i = 0; i < c.a.size(); ++i) {
            c.a[i] = start.a[i] + s * (c.a[i] - start.a[i]);
        }
        c.b = start.b + s * (c.b - start.b);
        // The contact behind the row moves with it (relative vectors: they interpolate whole).
        if (c.contact.joints > 0) {  // the same joints as start: sameStructure()
            auto lerp = [s](double from, double to) { return from + s * (to - from); };
            msgs::ContactKinematics& k = c.contact;
            const msgs::ContactKinematics& k0 = start.contact;
            k.gap_m = lerp(k0.gap_m, k.gap_m);
            for (std::size_t i = 0; i < 3; ++i) {
                k.normal[i] = lerp(k0.normal[i], k.normal[i]);
            }
            for (std::size_t j = 0; j < msgs::kMaxContactJoints; ++j) {
                k.q_ref_rad[j] = lerp(k0.q_ref_rad[j], k.q_ref_rad[j]);
                for (std::size_t i = 0; i < 3; ++i) {
                    k.axis[j][i] = lerp(k0.axis[j][i], k.axis[j][i]);
                    k.lever_m[j][i] = lerp(k0.lever_m[j][i], k.lever_m[j][i]);
                }
            }
        }
        blended_.push_back(c);
    }
    return blended_.used();
}

}  // namespace haptic::kinesthetic
