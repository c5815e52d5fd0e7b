#pragma once

// Operator commands between hapticd's non-RT thread (DDS) and the RT thread. Two bounded
// single-producer single-consumer queues (spsc_queue.hpp): commands in, replies out. Each has
// one thread on either end (the command relay, the RT thread). Neither side ever blocks or
// allocates; a full queue refuses the push and the caller answers for it.

#include <cstdint>

#include "haptic/daemon/spsc_queue.hpp"
#include "haptic/msgs/messages.hpp"

namespace haptic::daemon {

class CommandChannel {
  public:
    // Operators type commands; 16 in flight is far beyond any real burst.
    static constexpr std::uint64_t kCapacity = 16;

    // Non-RT side. False when the RT thread has not drained the queue (it is stalled).
    bool submit(const msgs::HapticCommand& command) noexcept { return commands_.push(command); }
    bool takeReply(msgs::HapticCommandReply& reply) noexcept { return replies_.pop(reply); }

    // RT side.
    bool takeCommand(msgs::HapticCommand& command) noexcept { return commands_.pop(command); }
    // False only if the non-RT side stopped reading replies; the command still took effect.
    bool postReply(const msgs::HapticCommandReply& reply) noexcept { return replies_.push(reply); }

  private:
    SpscQueue<msgs::HapticCommand, kCapacity> commands_;
    SpscQueue<msgs::HapticCommandReply, kCapacity> replies_;
};

}  // namespace haptic::daemon
