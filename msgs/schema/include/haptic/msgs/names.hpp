#pragma once

// The one printable name of each message enum, as the status screen, the journal and the
// telemetry CSV show it. Literals, so callers may keep the pointer; "UNKNOWN" for a value
// outside the enum (a twin converted from a newer peer).

#include "haptic/msgs/messages.hpp"

namespace haptic::msgs {

[[nodiscard]] constexpr const char* toString(DaemonState state) noexcept {
    switch (state) {
        case DaemonState::kInit:
            return "INIT";
        case DaemonState::kIdle:
            return "IDLE";
        case DaemonState::kRendering:
            return "RENDERING";
        case DaemonState::kFault:
            return "FAULT";
        case DaemonState::kEstop:
            return "E-STOP";
    }
    return "UNKNOWN";
}

[[nodiscard]] constexpr const char* toString(DeviceRunState state) noexcept {
    switch (state) {
        case DeviceRunState::kOffline:
            return "OFFLINE";
        case DeviceRunState::kReady:
            return "READY";
        case DeviceRunState::kActive:
            return "ACTIVE";
        case DeviceRunState::kSafe:
            return "SAFE";
        case DeviceRunState::kFault:
            return "FAULT";
    }
    return "UNKNOWN";
}

[[nodiscard]] constexpr const char* toString(DeviceKind kind) noexcept {
    switch (kind) {
        case DeviceKind::kExoskeleton:
            return "exoskeleton";
        case DeviceKind::kThimble:
            return "thimble";
    }
    return "UNKNOWN";
}

[[nodiscard]] constexpr const char* toString(BusState state) noexcept {
    switch (state) {
        case BusState::kUnknown:
            return "unknown";
        case BusState::kErrorActive:
            return "error-active";
        case BusState::kErrorWarning:
            return "error-warning";
        case BusState::kErrorPassive:
            return "error-passive";
        case BusState::kBusOff:
            return "bus-off";
    }
    return "UNKNOWN";
}

[[nodiscard]] constexpr const char* toString(SimTransport transport) noexcept {
    switch (transport) {
        case SimTransport::kIceoryx:
            return "iceoryx";
        case SimTransport::kDds:
            return "dds";
    }
    return "UNKNOWN";
}

// The key hapticctl shows a rejection reason under (status screen and JSON).
[[nodiscard]] constexpr const char* toString(SimInputRejection reason) noexcept {
    switch (reason) {
        case SimInputRejection::kNone:
            return "none";
        case SimInputRejection::kWrongDevice:
            return "wrong_device";
        case SimInputRejection::kDofMismatch:
            return "dof_mismatch";
        case SimInputRejection::kNonFinite:
            return "non_finite";
        case SimInputRejection::kCountOverCapacity:
            return "count_over_capacity";
        case SimInputRejection::kDegenerateConstraint:
            return "degenerate_constraint";
        case SimInputRejection::kBadNormal:
            return "bad_normal";
        case SimInputRejection::kNegativeWeight:
            return "negative_weight";
        case SimInputRejection::kNotNewer:
            return "not_newer";
        case SimInputRejection::kDelayed:
            return "delayed";
        case SimInputRejection::kBadStamp:
            return "bad_stamp";
        case SimInputRejection::kStampAhead:
            return "stamp_ahead";
        case SimInputRejection::kOtherSchema:
            return "other_schema";
        case SimInputRejection::kCount_:
            break;
    }
    return "UNKNOWN";
}

// The hapticctl subcommand that sends the command.
[[nodiscard]] constexpr const char* toString(CommandKind kind) noexcept {
    switch (kind) {
        case CommandKind::kEnable:
            return "enable";
        case CommandKind::kDisable:
            return "disable";
        case CommandKind::kSetMethod:
            return "method";
        case CommandKind::kEstop:
            return "estop";
        case CommandKind::kClearFault:
            return "clear";
    }
    return "UNKNOWN";
}

}  // namespace haptic::msgs
