#pragma once

// The non-RT end of haptic/command: takes commands from DDS, hands them to the RT thread
// through the lock-free CommandChannel and publishes the RT thread's replies on
// haptic/command_reply; replies to the local control socket's callers go to it instead. Runs
// on hapticd's main (non-RT) thread only.
//
// Anyone who can reach the DDS domain can write haptic/command, and DDS here carries no
// identity: over DDS only `estop` is taken (stopping is always allowed). Operating (enable,
// disable, clear, method) goes through the local socket, whose caller is known.

#include <cstdint>
#include <deque>

#include "HapticCommandPubSubTypes.h"
#include "haptic/control/control_server.hpp"
#include "haptic/daemon/command_channel.hpp"
#include "haptic/ipc/dds_participant.hpp"

namespace haptic::hapticd {

class CommandRelay {
  public:
    CommandRelay(ipc::DdsParticipant& participant, daemon::CommandChannel& channel,
                 control::ControlServer& local);

    // Forwards every waiting command and publishes every reply the RT thread has posted.
    void poll();

  private:
    void reply(const msgs::HapticCommandReply& reply);
    void refuse(std::uint64_t request_id, const std::string& reason);
    // A client that missed our reply (DDS discovery still in progress) resends the same
    // request; it gets the recorded answer instead of the command running twice.
    const msgs::HapticCommandReply* recorded(std::uint64_t request_id) const;

    daemon::CommandChannel& channel_;
    control::ControlServer& local_;
    ipc::DdsReader<idl::HapticCommand> commands_;
    ipc::DdsWriter<idl::HapticCommandReply> replies_;
    std::deque<msgs::HapticCommandReply> recent_;
    std::deque<std::uint64_t> in_flight_;
    std::uint64_t reply_seq_{0};
};

}  // namespace haptic::hapticd
