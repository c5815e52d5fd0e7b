#include "haptic/control/control_server.hpp"

#include <grp.h>
#include <poll.h>
#include <pwd.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "haptic/msgs/conversions.hpp"
#include "haptic/msgs/names.hpp"

namespace haptic::control {
namespace {

std::string failure(const std::filesystem::path& path, const std::string& what) {
    return "control socket " + path.string() + ": " + what + ": " + std::strerror(errno);
}

sockaddr_un addressOf(const std::filesystem::path& path) {
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    const std::string text = path.string();
    if (text.size() >= sizeof(address.sun_path)) {
        throw std::runtime_error("control socket " + text + ": path too long for a Unix socket (" +
                                 std::to_string(sizeof(address.sun_path) - 1) + " bytes at most)");
    }
    std::memcpy(address.sun_path, text.c_str(), text.size() + 1);
    return address;
}

std::optional<gid_t> groupId(const std::string& name) {
    std::vector<char> buffer(16 * 1024);
    group entry{};
    group* found = nullptr;
    if (::getgrnam_r(name.c_str(), &entry, buffer.data(), buffer.size(), &found) != 0 ||
        found == nullptr) {
        return std::nullopt;
    }
    return found->gr_gid;
}

// The user's groups from the user database (SO_PEERCRED carries the primary group only).
bool inGroup(uid_t uid, gid_t primary_gid, gid_t wanted) {
    if (primary_gid == wanted) {
        return true;
    }
    std::vector<char> buffer(16 * 1024);
    passwd entry{};
    passwd* found = nullptr;
    if (::getpwuid_r(uid, &entry, buffer.data(), buffer.size(), &found) != 0 || found == nullptr) {
        return false;
    }
    std::vector<gid_t> groups(64);
    int count = static_cast<int>(groups.size());
    if (::getgrouplist(found->pw_name, found->pw_gid, groups.data(), &count) < 0) {
        groups.resize(static_cast<std::size_t>(count));
        if (::getgrouplist(found->pw_name, found->pw_gid, groups.data(), &count) < 0) {
            return false;
        }
    }
    groups.resize(static_cast<std::size_t>(count));
    return std::find(groups.begin(), groups.end(), wanted) != groups.end();
}

std::vector<char> errorDatagram(const std::string& text) {
    std::vector<char> datagram(text.size() + 1);
    datagram[0] = kErrorAnswer;
    std::copy(text.begin(), text.end(), datagram.begin() + 1);
    return datagram;
}

std::string describe(const PeerCredentials& peer) {
    return "uid " + std::to_string(peer.uid) + " pid " + std::to_string(peer.pid);
}

// Stopping is always allowed.
bool anyoneMay(msgs::CommandKind kind) {
    return kind == msgs::CommandKind::kEstop;
}

}  // namespace

ControlServer::ControlServer(std::filesystem::path path, std::string operator_group,
                             daemon::CommandChannel& channel)
    : path_(std::move(path)),
      operator_group_(std::move(operator_group)),
      group_gid_(groupId(operator_group_)),
      channel_(channel),
      buffer_(kMaxDatagram) {
    const sockaddr_un address = addressOf(path_);
    const std::filesystem::path dir = path_.parent_path();
    if (::mkdir(dir.c_str(), 0755) != 0 && errno != EEXIST) {
        throw std::runtime_error(failure(path_, "cannot create " + dir.string()));
    }
    listen_fd_ = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (listen_fd_ < 0) {
        throw std::runtime_error(failure(path_, "socket"));
    }
    // A file left by a killed hapticd has nobody listening: replace it. One that answers
    // belongs to a hapticd that is running: never take its place.
    const int probe = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
    const bool served = probe >= 0 && ::connect(probe, reinterpret_cast<const sockaddr*>(&address),
                                                sizeof(address)) == 0;
    if (probe >= 0) {
        ::close(probe);
    }
    if (served) {
        ::close(listen_fd_);
        throw std::runtime_error("control socket " + path_.string() +
                                 ": another hapticd serves it (one daemon per DDS domain)");
    }
    (void)::unlink(path_.c_str());
    if (::bind(listen_fd_, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) != 0 ||
        ::chmod(path_.c_str(), 0666) != 0 || ::listen(listen_fd_, 16) != 0) {
        const std::string reason = failure(path_, "bind");
        ::close(listen_fd_);
        throw std::runtime_error(reason);
    }
}

ControlServer::~ControlServer() {
    for (const Caller& caller : callers_) {
        ::close(caller.fd);
    }
    if (listen_fd_ >= 0) {
        ::close(listen_fd_);
        (void)::unlink(path_.c_str());
    }
}

void ControlServer::publish(const idl::HapticStatus& status) {
    if (!encode(kStatusAnswer, status, status_datagram_)) {
        status_datagram_.clear();
        return;
    }
    status_predates_reply_ = false;
    for (const int fd : awaiting_status_) {
        send(fd, status_datagram_);
    }
    awaiting_status_.clear();
}

bool ControlServer::mayOperate(const PeerCredentials& peer) const {
    return peer.uid == 0 || peer.uid == ::geteuid() ||
           (group_gid_ && inGroup(peer.uid, peer.gid, *group_gid_));
}

void ControlServer::accept() {
    for (;;) {
        const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd < 0) {
            return;  // EAGAIN: no one else waiting
        }
        const auto peer = peerCredentials(fd);
        if (!peer) {
            ::close(fd);
            continue;
        }
        callers_.push_back({fd, *peer, mayOperate(*peer)});
    }
}

void ControlServer::send(int fd, const std::vector<char>& datagram) {
    // A caller that went away just loses its answer.
    (void)::send(fd, datagram.data(), datagram.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
}

void ControlServer::refuse(const Caller& caller, std::uint64_t request_id,
                           const std::string& reason) {
    msgs::HapticCommandReply refusal;
    refusal.header.source_id.assign("hapticd");
    refusal.request_id = request_id;
    refusal.accepted = false;
    refusal.message.assign(reason);
    std::vector<char> datagram;
    if (encode(kReplyAnswer, msgs::toIdl(refusal), datagram)) {
        send(caller.fd, datagram);
    }
}

void ControlServer::handleCommand(Caller& caller, const char* body, std::size_t size) {
    idl::HapticCommand wire;
    msgs::HapticCommand command;
    if (!decode(body, size, wire)) {
        spdlog::warn("local command from {}: malformed", describe(caller.peer));
        send(caller.fd, errorDatagram("malformed command"));
        return;
    }
    if (const auto result = msgs::fromIdl(wire, command); !result.ok()) {
        spdlog::warn("local command {} from {} rejected: {}", wire.request_id(),
                     describe(caller.peer), result.error);
        refuse(caller, wire.request_id(), "malformed command: " + result.error);
        return;
    }
    const std::string kind(msgs::toString(command.kind));
    if (!caller.may_operate && !anyoneMay(command.kind)) {
        const std::string reason =
            "uid " + std::to_string(caller.peer.uid) + " is not in group '" + operator_group_ +
            "'" + (group_gid_ ? "" : " (no such group on this host)") +
            ": only its members may enable, disable, clear and choose the method; anyone may "
            "read the status and send estop";
        spdlog::warn("local command '{}' from {} refused: {}", kind, describe(caller.peer), reason);
        refuse(caller, command.request_id, reason);
        return;
    }
    const std::uint64_t caller_request_id = command.request_id;
    command.request_id = kLocalRequestBit | ++next_local_id_;
    if (!channel_.submit(command)) {
        spdlog::warn("local command '{}' from {} refused: the RT loop is not taking commands", kind,
                     describe(caller.peer));
        refuse(caller, caller_request_id, "the RT loop is not taking commands (queue full)");
        return;
    }
    spdlog::info("local command '{}' {} from {}", kind, command.argument.view(),
                 describe(caller.peer));
    pending_.push_back(
        {command.request_id, caller_request_id, caller.fd, caller.peer, command.kind});
}

bool ControlServer::handle(Caller& caller) {
    for (;;) {
        const ssize_t received = ::recv(caller.fd, buffer_.data(), buffer_.size(), MSG_DONTWAIT);
        if (received < 0) {
            return errno == EAGAIN || errno == EWOULDBLOCK;
        }
        if (received == 0) {
            return false;  // closed
        }
        const char kind = buffer_[0];
        if (kind == kStatusRequest) {
            if (status_predates_reply_) {
                awaiting_status_.push_back(caller.fd);
            } else if (status_datagram_.empty()) {
                send(caller.fd, errorDatagram("no status yet (the loop is starting)"));
            } else {
                send(caller.fd, status_datagram_);
            }
        } else if (kind == kCommandRequest) {
            handleCommand(caller, buffer_.data() + 1, static_cast<std::size_t>(received) - 1);
        } else {
            spdlog::warn("local caller {}: unknown request '{}', disconnected",
                         describe(caller.peer), kind);
            return false;
        }
    }
}

void ControlServer::drop(int fd) {
    ::close(fd);
    awaiting_status_.erase(std::remove(awaiting_status_.begin(), awaiting_status_.end(), fd),
                           awaiting_status_.end());
    // Its commands still run; their replies just have nobody to go to.
    for (Pending& pending : pending_) {
        if (pending.fd == fd) {
            pending.fd = -1;
        }
    }
}

void ControlServer::serve(std::chrono::milliseconds max_wait) {
    std::vector<pollfd> fds;
    fds.reserve(callers_.size() + 1);
    fds.push_back({listen_fd_, POLLIN, 0});
    for (const Caller& caller : callers_) {
        fds.push_back({caller.fd, POLLIN, 0});
    }
    if (::poll(fds.data(), fds.size(), static_cast<int>(max_wait.count())) <= 0) {
        return;
    }
    for (std::size_t i = 1; i < fds.size(); ++i) {
        if (fds[i].revents == 0) {
            continue;
        }
        const auto caller = std::find_if(callers_.begin(), callers_.end(),
                                         [&](const Caller& c) { return c.fd == fds[i].fd; });
        if (caller != callers_.end() && !handle(*caller)) {
            drop(caller->fd);
            callers_.erase(caller);
        }
    }
    if (fds[0].revents != 0) {
        accept();
    }
}

bool ControlServer::deliver(const msgs::HapticCommandReply& reply) {
    const auto pending = std::find_if(pending_.begin(), pending_.end(), [&](const Pending& p) {
        return p.local_id == reply.request_id;
    });
    status_predates_reply_ = true;  // whoever sent the command
    if (pending == pending_.end()) {
        return false;
    }
    spdlog::info("local command '{}' from {}: {}: {}", msgs::toString(pending->kind),
                 describe(pending->peer), reply.accepted ? "accepted" : "refused",
                 reply.message.view());
    if (pending->fd >= 0) {
        msgs::HapticCommandReply answer = reply;
        answer.request_id = pending->caller_request_id;
        std::vector<char> datagram;
        if (encode(kReplyAnswer, msgs::toIdl(answer), datagram)) {
            send(pending->fd, datagram);
        }
    }
    pending_.erase(pending);
    return true;
}

}  // namespace haptic::control
