#pragma once

// Online estimate of the user's stiffness k_u, the value anisotropic's closed-form rho* needs
// (docs/algorithms.md §6.11). The finger in the device obeys, along the actuator,
//
//   u = k (ell - ell_u) + b ell_dot + m ell_ddot
//
// with u the force the actuator measures, ell its coordinate, and ell_u where the user's
// intent would put it. The intent is unknown and moves, and during contact the wall's own
// feedback ties u to ell with the wall's stiffness: a plain regression of u on ell would
// identify the wall, not the user. So the channel adds a small probe to the proxy (two sines
// along the actuator, at probe_frequency_hz and twice it), and the estimator is a lock-in:
// per tone, the correlations of u and ell with the tone's complex exponential over a sliding
// window of whole periods of the lower tone (an instrumental-variable least squares with the tone's
// sine and cosine as instruments: the intent, and the wall's answer to it, do not correlate with
// them) give the finger's dynamic stiffness H(omega) = U / L = k - omega^2 m + i omega b. Two tones
// separate k from the finger's inertia: k = (omega_2^2 Re H_1 - omega_1^2 Re H_2) / (omega_2^2 -
// omega_1^2). A lag dt between the force and the position it is read with (a device reports
// the force of a tick with the position it produced) turns H into H e^(-i omega dt), whose
// real part gains omega^2 b dt: a mass of -b dt, which the two tones take out of k with the
// mass. Both signals are high-passed first (fourth order, at half the lower tone) so
// that the pressing itself, a far larger motion than the probe's, leaks in as little as
// possible; the filter is the same for u and ell and cancels in H. The window holds whole
// periods of both tones, so neither tone leaks into the other's sums (an exponential
// forgetting window does, and made the estimate ripple at the tones' difference).
//
// The estimate is in the joint space the renderer's k_u lives in: for an isotropic user
// K_u = k_u I, the actuator sees k = k_u / |B|^2, so k_u = |B|^2 k. It is bounded to
// [min_stiffness, max_stiffness] and only reported once the window is full and the response
// at both tones is above min_response_m. Contract: the constructor allocates the window;
// update() is noexcept, allocation-free, lock-free and O(1).

#include <array>
#include <cstddef>
#include <vector>

namespace haptic::kinesthetic {

struct UserStiffnessEstimatorConfig {
    double period_s{0.001};
    double probe_frequency_hz{5.0};
    double window_periods{2.0};  // the window, in periods of probe_frequency_hz (rounded)
    // How long each contact is probed, rounded up to whole periods of the lower tone (both
    // tones then end at a zero: no step); the estimate then holds until the next contact.
    double probe_time_s{1.5};
    // Contact lost for less than this pauses the probe instead of ending it (a wall the finger
    // grazes flickers in and out).
    double contact_debounce_s{0.05};
    // After a probe ends, the next starts no sooner than this: a finger tapping a surface does
    // not feel a ripple all the time.
    double probe_cooldown_s{1.0};
    double min_stiffness{0.02};  // bounds of the estimate (N m/rad)
    double max_stiffness{5.0};
    double min_response_m{2e-6};  // smaller probe responses than this are not trusted
};

class UserStiffnessEstimator {
  public:
    // Throws std::invalid_argument naming the first bad field.
    explicit UserStiffnessEstimator(const UserStiffnessEstimatorConfig& config);

    // The probe of the tick about to be sent, in [-2, 2]: the sum of the two tones' sines
    // while in contact, 0 otherwise. The caller scales it (each tone's amplitude along the
    // actuator).
    [[nodiscard]] double probe() const noexcept {
        return probing() && paused_s_ == 0.0 ? tones_[0].sin + tones_[1].sin : 0.0;
    }

    // One tick, after the device state was read: whether the rendering is in contact, the
    // force the actuator measures (N), the actuator coordinate sigma(q) (m) and |B(q)|^2
    // (m^2/rad^2). Non-finite inputs end the contact (the sums restart at the next one).
    // Advances the probe's phase.
    void update(bool in_contact, double force_n, double ell_m, double actuation_gram) noexcept;

    // End the probe and forget its sums; the last estimate stays. The cooldown starts.
    void restart() noexcept;

    // Whether this contact's probe has produced an estimate (it holds once it has).
    [[nodiscard]] bool valid() const noexcept { return valid_; }
    [[nodiscard]] bool probing() const noexcept { return probing_ && !probeTimeOver(); }
    // k_u (N m/rad), bounded; the last valid value, or NaN if there never was one.
    [[nodiscard]] double stiffness() const noexcept { return stiffness_; }
    // Of the last solve, along the actuator: k (N/m), the damping b (N s/m) and the mass m (kg).
    [[nodiscard]] double actuatorStiffness() const noexcept { return actuator_stiffness_; }
    [[nodiscard]] double actuatorDamping() const noexcept { return actuator_damping_; }
    [[nodiscard]] double actuatorMass() const noexcept { return actuator_mass_; }
    // Amplitude of the actuator's response to the weaker-answered tone (m) in the sums.
    [[nodiscard]] double responseAmplitude() const noexcept { return response_m_; }
    [[nodiscard]] double contactTime() const noexcept {
        return static_cast<double>(contact_ticks_) * config_.period_s;
    }

    [[nodiscard]] const UserStiffnessEstimatorConfig& config() const noexcept { return config_; }

  private:
    // Direct form II transposed biquad.
    struct Biquad {
        std::array<double, 3> b{};
        std::array<double, 2> a{};
        std::array<double, 2> state{};
        double step(double x) noexcept;
        void reset(double x) noexcept;  // settled at a constant input x (high-pass: output 0)
    };
    // One probe tone: its phase as a unit rotation (renormalised each tick: no drift, no
    // sin() call).
    struct Tone {
        double omega{0.0};
        double step_cos{1.0};
        double step_sin{0.0};
        double sin{0.0};
        double cos{1.0};
        void advance() noexcept;
    };
    // Per tone: u and ell times exp(-i phase), real and imaginary parts.
    using Products = std::array<double, 8>;

    [[nodiscard]] bool probeTimeOver() const noexcept { return contact_ticks_ >= probe_ticks_; }
    void startContact(double force_n, double ell_m) noexcept;
    void solve(double actuation_gram) noexcept;

    UserStiffnessEstimatorConfig config_;
    long probe_ticks_;              // whole periods of the lower tone
    std::vector<Products> window_;  // ring of the last window_.size() samples' products
    std::size_t next_{0};
    std::size_t count_{0};  // samples in the window
    Products sums_{};
    // The products since the ring last wrapped: when it wraps again they are exactly the
    // window, and replace sums_ (rounding cannot accumulate; O(1) per tick).
    Products shadow_{};
    // Fourth-order high-pass: two biquads per signal.
    std::array<Biquad, 2> force_filter_;
    std::array<Biquad, 2> ell_filter_;
    std::array<Tone, 2> tones_;
    bool probing_{false};
    long contact_ticks_{0};
    double paused_s_{0.0};    // contact lost for this long, within the debounce
    double cooldown_s_{0.0};  // left before the next probe may start
    bool valid_{false};
    double stiffness_;
    double actuator_stiffness_;
    double actuator_damping_;
    double actuator_mass_;
    double response_m_{0.0};
};

}  // namespace haptic::kinesthetic
