#include "haptic/control/control_server.hpp"

#include <fcntl.h>
#include <grp.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/file.h>
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

// The groups of the connecting process itself (SO_PEERGROUPS, Linux 4.13+): its real
// supplementary groups, with no user-database lookup that could block this thread.
bool peerInGroup(int fd, gid_t primary_gid, gid_t wanted) {
    if (primary_gid == wanted) {
        return true;
    }
    std::vector<gid_t> groups(64);
    for (int attempt = 0; attempt < 2; ++attempt) {
        socklen_t length = static_cast<socklen_t>(groups.size() * sizeof(gid_t));
        if (::getsockopt(fd, SOL_SOCKET, SO_PEERGROUPS, groups.data(), &length) == 0) {
            groups.resize(length / sizeof(gid_t));
            return std::find(groups.begin(), groups.end(), wanted) != groups.end();
        }
        if (errno != ERANGE) {
            return false;
        }
        groups.resize(length / sizeof(gid_t) + 1);
    }
    return false;
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

constexpr std::size_t kMaxCallersPerUser = 16;
constexpr std::size_t kMaxCallers = 128;
// Connections taken per serve(): a flood of connects must not keep this thread from the
// requests already waiting, nor from publishing the status and pinging the watchdog.
constexpr int kAcceptsPerServe = 8;
// A forwarded command whose reply has not come back by then is given up (the RT thread is
// stalled, or its reply queue overflowed): its caller is told, the slot freed.
constexpr std::chrono::seconds kReplyTimeout{2};

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
    if (::mkdir(dir.c_str(), 0755) == 0) {
        (void)::chmod(dir.c_str(), 0755);  // whatever the umask: others must reach the socket
    } else if (errno != EEXIST) {
        throw std::runtime_error(failure(path_, "cannot create " + dir.string()));
    }
    // Not a directory others may write to (they could put their own socket in our place).
    struct stat info {};
    if (::lstat(dir.c_str(), &info) != 0 || !S_ISDIR(info.st_mode) ||
        (info.st_uid != ::geteuid() && info.st_uid != 0) || (info.st_mode & S_IWOTH) != 0) {
        throw std::runtime_error("control socket " + path_.string() + ": " + dir.string() +
                                 " must be a directory owned by hapticd's user or root that "
                                 "others cannot write to");
    }
    // One daemon per socket: a lock held for hapticd's lifetime (the kernel drops it however
    // hapticd ends), so two starting at once cannot both take the socket.
    const std::string lock_path = path_.string() + ".lock";
    lock_fd_ = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (lock_fd_ < 0) {
        throw std::runtime_error(failure(path_, "cannot open " + lock_path));
    }
    if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
        ::close(lock_fd_);
        throw std::runtime_error("control socket " + path_.string() +
                                 ": another hapticd serves it (one daemon per DDS domain)");
    }
    // With the lock held, a socket file here is a dead hapticd's: replace it. Anything else
    // is not ours to delete.
    if (::lstat(path_.c_str(), &info) == 0) {
        if (!S_ISSOCK(info.st_mode)) {
            ::close(lock_fd_);
            throw std::runtime_error("control socket " + path_.string() +
                                     ": exists and is not a socket; remove it or change "
                                     "control.socket_dir");
        }
        (void)::unlink(path_.c_str());
    }
    listen_fd_ = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (listen_fd_ < 0 ||
        ::bind(listen_fd_, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) != 0 ||
        ::chmod(path_.c_str(), 0666) != 0 || ::listen(listen_fd_, 16) != 0) {
        const std::string reason = failure(path_, "bind");
        if (listen_fd_ >= 0) {
            ::close(listen_fd_);
        }
        ::close(lock_fd_);
        throw std::runtime_error(reason);
    }
    // The descriptor accept() gives up when hapticd has none left (EMFILE), to take the
    // waiting connection and close it rather than spin on a listening socket that stays
    // readable.
    spare_fd_ = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
}

ControlServer::~ControlServer() {
    for (const Caller& caller : callers_) {
        ::close(caller.fd);
    }
    ::close(listen_fd_);
    (void)::unlink(path_.c_str());
    if (spare_fd_ >= 0) {
        ::close(spare_fd_);
    }
    ::close(lock_fd_);  // last: the next hapticd may take the socket from here on
}

void ControlServer::publish(const idl::HapticStatus& status) {
    if (!encode(kStatusAnswer, status, status_datagram_)) {
        status_datagram_.clear();
        return;
    }
    // A snapshot the RT thread took before the tick that applied the last command (published
    // late by this thread) does not show that command yet: keep the callers waiting for one.
    status_predates_reply_ = status.header().stamp_ns() <= last_reply_applied_ns_;
    if (status_predates_reply_) {
        return;
    }
    for (const int fd : awaiting_status_) {
        send(fd, status_datagram_);
    }
    awaiting_status_.clear();
}

bool ControlServer::mayOperate(int fd, const PeerCredentials& peer) const {
    return peer.uid == 0 || peer.uid == ::geteuid() ||
           (group_gid_ && peerInGroup(fd, peer.gid, *group_gid_));
}

void ControlServer::accept() {
    for (int taken = 0; taken < kAcceptsPerServe; ++taken) {
        int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd < 0 && (errno == EMFILE || errno == ENFILE) && spare_fd_ >= 0) {
            ::close(spare_fd_);
            fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
            if (fd >= 0) {
                ::close(fd);
            }
            spare_fd_ = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
            spdlog::warn("local caller refused: hapticd has no file descriptor left");
            continue;
        }
        if (fd < 0) {
            return;  // EAGAIN: no one else waiting
        }
        const auto peer = peerCredentials(fd);
        if (!peer) {
            ::close(fd);
            continue;
        }
        // A user opening connections by the thousand must neither use up hapticd's file
        // descriptors nor keep anyone else out (an E-stop must always get in): each user
        // keeps its newest few, and all users together the newest kMaxCallers.
        const auto mine = [&](const Caller& c) { return c.peer.uid == peer->uid; };
        if (static_cast<std::size_t>(std::count_if(callers_.begin(), callers_.end(), mine)) >=
            kMaxCallersPerUser) {
            const auto oldest = std::find_if(callers_.begin(), callers_.end(), mine);
            drop(oldest->fd);
            callers_.erase(oldest);
        } else if (callers_.size() >= kMaxCallers) {
            drop(callers_.front().fd);
            callers_.erase(callers_.begin());
        }
        callers_.push_back({fd, *peer, mayOperate(fd, *peer)});
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
    // Refusals only: accepted commands are always logged and use none of the user's lines.
    const auto log_refusal = [&] {
        return refusal_log_.admit(caller.peer.uid, std::chrono::steady_clock::now());
    };
    if (!decode(body, size, wire)) {
        if (log_refusal()) {
            spdlog::warn("local command from {}: malformed", describe(caller.peer));
        }
        send(caller.fd, errorDatagram("malformed command"));
        return;
    }
    if (const auto result = msgs::fromIdl(wire, command); !result.ok()) {
        if (log_refusal()) {
            spdlog::warn("local command {} from {} rejected: {}", wire.request_id(),
                         describe(caller.peer), result.error);
        }
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
        if (log_refusal()) {
            spdlog::warn("local command '{}' from {} refused: {}", kind, describe(caller.peer),
                         reason);
        }
        refuse(caller, command.request_id, reason);
        return;
    }
    const std::uint64_t caller_request_id = command.request_id;
    command.request_id = kLocalRequestBit | ++next_local_id_;
    if (!channel_.submit(command)) {
        if (log_refusal()) {
            spdlog::warn("local command '{}' from {} refused: the RT loop is not taking commands",
                         kind, describe(caller.peer));
        }
        refuse(caller, caller_request_id, "the RT loop is not taking commands (queue full)");
        return;
    }
    spdlog::info("local command '{}' {} from {}", kind, command.argument.view(),
                 describe(caller.peer));
    pending_.push_back({command.request_id, caller_request_id, caller.fd, caller.peer, command.kind,
                        std::chrono::steady_clock::now()});
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

void ControlServer::expirePending() {
    const auto now = std::chrono::steady_clock::now();
    for (auto it = pending_.begin(); it != pending_.end();) {
        if (now - it->submitted < kReplyTimeout) {
            ++it;
            continue;
        }
        spdlog::warn("local command '{}' from {}: no reply from the RT loop within {} s",
                     msgs::toString(it->kind), describe(it->peer), kReplyTimeout.count());
        if (it->fd >= 0) {
            const Caller caller{it->fd, it->peer, false};
            refuse(caller, it->caller_request_id,
                   "no reply from the RT loop within 2 s (it may still have taken effect; see "
                   "hapticctl status)");
        }
        it = pending_.erase(it);
    }
}

void ControlServer::serve(std::chrono::milliseconds max_wait) {
    expirePending();
    for (const auto& [uid, count] : refusal_log_.expired(std::chrono::steady_clock::now())) {
        spdlog::warn(
            "{} more refused or malformed local commands from uid {} were not logged "
            "({} a user per {} s are)",
            count, uid, refusal_log_.linesPerWindow(),
            std::chrono::duration_cast<std::chrono::seconds>(refusal_log_.window()).count());
    }
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
    last_reply_applied_ns_ = std::max(last_reply_applied_ns_, reply.header.stamp_ns);
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
