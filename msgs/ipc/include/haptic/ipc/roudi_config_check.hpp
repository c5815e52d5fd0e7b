#pragma once

// What `iceoryx.roudi_config` (daemon.yaml, sim.yaml) is for: the RouDi configuration the
// process's RouDi must be started with. A RouDi whose largest mempool chunk is smaller than
// a message only fails when that message is first loaned, mid-run (iceoryx's publisher then
// reports no chunk and the message is lost every time); checked at start, the process stops
// with the file, the message type and the pool size missing instead.

#include <cstddef>
#include <filesystem>
#include <span>
#include <string_view>

namespace haptic::ipc {

struct ShmMessageSize {
    std::string_view type;
    std::size_t bytes;
};

// Every message twin hapticd and handsim put through RouDi (msgs/messages.hpp).
[[nodiscard]] std::span<const ShmMessageSize> simLinkShmMessages();

// Parses `roudi_config` with iceoryx's own RouDi configuration parser (iceoryx_posh_config)
// and checks that some mempool's chunk holds each message. Throws IpcError with one line
// naming the file and what is wrong: not a RouDi configuration (iceoryx's reason), a pool
// iox-roudi refuses (count 0, size below 8), or the largest message no pool holds and the
// size its pool needs. Sizes only: whether a pool has chunks enough for the queues is not
// known before the processes subscribe.
void checkRoudiConfig(const std::filesystem::path& roudi_config,
                      std::span<const ShmMessageSize> messages = simLinkShmMessages());

}  // namespace haptic::ipc
