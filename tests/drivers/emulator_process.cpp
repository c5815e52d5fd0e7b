#include "emulator_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace haptic::testing {
namespace {

std::atomic<int> g_counter{0};

int decodeStatus(int status) {
    if (WIFEXITED(status)) {
        return WEXITSTATUS(status);
    }
    return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : -1;
}

}  // namespace

EmulatorProcess::EmulatorProcess(std::vector<std::string> argv) {
    log_path_ = "/tmp/haptic-emu-" + std::to_string(::getpid()) + "-" +
                std::to_string(g_counter++) + ".log";
    int pipe_fds[2];
    if (::pipe2(pipe_fds, O_CLOEXEC) != 0) {
        throw std::runtime_error("pipe failed");
    }
    pid_ = ::fork();
    if (pid_ < 0) {
        throw std::runtime_error("fork failed");
    }
    if (pid_ == 0) {
        ::prctl(PR_SET_PDEATHSIG, SIGKILL);
        const int log = ::open(log_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        ::dup2(log, STDOUT_FILENO);
        ::dup2(log, STDERR_FILENO);
        ::dup2(pipe_fds[0], STDIN_FILENO);
        std::vector<char*> args;
        for (auto& arg : argv) {
            args.push_back(arg.data());
        }
        args.push_back(nullptr);
        ::execv(args[0], args.data());
        ::_exit(127);
    }
    ::close(pipe_fds[0]);
    stdin_fd_ = pipe_fds[1];
}

EmulatorProcess::~EmulatorProcess() {
    stop();
    ::unlink(log_path_.c_str());
}

bool EmulatorProcess::sendCommand(const std::string& line) {
    const std::string text = line + "\n";
    return stdin_fd_ >= 0 &&
           ::write(stdin_fd_, text.data(), text.size()) == static_cast<ssize_t>(text.size());
}

bool EmulatorProcess::running() {
    if (exited_) {
        return false;
    }
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        exit_code_ = decodeStatus(status);
    }
    return !exited_;
}

int EmulatorProcess::stop() {
    if (stdin_fd_ >= 0) {
        ::close(stdin_fd_);
        stdin_fd_ = -1;
    }
    if (!running()) {
        return exit_code_;
    }
    ::kill(pid_, SIGTERM);
    for (int i = 0; i < 500 && running(); ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    if (running()) {
        ::kill(pid_, SIGKILL);
        int status = 0;
        ::waitpid(pid_, &status, 0);
        exited_ = true;
        exit_code_ = decodeStatus(status);
    }
    return exit_code_;
}

std::string EmulatorProcess::output() const {
    std::ifstream in(log_path_);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
}

}  // namespace haptic::testing
