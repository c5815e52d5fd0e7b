#include <sys/stat.h>

#include <cerrno>
#include <cstring>

#include "haptic/ipc/iceoryx_runtime.hpp"

namespace haptic::ipc {

RoudiWatch::RoudiWatch(std::string_view socket_path, std::string_view management_segment)
    : socket_path_(socket_path), management_segment_(management_segment) {
    struct stat info {};
    if (::stat(management_segment_.c_str(), &info) == 0) {
        segment_device_ = info.st_dev;
        segment_inode_ = info.st_ino;
        segment_known_ = true;
    }
}

std::optional<std::string> RoudiWatch::check() const {
    // A RouDi killed with SIGKILL leaves its socket file behind with nobody bound to it;
    // the probe tells that apart from a live RouDi.
    const RoudiProbe probe = probeRoudi(socket_path_);
    if (!probe.reachable) {
        return "the iceoryx broker RouDi went away: " + probe.reason;
    }
    // A live socket may belong to a RouDi started after ours died. Each RouDi creates its
    // own management segment, so a different inode means a different broker.
    if (segment_known_) {
        struct stat info {};
        if (::stat(management_segment_.c_str(), &info) != 0) {
            return "the iceoryx broker RouDi was restarted (" + management_segment_ + ": " +
                   std::strerror(errno) + ")";
        }
        if (info.st_dev != segment_device_ || info.st_ino != segment_inode_) {
            return "the iceoryx broker RouDi was restarted (" + management_segment_ +
                   " was re-created)";
        }
    }
    return std::nullopt;
}

}  // namespace haptic::ipc
