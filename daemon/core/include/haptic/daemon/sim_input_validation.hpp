#pragma once

#include <cstdint>
#include <string_view>

#include "haptic/msgs/messages.hpp"

namespace haptic::daemon {

// Why a message from the sim was rejected. Rejections are counted per reason and never
// reach a device: NaN/Inf and out-of-range values stop where they enter.
enum class InputRejection : std::uint8_t {
    kNone,
    kWrongDevice,           // source_id names another device
    kDofMismatch,           // dof differs from the device's joint count
    kNonFinite,             // NaN or Inf anywhere
    kCountOverCapacity,     // a count larger than its array (corrupt shared memory)
    kDegenerateConstraint,  // a constraint normal of zero length, or a contact beyond 1 m / 10 rad
    kBadNormal,             // a contact normal that is not unit length
    kNegativeWeight,
    kNotNewer,    // its header.seq does not advance (and it is no restart): a replay or duplicate
    kDelayed,     // older than sim_timeout_ns by its stamp (see DaemonCore::freshness())
    kBadStamp,    // header.stamp_ns is 0 or negative
    kStampAhead,  // stamped ahead of the sim's learnt clock by more than sim_timeout_ns
    kCount_,
};

std::string_view describe(InputRejection reason) noexcept;

InputRejection validate(const msgs::ConstraintSet& message, std::string_view device_id,
                        std::uint16_t joint_count) noexcept;
InputRejection validate(const msgs::ContactSurface& message, std::string_view device_id) noexcept;

}  // namespace haptic::daemon
