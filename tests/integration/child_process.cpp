#include "child_process.hpp"

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace haptic::testing {
namespace {

std::string readFile(const std::string& path) {
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
}

int decodeStatus(int status) {
    if (WIFEXITED(status)) {
        return WEXITSTATUS(status);
    }
    if (WIFSIGNALED(status)) {
        return 128 + WTERMSIG(status);
    }
    return -1;
}

std::atomic<int> g_counter{0};

}  // namespace

ChildProcess::ChildProcess(std::vector<std::string> argv, const std::string& log_prefix) {
    const std::string base = "/tmp/haptic-it-" + std::to_string(::getpid()) + "-" +
                             std::to_string(g_counter++) + "-" + log_prefix;
    stdout_path_ = base + ".out";
    stderr_path_ = base + ".err";
    pid_ = ::fork();
    if (pid_ < 0) {
        throw std::runtime_error("fork failed");
    }
    if (pid_ == 0) {
        // If the test binary dies (ctest timeout, crash), its RouDi and daemons must not
        // outlive it and block every later test on RouDi's fixed socket.
        ::prctl(PR_SET_PDEATHSIG, SIGKILL);
        const int out = ::open(stdout_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        const int err = ::open(stderr_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        ::dup2(out, STDOUT_FILENO);
        ::dup2(err, STDERR_FILENO);
        const int null_in = ::open("/dev/null", O_RDONLY);
        ::dup2(null_in, STDIN_FILENO);
        std::vector<char*> args;
        for (auto& a : argv) {
            args.push_back(a.data());
        }
        args.push_back(nullptr);
        ::execv(args[0], args.data());
        ::_exit(127);
    }
}

ChildProcess::~ChildProcess() {
    if (!exit_code_) {
        terminate(std::chrono::seconds(5));
    }
    ::unlink(stdout_path_.c_str());
    ::unlink(stderr_path_.c_str());
}

bool ChildProcess::running() {
    if (exit_code_) {
        return false;
    }
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        exit_code_ = decodeStatus(status);
        return false;
    }
    return true;
}

std::optional<int> ChildProcess::waitFor(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (running()) {
        if (std::chrono::steady_clock::now() >= deadline) {
            return std::nullopt;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return exit_code_;
}

std::optional<int> ChildProcess::terminate(std::chrono::milliseconds grace) {
    if (!running()) {
        return exit_code_;
    }
    ::kill(pid_, SIGTERM);
    if (auto code = waitFor(grace)) {
        return code;
    }
    ::kill(pid_, SIGKILL);
    return waitFor(std::chrono::seconds(5));
}

std::string ChildProcess::stdoutText() const {
    return readFile(stdout_path_);
}
std::string ChildProcess::stderrText() const {
    return readFile(stderr_path_);
}

CommandResult runCommand(const std::vector<std::string>& argv, std::chrono::milliseconds timeout) {
    const auto start = std::chrono::steady_clock::now();
    ChildProcess child(argv, "cmd");
    CommandResult result;
    if (auto code = child.waitFor(timeout)) {
        result.exit_code = *code;
    } else {
        child.terminate(std::chrono::seconds(1));
        result.exit_code = -1;  // timed out: a hang
    }
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    result.out = child.stdoutText();
    result.err = child.stderrText();
    return result;
}

bool fifoPermitted() {
    // Probed on a thread of its own, so the test process keeps its normal policy.
    static const bool permitted = [] {
        bool ok = false;
        std::thread probe([&] {
            sched_param param{};
            param.sched_priority = 1;
            ok = ::pthread_setschedparam(::pthread_self(), SCHED_FIFO, &param) == 0;
        });
        probe.join();
        return ok && ::access("/usr/bin/chrt", X_OK) == 0;
    }();
    return permitted;
}

std::vector<std::string> withFifoPriority(std::vector<std::string> argv, int priority) {
    if (!fifoPermitted()) {
        return argv;
    }
    argv.insert(argv.begin(), {"/usr/bin/chrt", "--fifo", std::to_string(priority)});
    return argv;
}

}  // namespace haptic::testing
