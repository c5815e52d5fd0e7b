#pragma once

// hapticd's local control socket (docs/hapticctl.md#local-control): a Unix SOCK_SEQPACKET
// socket on which hapticctl reads the status and sends commands. One datagram per request
// and per answer; the payloads are the CDR encodings DDS uses for the same messages, so the
// status a local caller reads is the very snapshot haptic/status publishes.
//   request  'S'                          the latest status
//            'C' + CDR(HapticCommand)     a command
//   answer   'S' + CDR(HapticStatus)
//            'R' + CDR(HapticCommandReply)
//            'E' + text                   an error (no status yet, malformed request)

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "HapticCommand.h"
#include "HapticStatus.h"

namespace haptic::control {

inline constexpr char kStatusRequest = 'S';
inline constexpr char kCommandRequest = 'C';
inline constexpr char kStatusAnswer = 'S';
inline constexpr char kReplyAnswer = 'R';
inline constexpr char kErrorAnswer = 'E';
// Far above a status with four devices and its fault list (about 2 kB in CDR).
inline constexpr std::size_t kMaxDatagram = 64 * 1024;

// A message as one datagram: `kind` then the CDR encoding. False if it does not fit.
bool encode(char kind, const idl::HapticStatus& status, std::vector<char>& out);
bool encode(char kind, const idl::HapticCommand& command, std::vector<char>& out);
bool encode(char kind, const idl::HapticCommandReply& reply, std::vector<char>& out);
// The CDR after the kind byte; false if it is malformed.
bool decode(const char* data, std::size_t size, idl::HapticStatus& status);
bool decode(const char* data, std::size_t size, idl::HapticCommand& command);
bool decode(const char* data, std::size_t size, idl::HapticCommandReply& reply);

// Who is at the other end of a connected Unix socket (SO_PEERCRED).
struct PeerCredentials {
    pid_t pid{0};
    uid_t uid{0};
    gid_t gid{0};
};
std::optional<PeerCredentials> peerCredentials(int fd);

// hapticctl's end. Each call is one request and its answer.
class ControlClient {
  public:
    enum class Connect { kConnected, kNoSocket, kRefused, kError };

    explicit ControlClient(std::filesystem::path path);
    ~ControlClient();
    ControlClient(const ControlClient&) = delete;
    ControlClient& operator=(const ControlClient&) = delete;

    // kNoSocket (no such file) and kRefused (a stale file, nobody listening) mean no hapticd
    // serves this socket; kError carries errno in error().
    Connect connect();
    [[nodiscard]] const std::string& error() const noexcept { return error_; }

    // The answer's kind and its bytes after the kind; nullopt on a timeout or a broken link
    // (error() says which).
    struct Answer {
        char kind{0};
        std::vector<char> body;
    };
    std::optional<Answer> request(const std::vector<char>& datagram,
                                  std::chrono::milliseconds timeout);

  private:
    std::filesystem::path path_;
    int fd_{-1};
    std::string error_;
};

}  // namespace haptic::control
