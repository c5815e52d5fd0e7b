#pragma once

#include <sys/types.h>

#include <optional>
#include <string>
#include <string_view>

#include "haptic/config/common.hpp"

namespace haptic::ipc {

// RouDi's well-known socket. iceoryx 2.0 builds it from IOX_UDS_SOCKET_PATH_PREFIX and
// IPC_CHANNEL_ROUDI_NAME; a test pins the two together.
inline constexpr std::string_view kRoudiSocketPath = "/tmp/roudi";
// RouDi's management segment; a new RouDi unlinks the old one and creates its own.
inline constexpr std::string_view kRoudiManagementSegment = "/dev/shm/iceoryx_mgmt";

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

// Notices that the RouDi this process registered with has gone away or been replaced.
// iceoryx 2.0 does not tell its clients: after a RouDi restart they keep running but never
// connect to anything again. Only a fresh process can register with the new RouDi, so our
// executables stop (exit code kRoudiLostExitCode) and let systemd start them again.
// check() costs two system calls; call it from a non-RT thread a few times per second.
class RoudiWatch {
  public:
    // Call right after initIceoryxRuntime(): remembers which management segment this
    // process registered with.
    explicit RoudiWatch(std::string_view socket_path = kRoudiSocketPath,
                        std::string_view management_segment = kRoudiManagementSegment);

    // nullopt while the same RouDi is alive, otherwise why not.
    [[nodiscard]] std::optional<std::string> check() const;

  private:
    std::string socket_path_;
    std::string management_segment_;
    dev_t segment_device_{0};
    ino_t segment_inode_{0};
    bool segment_known_{false};
};

// What hapticd and handsim do at start: with an iceoryx sim link (`uses_iceoryx`), check the
// RouDi configuration their file names (`iceoryx.roudi_config`, when the file has the map;
// checkRoudiConfig), register under `app_name` and watch that RouDi; over DDS they need no
// RouDi and get nullopt.
[[nodiscard]] std::optional<RoudiWatch> joinRoudi(
    bool uses_iceoryx, std::string_view app_name,
    const std::optional<config::IceoryxConfig>& iceoryx = std::nullopt);

// EX_TEMPFAIL from sysexits.h: "try again later", which is what a restart achieves.
inline constexpr int kRoudiLostExitCode = 75;

}  // namespace haptic::ipc
