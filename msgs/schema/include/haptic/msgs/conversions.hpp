#pragma once

// Conversions between the iceoryx twins (haptic::msgs) and the Fast DDS types generated
// from msgs/idl (haptic::idl). Used by the non-RT threads that bridge the two transports;
// they may allocate.

#include <string>

#include "ConstraintSet.h"
#include "ContactSurface.h"
#include "DeviceState.h"
#include "HandPose.h"
#include "HapticCommand.h"
#include "HapticStatus.h"
#include "HapticTelemetry.h"
#include "SimStatus.h"
#include "haptic/msgs/messages.hpp"

namespace haptic::msgs {

// Why a DDS sample could not become a twin: a header of another schema (msgs::kSchema; checked
// first), a sequence longer than the twin's capacity, or an enum value outside its range (CDR
// deserialises enums without checking them). A refused sample leaves the twin's header
// overwritten (a reader may count a refusal by its header) and the rest as it was: use the
// twin only after a success.
struct ConversionResult {
    std::string error;  // empty on success; otherwise names the field and the problem
    [[nodiscard]] bool ok() const noexcept { return error.empty(); }
};

idl::ConstraintSet toIdl(const ConstraintSet& in);
idl::ContactSurface toIdl(const ContactSurface& in);
idl::DeviceState toIdl(const DeviceState& in);
idl::HandPose toIdl(const HandPose& in);
idl::HapticStatus toIdl(const HapticStatus& in);
idl::HapticTelemetry toIdl(const HapticTelemetry& in);
idl::HapticCommand toIdl(const HapticCommand& in);
idl::HapticCommandReply toIdl(const HapticCommandReply& in);
idl::SimStatus toIdl(const SimStatus& in);

[[nodiscard]] ConversionResult fromIdl(const idl::ConstraintSet& in, ConstraintSet& out);
[[nodiscard]] ConversionResult fromIdl(const idl::ContactSurface& in, ContactSurface& out);
[[nodiscard]] ConversionResult fromIdl(const idl::DeviceState& in, DeviceState& out);
[[nodiscard]] ConversionResult fromIdl(const idl::HandPose& in, HandPose& out);
[[nodiscard]] ConversionResult fromIdl(const idl::HapticStatus& in, HapticStatus& out);
[[nodiscard]] ConversionResult fromIdl(const idl::HapticTelemetry& in, HapticTelemetry& out);
[[nodiscard]] ConversionResult fromIdl(const idl::HapticCommand& in, HapticCommand& out);
[[nodiscard]] ConversionResult fromIdl(const idl::HapticCommandReply& in, HapticCommandReply& out);
[[nodiscard]] ConversionResult fromIdl(const idl::SimStatus& in, SimStatus& out);

}  // namespace haptic::msgs
