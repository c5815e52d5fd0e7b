#pragma once

#include <string>
#include <string_view>

namespace haptic::ipc {

// RouDi's well-known socket. iceoryx 2.0 builds it from IOX_UDS_SOCKET_PATH_PREFIX and
// IPC_CHANNEL_ROUDI_NAME; a test pins the two together.
inline constexpr std::string_view kRoudiSocketPath = "/tmp/roudi";

struct RoudiProbe {
    bool reachable{false};
    std::string reason;  // why not, when !reachable
};

// Asks the kernel whether a process is bound to RouDi's socket, without registering.
// iceoryx's own registration blocks for 60 s and then aborts when RouDi is absent, so every
// executable probes first and fails fast with a message instead.
RoudiProbe probeRoudi(std::string_view socket_path = kRoudiSocketPath);

// Probes RouDi, quiets iceoryx's default verbose logging and registers this process under
// `app_name`. Throws IpcError with a one-line, actionable message when RouDi is not running.
void initIceoryxRuntime(std::string_view app_name);

}  // namespace haptic::ipc
