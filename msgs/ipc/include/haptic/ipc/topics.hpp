#pragma once

// Where each message travels. iceoryx names a channel by (service, instance, event); we use
// service "haptic", the device or scene id as the instance and the message type as the
// event, so one subscriber per device sees only its own data. DDS topics follow the
// architecture's table.

#include <string>
#include <string_view>

namespace haptic::ipc {

inline constexpr std::string_view kIceoryxService = "haptic";
inline constexpr std::string_view kConstraintSetEvent = "ConstraintSet";
inline constexpr std::string_view kContactSurfaceEvent = "ContactSurface";
inline constexpr std::string_view kDeviceStateEvent = "DeviceState";

inline constexpr const char* kStatusTopic = "haptic/status";
inline constexpr const char* kTelemetryTopic = "haptic/telemetry";
inline constexpr const char* kCommandTopic = "haptic/command";
inline constexpr const char* kCommandReplyTopic = "haptic/command_reply";
inline constexpr const char* kSimStatusTopic = "sim/status";
inline constexpr const char* kHandPoseTopic = "tracking/hand";
// The sim -> daemon link over DDS, for a sim on another host. One topic per device and
// message (see deviceTopic), as the iceoryx instance is per device: a reader sees only its
// own device and keep-last-1 cannot drop one device's newest sample for another's.
inline constexpr const char* kConstraintSetTopic = "sim/constraint_set";
inline constexpr const char* kContactSurfaceTopic = "sim/contact_surface";
inline constexpr const char* kDeviceStateTopic = "haptic/device_state";

// "sim/constraint_set/exo" for the base topic kConstraintSetTopic and device "exo".
inline std::string deviceTopic(std::string_view base, std::string_view device) {
    std::string topic(base);
    topic += '/';
    topic += device;
    return topic;
}

}  // namespace haptic::ipc
