#pragma once

// The non-RT end of haptic/command: takes commands from DDS, hands them to the RT thread
// through the lock-free CommandChannel and publishes the RT thread's replies on
// haptic/command_reply. Runs on hapticd's main (non-RT) thread only.

#include <cstdint>
#include <deque>

#include "HapticCommandPubSubTypes.h"
#include "haptic/daemon/command_channel.hpp"
#include "haptic/ipc/dds_participant.hpp"

namespace haptic::hapticd {

class CommandRelay {
  public:
    CommandRelay(ipc::DdsParticipant& participant, daemon::CommandChannel& channel);

    // Forwards every waiting command and publishes every reply the RT thread has posted.
    void poll();

  private:
    void reply(const msgs::HapticCommandReply& reply);
    void refuse(std::uint64_t request_id, const std::string& reason);
    // A client that missed our reply (DDS discovery still in progress) resends the same
    // request; it gets the recorded answer instead of the command running twice.
    const msgs::HapticCommandReply* recorded(std::uint64_t request_id) const;

    daemon::CommandChannel& channel_;
    ipc::DdsReader<idl::HapticCommand> commands_;
    ipc::DdsWriter<idl::HapticCommandReply> replies_;
    std::deque<msgs::HapticCommandReply> recent_;
    std::deque<std::uint64_t> in_flight_;
    std::uint64_t reply_seq_{0};
};

}  // namespace haptic::hapticd
