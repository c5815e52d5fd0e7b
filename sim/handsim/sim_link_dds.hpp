#pragma once

// handsim's end of the sim link over DDS (sim_link.transport: dds): one writer per device for
// its ConstraintSet or ContactSurface and one reader per device for the daemon's DeviceState,
// on the per-device topics of haptic/ipc/topics.hpp. handsim then needs no RouDi.

#include <cstdint>
#include <vector>

#include "ConstraintSetPubSubTypes.h"
#include "ContactSurfacePubSubTypes.h"
#include "DeviceStatePubSubTypes.h"
#include "haptic/config/device.hpp"
#include "haptic/ipc/dds_participant.hpp"
#include "haptic/msgs/messages.hpp"

namespace haptic::handsim {

class SimLinkDds {
  public:
    // Throws ipc::IpcError if DDS refuses a reader or writer.
    SimLinkDds(ipc::DdsParticipant& participant, const std::vector<config::DeviceConfig>& devices);

    // Returns false if DDS refused the sample.
    bool publish(std::size_t device, const msgs::ConstraintSet& message);
    bool publish(std::size_t device, const msgs::ContactSurface& message);

    // Takes every DeviceState waiting for the device; the newest convertible one ends up in
    // `latest`. Returns how many were taken (unconvertible ones are counted, not returned).
    // `other_schema` counts the states of another message schema among those refused.
    std::size_t takeDeviceStates(std::size_t device, msgs::DeviceState& latest,
                                 std::uint64_t& other_schema);

    [[nodiscard]] std::uint64_t unconvertibleStates() const noexcept {
        return unconvertible_states_;
    }

  private:
    struct DeviceLink {
        ipc::DdsWriter<idl::ConstraintSet> constraint_writer;
        ipc::DdsWriter<idl::ContactSurface> surface_writer;
        ipc::DdsReader<idl::DeviceState> state_reader;
    };
    std::vector<DeviceLink> links_;
    idl::DeviceState idl_state_;
    msgs::DeviceState state_{};
    std::uint64_t unconvertible_states_{0};
};

}  // namespace haptic::handsim
