#pragma once

#include <cstdint>
#include <string_view>

#include "haptic/msgs/messages.hpp"

namespace haptic::daemon {

// Why a message from the sim was rejected: the status message's reasons (messages.hpp), so
// that hapticctl can show the counts by reason.
using InputRejection = msgs::SimInputRejection;

std::string_view describe(InputRejection reason) noexcept;

InputRejection validate(const msgs::ConstraintSet& message, std::string_view device_id,
                        std::uint16_t joint_count) noexcept;
InputRejection validate(const msgs::ContactSurface& message, std::string_view device_id) noexcept;

}  // namespace haptic::daemon
