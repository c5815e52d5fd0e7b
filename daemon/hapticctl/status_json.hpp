#pragma once

// `hapticctl status --json` and `hapticctl sim --json`: the same snapshot as the screens, one
// JSON object per call for scripts and monitoring. The schema (names, units, which values may
// be null) is documented in docs/hapticctl.md, "Machine-readable status"; a field is never
// renamed or removed without changing "schema".

#include <string>

#include "haptic/msgs/messages.hpp"

namespace haptic::ctl {

inline constexpr const char* kStatusJsonSchema = "haptic.status/1";
inline constexpr const char* kSimStatusJsonSchema = "haptic.sim_status/1";

// `sample_age_s` negative: unknown (null in the output). One line, no trailing newline.
[[nodiscard]] std::string statusJson(const msgs::HapticStatus& status, double sample_age_s);
[[nodiscard]] std::string simStatusJson(const msgs::SimStatus& status, double sample_age_s);

}  // namespace haptic::ctl
