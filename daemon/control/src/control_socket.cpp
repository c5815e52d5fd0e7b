#include "haptic/control/control_socket.hpp"

#include <fastcdr/exceptions/Exception.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "HapticCommandPubSubTypes.h"
#include "HapticStatusPubSubTypes.h"

namespace haptic::control {
namespace {

template <class PubSubType, class Message>
bool encodeWith(char kind, const Message& message, std::vector<char>& out) {
    PubSubType type;
    auto& data = const_cast<Message&>(message);  // the generated API takes void*
    eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&data)());
    if (!type.serialize(&data, &payload) || payload.length + 1 > kMaxDatagram) {
        return false;
    }
    out.resize(payload.length + 1);
    out[0] = kind;
    std::memcpy(out.data() + 1, payload.data, payload.length);
    return true;
}

template <class PubSubType, class Message>
bool decodeWith(const char* data, std::size_t size, Message& message) {
    if (size == 0 || size > kMaxDatagram) {
        return false;
    }
    PubSubType type;
    eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<std::uint32_t>(size));
    std::memcpy(payload.data, data, size);
    payload.length = static_cast<std::uint32_t>(size);
    try {
        return type.deserialize(&payload, &message);
    } catch (const eprosima::fastcdr::exception::Exception&) {
        return false;  // truncated or corrupt CDR
    }
}

}  // namespace

bool encode(char kind, const idl::HapticStatus& status, std::vector<char>& out) {
    return encodeWith<idl::HapticStatusPubSubType>(kind, status, out);
}
bool encode(char kind, const idl::HapticCommand& command, std::vector<char>& out) {
    return encodeWith<idl::HapticCommandPubSubType>(kind, command, out);
}
bool encode(char kind, const idl::HapticCommandReply& reply, std::vector<char>& out) {
    return encodeWith<idl::HapticCommandReplyPubSubType>(kind, reply, out);
}
bool decode(const char* data, std::size_t size, idl::HapticStatus& status) {
    return decodeWith<idl::HapticStatusPubSubType>(data, size, status);
}
bool decode(const char* data, std::size_t size, idl::HapticCommand& command) {
    return decodeWith<idl::HapticCommandPubSubType>(data, size, command);
}
bool decode(const char* data, std::size_t size, idl::HapticCommandReply& reply) {
    return decodeWith<idl::HapticCommandReplyPubSubType>(data, size, reply);
}

std::optional<PeerCredentials> peerCredentials(int fd) {
    ucred credentials{};
    socklen_t length = sizeof(credentials);
    if (::getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &credentials, &length) != 0 ||
        length != sizeof(credentials)) {
        return std::nullopt;
    }
    return PeerCredentials{credentials.pid, credentials.uid, credentials.gid};
}

ControlClient::ControlClient(std::filesystem::path path) : path_(std::move(path)) {}

ControlClient::~ControlClient() {
    if (fd_ >= 0) {
        ::close(fd_);
    }
}

ControlClient::Connect ControlClient::connect() {
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    const std::string path = path_.string();
    if (path.size() >= sizeof(address.sun_path)) {
        error_ = path + ": path too long for a Unix socket";
        return Connect::kError;
    }
    std::memcpy(address.sun_path, path.c_str(), path.size() + 1);
    fd_ = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
    if (fd_ < 0) {
        error_ = std::string("socket: ") + std::strerror(errno);
        return Connect::kError;
    }
    // A daemon whose backlog is full would hold a blocking connect for ever; on a Unix
    // socket SO_SNDTIMEO bounds it.
    const timeval limit{1, 0};
    (void)::setsockopt(fd_, SOL_SOCKET, SO_SNDTIMEO, &limit, sizeof(limit));
    if (::connect(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) == 0) {
        return Connect::kConnected;
    }
    const int failure = errno;
    error_ = path + ": " + std::strerror(failure);
    ::close(fd_);
    fd_ = -1;
    if (failure == ENOENT) {
        return Connect::kNoSocket;
    }
    return failure == ECONNREFUSED ? Connect::kRefused : Connect::kError;  // EAGAIN: timed out
}

std::optional<ControlClient::Answer> ControlClient::request(const std::vector<char>& datagram,
                                                            std::chrono::milliseconds timeout) {
    if (fd_ < 0) {
        error_ = "not connected";
        return std::nullopt;
    }
    if (::send(fd_, datagram.data(), datagram.size(), MSG_NOSIGNAL) !=
        static_cast<ssize_t>(datagram.size())) {
        error_ = std::string("send: ") + std::strerror(errno);
        return std::nullopt;
    }
    pollfd waiting{fd_, POLLIN, 0};
    const int ready = ::poll(&waiting, 1, static_cast<int>(timeout.count()));
    if (ready <= 0) {
        error_ = ready == 0 ? "no answer within " + std::to_string(timeout.count()) + " ms"
                            : std::string("poll: ") + std::strerror(errno);
        return std::nullopt;
    }
    std::vector<char> buffer(kMaxDatagram);
    const ssize_t received = ::recv(fd_, buffer.data(), buffer.size(), 0);
    if (received <= 0) {
        error_ = received == 0 ? "hapticd closed the connection"
                               : std::string("recv: ") + std::strerror(errno);
        return std::nullopt;
    }
    Answer answer;
    answer.kind = buffer[0];
    answer.body.assign(buffer.begin() + 1, buffer.begin() + received);
    return answer;
}

}  // namespace haptic::control
