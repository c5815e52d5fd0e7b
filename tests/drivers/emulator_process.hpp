#pragma once

// hapticemu as a real child process with a pipe to its stdin (fault commands) and its
// output in files, so the round-trip tests exercise the shipped executable.

#include <sys/types.h>

#include <string>
#include <vector>

namespace haptic::testing {

class EmulatorProcess {
  public:
    explicit EmulatorProcess(std::vector<std::string> argv);
    ~EmulatorProcess();
    EmulatorProcess(const EmulatorProcess&) = delete;
    EmulatorProcess& operator=(const EmulatorProcess&) = delete;

    // Writes one fault command line (without newline) to the emulator's stdin.
    bool sendCommand(const std::string& line);
    [[nodiscard]] bool running();
    // SIGTERM, then SIGKILL after 5 s. Returns the exit code (128 + signal when killed).
    int stop();
    [[nodiscard]] std::string output() const;  // stdout and stderr

  private:
    pid_t pid_{-1};
    int stdin_fd_{-1};
    int exit_code_{-1};
    bool exited_{false};
    std::string log_path_;
};

}  // namespace haptic::testing
