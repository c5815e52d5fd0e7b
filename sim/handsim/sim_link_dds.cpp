#include "sim_link_dds.hpp"

#include <spdlog/spdlog.h>

#include "haptic/ipc/topics.hpp"
#include "haptic/msgs/conversions.hpp"

namespace haptic::handsim {

SimLinkDds::SimLinkDds(ipc::DdsParticipant& participant,
                       const std::vector<config::DeviceConfig>& devices) {
    links_.resize(devices.size());
    for (std::size_t i = 0; i < devices.size(); ++i) {
        const std::string& name = devices[i].name;
        if (devices[i].isExoskeleton()) {
            links_[i].constraint_writer = participant.createWriter<idl::ConstraintSetPubSubType>(
                ipc::deviceTopic(ipc::kConstraintSetTopic, name), ipc::TopicKind::kLatestState);
        } else {
            links_[i].surface_writer = participant.createWriter<idl::ContactSurfacePubSubType>(
                ipc::deviceTopic(ipc::kContactSurfaceTopic, name), ipc::TopicKind::kLatestState);
        }
        links_[i].state_reader = participant.createReader<idl::DeviceStatePubSubType>(
            ipc::deviceTopic(ipc::kDeviceStateTopic, name), ipc::TopicKind::kLatestState);
    }
}

bool SimLinkDds::publish(std::size_t device, const msgs::ConstraintSet& message) {
    return links_[device].constraint_writer.write(msgs::toIdl(message));
}

bool SimLinkDds::publish(std::size_t device, const msgs::ContactSurface& message) {
    return links_[device].surface_writer.write(msgs::toIdl(message));
}

std::size_t SimLinkDds::takeDeviceStates(std::size_t device, msgs::DeviceState& latest,
                                         std::uint64_t& other_schema) {
    std::size_t taken = 0;
    while (links_[device].state_reader.take(idl_state_)) {
        const auto result = msgs::fromIdl(idl_state_, state_);
        if (!result.ok()) {
            if (state_.header.schema != msgs::kSchema) {
                ++other_schema;
            }
            if (unconvertible_states_++ % 1000 == 0) {
                spdlog::warn("sim link dds: dropped a DeviceState that fits no twin: {}",
                             result.error);
            }
            continue;
        }
        latest = state_;  // only a complete conversion replaces the caller's state
        ++taken;
    }
    return taken;
}

}  // namespace haptic::handsim
