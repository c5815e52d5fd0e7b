#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "haptic/msgs/messages.hpp"

namespace haptic::ctl {

// One screen in the style of `systemctl status`: state, loop statistics, sim link, devices
// and faults. `sample_age_s` is the snapshot's age (negative: unknown, not shown).
std::string formatStatus(const msgs::HapticStatus& status, double sample_age_s);

// handsim's sim/status in the same style: scene and model, step rate and time, and what the
// solver did instead of a plain step (zeroed, substepped) and the tracking inputs it refused.
std::string formatSimStatus(const msgs::SimStatus& status, double sample_age_s);

// What the status screen and a recording's provenance print for a text hapticd left empty
// (an older daemon, or none heard): "(unknown)".
[[nodiscard]] inline std::string_view orUnknown(std::string_view text) noexcept {
    return text.empty() ? std::string_view("(unknown)") : text;
}

}  // namespace haptic::ctl
