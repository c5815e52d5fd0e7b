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

}  // namespace haptic::ctl
