#pragma once

#include <sys/types.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

namespace haptic::testing {

// A real child process (fork + exec) whose stdout and stderr go to files, so integration
// tests run the shipped executables exactly as a user would.
class ChildProcess {
  public:
    ChildProcess(std::vector<std::string> argv, const std::string& log_prefix);
    ~ChildProcess();
    ChildProcess(const ChildProcess&) = delete;
    ChildProcess& operator=(const ChildProcess&) = delete;

    [[nodiscard]] bool running();
    // Sends SIGTERM and waits; SIGKILL after `grace`. Returns the exit status.
    std::optional<int> terminate(std::chrono::milliseconds grace = std::chrono::seconds(10));
    // Waits for exit up to `timeout`; nullopt if still running. Exit code, or 128 + signal.
    std::optional<int> waitFor(std::chrono::milliseconds timeout);

    [[nodiscard]] std::string stdoutText() const;
    [[nodiscard]] std::string stderrText() const;
    [[nodiscard]] pid_t pid() const { return pid_; }

  private:
    pid_t pid_{-1};
    std::optional<int> exit_code_;
    std::string stdout_path_;
    std::string stderr_path_;
};

// Runs a command to completion (with a timeout) and returns {exit code, stdout, stderr}.
struct CommandResult {
    int exit_code{-1};
    std::string out;
    std::string err;
    double seconds{0.0};
};
CommandResult runCommand(const std::vector<std::string>& argv, std::chrono::milliseconds timeout);

// Whether this process may start others under SCHED_FIFO (root, CAP_SYS_NICE or
// LimitRTPRIO) with chrt.
bool fifoPermitted();

// `argv` run under SCHED_FIFO `priority` (util-linux's chrt) where this host allows it, as is.
// For the emulated devices: their firmware runs on its own microcontroller, so a device that
// misses its state or heartbeat period because a loaded CI machine starved a normal-priority
// process is a test artefact that hapticd would rightly report as a device fault.
std::vector<std::string> withFifoPriority(std::vector<std::string> argv, int priority);

}  // namespace haptic::testing
