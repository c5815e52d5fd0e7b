#pragma once

// Operator commands between hapticd's non-RT thread (DDS) and the RT thread. Two bounded
// lock-free queues from iceoryx_hoofs: commands in, replies out. Neither side ever blocks or
// allocates; a full queue refuses the push and the caller answers for it.

#include <cstdint>

#include "haptic/msgs/messages.hpp"
#include "iceoryx_hoofs/concurrent/lockfree_queue.hpp"

namespace haptic::daemon {

class CommandChannel {
  public:
    // Operators type commands; 16 in flight is far beyond any real burst.
    static constexpr std::uint64_t kCapacity = 16;

    // Non-RT side. False when the RT thread has not drained the queue (it is stalled).
    bool submit(const msgs::HapticCommand& command) noexcept { return commands_.tryPush(command); }
    bool takeReply(msgs::HapticCommandReply& reply) noexcept { return take(replies_, reply); }

    // RT side.
    bool takeCommand(msgs::HapticCommand& command) noexcept { return take(commands_, command); }
    // False only if the non-RT side stopped reading replies; the command still took effect.
    bool postReply(const msgs::HapticCommandReply& reply) noexcept {
        return replies_.tryPush(reply);
    }

  private:
    template <typename Queue, typename T>
    static bool take(Queue& queue, T& out) noexcept {
        auto value = queue.pop();
        if (!value.has_value()) {
            return false;
        }
        out = *value;
        return true;
    }

    iox::concurrent::LockFreeQueue<msgs::HapticCommand, kCapacity> commands_;
    iox::concurrent::LockFreeQueue<msgs::HapticCommandReply, kCapacity> replies_;
};

}  // namespace haptic::daemon
