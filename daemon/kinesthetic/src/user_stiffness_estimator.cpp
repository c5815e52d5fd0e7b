#include "haptic/kinesthetic/user_stiffness_estimator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace haptic::kinesthetic {

namespace {

// The high-pass sits this far below the lower tone: the pressing out, the probe in.
constexpr double kHighPassFraction = 0.5;
// The upper tone, as a multiple of the lower.
constexpr double kToneRatio = 2.0;

void require(bool ok, const char* field, const char* rule) {
    if (!ok) {
        throw std::invalid_argument(std::string("UserStiffnessEstimator: ") + field + " " + rule);
    }
}

}  // namespace

double UserStiffnessEstimator::Biquad::step(double x) noexcept {
    const double y = b[0] * x + state[0];
    state[0] = b[1] * x - a[0] * y + state[1];
    state[1] = b[2] * x - a[1] * y;
    return y;
}

void UserStiffnessEstimator::Biquad::reset(double x) noexcept {
    state[1] = b[2] * x;
    state[0] = b[1] * x + state[1];
}

void UserStiffnessEstimator::Tone::advance() noexcept {
    const double s = sin * step_cos + cos * step_sin;
    const double c = cos * step_cos - sin * step_sin;
    const double norm = std::hypot(s, c);
    sin = s / norm;
    cos = c / norm;
}

UserStiffnessEstimator::UserStiffnessEstimator(const UserStiffnessEstimatorConfig& config)
    : config_(config),
      probe_ticks_(std::lround(std::ceil(config.probe_time_s * config.probe_frequency_hz - 1e-9) /
                               (config.probe_frequency_hz * config.period_s))),
      stiffness_(std::numeric_limits<double>::quiet_NaN()),
      actuator_stiffness_(std::numeric_limits<double>::quiet_NaN()),
      actuator_damping_(std::numeric_limits<double>::quiet_NaN()),
      actuator_mass_(std::numeric_limits<double>::quiet_NaN()) {
    require(config.period_s > 0.0 && std::isfinite(config.period_s), "period_s", "must be > 0");
    require(config.probe_frequency_hz > 0.0 &&
                kToneRatio * config.probe_frequency_hz * config.period_s <= 0.05,
            "probe_frequency_hz", "must be > 0 and twice it at most a twentieth of the loop rate");
    require(config.window_periods >= 1.0 && config.window_periods <= 10.0, "window_periods",
            "must be in [1, 10]");
    require(config.probe_time_s * config.probe_frequency_hz >= config.window_periods &&
                std::isfinite(config.probe_time_s),
            "probe_time_s", "must fill the window at least once");
    require(config.contact_debounce_s >= 0.0 && config.contact_debounce_s <= 1.0,
            "contact_debounce_s", "must be in [0, 1]");
    require(config.probe_cooldown_s >= 0.0 && std::isfinite(config.probe_cooldown_s),
            "probe_cooldown_s", "must be >= 0");
    require(config.min_stiffness > 0.0 && config.max_stiffness > config.min_stiffness &&
                std::isfinite(config.max_stiffness),
            "min_stiffness/max_stiffness", "must satisfy 0 < min < max < inf");
    require(config.min_response_m > 0.0 && std::isfinite(config.min_response_m), "min_response_m",
            "must be > 0");
    // RBJ high-pass, Q = 1/sqrt(2) (Butterworth), normalised by a0; two in series.
    const double w0 =
        2.0 * std::numbers::pi * kHighPassFraction * config.probe_frequency_hz * config.period_s;
    const double alpha = std::sin(w0) / std::numbers::sqrt2;
    const double cos_w0 = std::cos(w0);
    const double a0 = 1.0 + alpha;
    Biquad high_pass;
    high_pass.b = {0.5 * (1.0 + cos_w0) / a0, -(1.0 + cos_w0) / a0, 0.5 * (1.0 + cos_w0) / a0};
    high_pass.a = {-2.0 * cos_w0 / a0, (1.0 - alpha) / a0};
    force_filter_ = {high_pass, high_pass};
    ell_filter_ = {high_pass, high_pass};
    for (std::size_t i = 0; i < tones_.size(); ++i) {
        Tone& tone = tones_[i];
        tone.omega =
            2.0 * std::numbers::pi * config.probe_frequency_hz * (i == 0 ? 1.0 : kToneRatio);
        tone.step_cos = std::cos(tone.omega * config.period_s);
        tone.step_sin = std::sin(tone.omega * config.period_s);
    }
    window_.resize(static_cast<std::size_t>(
        std::lround(config.window_periods / (config.probe_frequency_hz * config.period_s))));
}

void UserStiffnessEstimator::restart() noexcept {
    if (probing_) {
        cooldown_s_ = config_.probe_cooldown_s;
    }
    probing_ = false;
    valid_ = false;
    paused_s_ = 0.0;
    contact_ticks_ = 0;
    response_m_ = 0.0;
    next_ = 0;
    count_ = 0;
    sums_.fill(0.0);
    shadow_.fill(0.0);
    for (Tone& tone : tones_) {
        tone.sin = 0.0;
        tone.cos = 1.0;
    }
}

void UserStiffnessEstimator::startContact(double force_n, double ell_m) noexcept {
    restart();
    probing_ = true;
    force_filter_[0].reset(force_n);
    force_filter_[1].reset(0.0);
    ell_filter_[0].reset(ell_m);
    ell_filter_[1].reset(0.0);
}

void UserStiffnessEstimator::update(bool in_contact, double force_n, double ell_m,
                                    double actuation_gram) noexcept {
    const bool finite_input = std::isfinite(force_n) && std::isfinite(ell_m) &&
                              actuation_gram > 0.0 && std::isfinite(actuation_gram);
    if (!finite_input) {
        restart();
        return;
    }
    if (!in_contact) {
        if (probing_) {
            paused_s_ += config_.period_s;
            if (paused_s_ > config_.contact_debounce_s || probeTimeOver()) {
                restart();
            }
        } else {
            cooldown_s_ = std::max(0.0, cooldown_s_ - config_.period_s);
        }
        return;
    }
    paused_s_ = 0.0;
    if (!probing_) {
        if (cooldown_s_ > 0.0) {
            cooldown_s_ = std::max(0.0, cooldown_s_ - config_.period_s);
            return;
        }
        startContact(force_n, ell_m);
    }
    if (probeTimeOver()) {
        return;
    }
    const double force_hp = force_filter_[1].step(force_filter_[0].step(force_n));
    const double ell_hp = ell_filter_[1].step(ell_filter_[0].step(ell_m));
    Products products{};
    for (std::size_t i = 0; i < tones_.size(); ++i) {
        Tone& tone = tones_[i];
        // The instruments are the tone of the force this measurement answers: the one sent
        // last tick (the phase before advancing).
        products[4 * i + 0] = tone.cos * force_hp;
        products[4 * i + 1] = -tone.sin * force_hp;
        products[4 * i + 2] = tone.cos * ell_hp;
        products[4 * i + 3] = -tone.sin * ell_hp;
        tone.advance();
    }
    Products& slot = window_[next_];
    const bool full = count_ == window_.size();
    for (std::size_t j = 0; j < products.size(); ++j) {
        sums_[j] += products[j] - (full ? slot[j] : 0.0);
        shadow_[j] += products[j];
    }
    slot = products;
    next_ = next_ + 1 == window_.size() ? 0 : next_ + 1;
    count_ = full ? count_ : count_ + 1;
    if (next_ == 0) {
        sums_ = shadow_;  // exactly the window's products, freshly summed
        shadow_.fill(0.0);
    }
    ++contact_ticks_;
    solve(actuation_gram);
}

void UserStiffnessEstimator::solve(double actuation_gram) noexcept {
    // A solve that fails keeps this contact's last good estimate (and valid_).
    // A tone's cos and sin each average 1/2 over a period: an amplitude is twice the
    // correlation per sample.
    response_m_ = std::numeric_limits<double>::infinity();
    std::array<double, 2> real_part{};
    std::array<double, 2> imaginary_part{};
    for (std::size_t i = 0; i < tones_.size(); ++i) {
        const double force_re = sums_[4 * i + 0];
        const double force_im = sums_[4 * i + 1];
        const double ell_re = sums_[4 * i + 2];
        const double ell_im = sums_[4 * i + 3];
        const double ell_squared = ell_re * ell_re + ell_im * ell_im;
        response_m_ =
            std::min(response_m_, 2.0 * std::sqrt(ell_squared) / static_cast<double>(count_));
        // H = U / L
        real_part[i] = (force_re * ell_re + force_im * ell_im) / ell_squared;
        imaginary_part[i] = (force_im * ell_re - force_re * ell_im) / ell_squared;
    }
    if (count_ < window_.size() || !(response_m_ >= config_.min_response_m)) {
        return;
    }
    const double w1 = tones_[0].omega * tones_[0].omega;
    const double w2 = tones_[1].omega * tones_[1].omega;
    const double k = (w2 * real_part[0] - w1 * real_part[1]) / (w2 - w1);
    const double m = (real_part[0] - real_part[1]) / (w2 - w1);
    const double b =
        0.5 * (imaginary_part[0] / tones_[0].omega + imaginary_part[1] / tones_[1].omega);
    if (!std::isfinite(k) || !std::isfinite(m) || !std::isfinite(b) || !(k > 0.0)) {
        return;
    }
    actuator_stiffness_ = k;
    actuator_mass_ = m;
    actuator_damping_ = b;
    stiffness_ = std::clamp(actuation_gram * k, config_.min_stiffness, config_.max_stiffness);
    valid_ = true;
}

}  // namespace haptic::kinesthetic
