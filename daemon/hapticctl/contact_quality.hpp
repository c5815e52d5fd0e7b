#pragma once

// What the finger feels of the exoskeleton's force, from the telemetry of one run: how often
// the command sits at its clamp while in contact, and how much it chatters. These are the
// figures the closed-loop issue judges the rendering by (docs/hapticctl.md, "plot"):
//   contact   ticks whose |force command| exceeds contact_threshold_n;
//   at clamp  contact ticks with |force| >= clamp_fraction * clamp_n;
//   chatter   RMS over contact ticks of (force - its centred moving average over
//             smoothing_ticks), as a fraction of the mean |force| over contact ticks.

#include <cstddef>
#include <span>

namespace haptic::ctl {

struct ContactQualitySettings {
    double clamp_n{10.0};  // the device's safety.max_force_n
    double clamp_fraction{0.99};
    double contact_threshold_n{0.05};
    std::size_t smoothing_ticks{33};  // odd; 33 ms at 1 kHz
    double max_step_n{0.5};           // the rate limit over one tick (500 N/s shipped)
};

struct ContactQuality {
    std::size_t ticks{0};
    std::size_t contact_ticks{0};
    std::size_t clamp_ticks{0};
    double mean_contact_force_n{0.0};
    double chatter_rms_n{0.0};
    [[nodiscard]] double clampFraction() const noexcept {
        return contact_ticks == 0
                   ? 0.0
                   : static_cast<double>(clamp_ticks) / static_cast<double>(contact_ticks);
    }
    [[nodiscard]] double chatterFraction() const noexcept {
        return mean_contact_force_n > 0.0 ? chatter_rms_n / mean_contact_force_n : 0.0;
    }
};

// `force_n`: one device's commanded force, one value per tick, in tick order.
[[nodiscard]] ContactQuality contactQuality(std::span<const double> force_n,
                                            const ContactQualitySettings& settings = {});

}  // namespace haptic::ctl
