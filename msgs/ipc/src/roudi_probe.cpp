#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "haptic/ipc/iceoryx_runtime.hpp"

namespace haptic::ipc {
namespace {

int tryConnect(const sockaddr_un& address, int type) {
    const int fd = ::socket(AF_UNIX, type | SOCK_CLOEXEC, 0);
    if (fd < 0) {
        return errno;
    }
    const int rc =
        ::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address));  // NOLINT
    const int error = rc == 0 ? 0 : errno;
    ::close(fd);
    return error;
}

}  // namespace

RoudiProbe probeRoudi(std::string_view socket_path) {
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    if (socket_path.size() >= sizeof(address.sun_path)) {
        return {false, "RouDi socket path is too long: " + std::string(socket_path)};
    }
    std::memcpy(address.sun_path, socket_path.data(), socket_path.size());

    // A connect() to a datagram socket succeeds only while someone is bound to the path; a
    // stale file left by a killed RouDi gives ECONNREFUSED, a missing one ENOENT.
    int error = tryConnect(address, SOCK_DGRAM);
    if (error == EPROTOTYPE) {
        error = tryConnect(address, SOCK_STREAM);
    }
    if (error == 0) {
        return {true, {}};
    }
    std::string reason = "RouDi is not running (" + std::string(socket_path) + ": " +
                         std::strerror(error) + "); start it with 'iox-roudi -c config/roudi.toml'";
    if (error == EACCES) {
        reason += " as the same user as this process";
    }
    return {false, reason};
}

}  // namespace haptic::ipc
