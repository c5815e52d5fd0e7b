#pragma once

// The daemon's end of the local control socket (control_socket.hpp), served by hapticd's
// main (non-RT) thread: the only thread that submits to the RT thread's command queue, so the
// queue keeps its single producer. Each caller's rights come from its peer credentials
// (SO_PEERCRED, and SO_PEERGROUPS for its supplementary groups), taken when it connects: root,
// hapticd's own user and members of the operator group may enable, disable, clear and choose the
// method; anyone may read the status and send an E-stop, because stopping is always allowed.

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "haptic/control/control_socket.hpp"
#include "haptic/control/log_limit.hpp"
#include "haptic/daemon/command_channel.hpp"
#include "haptic/msgs/messages.hpp"

namespace haptic::control {

class ControlServer {
  public:
    // Creates the socket's directory (0755) when missing, refuses one others may write to,
    // takes <socket>.lock (flock, for the daemon's lifetime) and binds the socket (0666:
    // anyone may connect, the credentials decide). A socket file left by a killed hapticd is
    // replaced; any other file there is not. Throws std::runtime_error naming the path when
    // another hapticd holds the lock or the socket cannot be made.
    ControlServer(std::filesystem::path path, std::string operator_group,
                  daemon::CommandChannel& channel);
    ~ControlServer();
    ControlServer(const ControlServer&) = delete;
    ControlServer& operator=(const ControlServer&) = delete;

    // The snapshot status requests are answered with (the one haptic/status publishes).
    void publish(const idl::HapticStatus& status);
    // Waits up to `max_wait` for requests and serves them; returns early once one was served.
    void serve(std::chrono::milliseconds max_wait);
    // A reply the RT thread posted: true when it answers one of this socket's callers (it is
    // then sent to that caller), false when it belongs to someone else (haptic/command).
    bool deliver(const msgs::HapticCommandReply& reply);
    // Commands forwarded and not yet answered: the main thread then polls the reply queue
    // every millisecond instead of sleeping.
    [[nodiscard]] bool awaitingReplies() const noexcept { return !pending_.empty(); }
    [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }
    // Whether the operator group exists on this host (when not, only root and hapticd's own
    // user may operate).
    [[nodiscard]] bool groupKnown() const noexcept { return group_gid_.has_value(); }

    // Request ids the server gives forwarded commands: the top bit marks them as local.
    static constexpr std::uint64_t kLocalRequestBit = std::uint64_t{1} << 63;

  private:
    struct Caller {
        int fd;
        PeerCredentials peer;
        bool may_operate;
    };
    struct Pending {
        std::uint64_t local_id;
        std::uint64_t caller_request_id;
        int fd;
        PeerCredentials peer;
        msgs::CommandKind kind;
        std::chrono::steady_clock::time_point submitted;
    };

    void accept();
    // False when the caller is gone (closed, or a broken request): it is then dropped.
    bool handle(Caller& caller);
    void handleCommand(Caller& caller, const char* body, std::size_t size);
    void refuse(const Caller& caller, std::uint64_t request_id, const std::string& reason);
    void send(int fd, const std::vector<char>& datagram);
    [[nodiscard]] bool mayOperate(int fd, const PeerCredentials& peer) const;
    void drop(int fd);
    void expirePending();

    std::filesystem::path path_;
    std::string operator_group_;
    std::optional<gid_t> group_gid_;
    daemon::CommandChannel& channel_;
    int listen_fd_{-1};
    int lock_fd_{-1};
    int spare_fd_{-1};
    std::vector<Caller> callers_;
    std::vector<Pending> pending_;
    std::vector<char> status_datagram_;
    // After a command's reply, the status on hand predates it (snapshots come at
    // loop.status_rate_hz): status requests then wait for the next one, so that `estop` then
    // `status` never shows the state before the stop.
    bool status_predates_reply_{false};
    std::int64_t last_reply_applied_ns_{0};  // the RT tick of the last reply (its stamp)
    std::vector<int> awaiting_status_;
    std::vector<char> buffer_;
    std::uint64_t next_local_id_{0};
    // Refused and malformed commands: 5 journal lines per uid per 10 s, the rest summed up.
    PerUidLogLimit refusal_log_{5, std::chrono::seconds(10)};
};

}  // namespace haptic::control
