#include "loop_stall_retry.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace haptic::testing {
namespace {

// The fault line hapticd logs (daemon_core.cpp, kFaultLoopStalled).
constexpr const char* kStallFault = "fault [110] hapticd: loop stalled";
// The same host's doing spread out: the loop starved below half its rate (kFaultLoopTooSlow).
constexpr const char* kTooSlowFault = "fault [114] hapticd: loop too slow";
// The line an exiting hapticd logs when the stall came between its last tick and its
// fail-stop (daemon_app.cpp, RealtimeLoop::exitStallNs).
constexpr const char* kFailStopStall = "fail-stop: loop stalled";

std::string& stallLine() {
    static std::string line;
    return line;
}

int attemptFromEnvironment() {
    const char* value = std::getenv("HAPTIC_LOOP_STALL_ATTEMPT");
    const int attempt = value != nullptr ? std::atoi(value) : 1;
    return attempt >= 1 ? attempt : 1;
}

// Records the first line of `hapticd_log` that starts with `marker`, unless a stall is
// already recorded or the log holds a sanitizer's report.
void noteStallLine(const std::string& hapticd_log, const char* marker) {
    if (!stallLine().empty()) {
        return;
    }
    for (const char* report : {"Sanitizer", "runtime error:"}) {
        if (hapticd_log.find(report) != std::string::npos) {
            return;
        }
    }
    const auto at = hapticd_log.find(marker);
    if (at == std::string::npos) {
        return;
    }
    const auto end = hapticd_log.find('\n', at);
    stallLine() = hapticd_log.substr(at, end == std::string::npos ? end : end - at);
}

}  // namespace

void noteFailureAfterLoopStall(const std::string& hapticd_log, bool hapticd_running) {
    if (hapticd_running) {
        noteStallLine(hapticd_log, kStallFault);
        noteStallLine(hapticd_log, kTooSlowFault);
    }
}

void noteFailureAfterFailStopStall(const std::string& hapticd_log,
                                   std::optional<int> hapticd_exit_code) {
    if (hapticd_exit_code == std::optional<int>(0)) {
        noteStallLine(hapticd_log, kFailStopStall);
        noteStallLine(hapticd_log, kStallFault);
        noteStallLine(hapticd_log, kTooSlowFault);
    }
}

}  // namespace haptic::testing

int main(int argc, char** argv) {
    // InitGoogleMock takes its flags out of argv; the retry needs them as given (ctest's
    // --gtest_filter above all).
    std::vector<char*> original(argv, argv + argc);
    original.push_back(nullptr);
    ::testing::InitGoogleMock(&argc, argv);
    const int result = RUN_ALL_TESTS();
    const int attempt = haptic::testing::attemptFromEnvironment();
    const std::string& stall = haptic::testing::stallLine();
    if (result == 0 || stall.empty()) {
        return result;
    }
    if (attempt >= haptic::testing::kMaxAttempts) {
        std::printf(
            "[ NO RETRY ] hapticd's loop stalled in this failed run too (%s); attempt "
            "%d of %d, the failure stands\n",
            stall.c_str(), attempt, haptic::testing::kMaxAttempts);
        return result;
    }
    std::printf(
        "[ RETRY    ] the failed test's hapticd stalled (%s): its SCHED_FIFO thread "
        "was off the CPU past the devices' command timeout, which on this VM is the "
        "host's doing; running again, attempt %d of %d\n",
        stall.c_str(), attempt + 1, haptic::testing::kMaxAttempts);
    std::fflush(stdout);
    std::fflush(stderr);
    const std::string next = std::to_string(attempt + 1);
    ::setenv("HAPTIC_LOOP_STALL_ATTEMPT", next.c_str(), 1);
    // Only the standard streams go on: a descriptor the run left open (a socket, a pipe)
    // must not reach the next attempt.
    (void)::close_range(3, ~0U, 0);
    ::execv("/proc/self/exe", original.data());
    std::perror("execv /proc/self/exe");
    return result;
}
