#include "haptic/daemon/periodic_timer.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstring>

#include "haptic/common/clock.hpp"

namespace haptic::daemon {
namespace {

constexpr std::int64_t kNsPerSecond = 1'000'000'000;

std::int64_t toNs(const timespec& t) noexcept {
    return static_cast<std::int64_t>(t.tv_sec) * kNsPerSecond + t.tv_nsec;
}

timespec fromNs(std::int64_t ns) noexcept {
    timespec t{};
    t.tv_sec = static_cast<time_t>(ns / kNsPerSecond);
    t.tv_nsec = static_cast<long>(ns % kNsPerSecond);
    return t;
}

}  // namespace

RealtimeSetupResult applyRealtimeSettings(const RealtimeSettings& settings) {
    RealtimeSetupResult result;
    std::string failures;
    auto fail = [&](const std::string& reason) {
        if (!failures.empty()) {
            failures += "; ";
        }
        failures += reason;
    };
    auto failWithErrno = [&](const std::string& what, int error) {
        fail(what + ": " + std::strerror(error));
    };

    if (::mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
        failWithErrno("mlockall", errno);
    }
    sched_param param{};
    param.sched_priority = settings.priority;
    if (const int rc = ::pthread_setschedparam(::pthread_self(), SCHED_FIFO, &param); rc != 0) {
        failWithErrno("SCHED_FIFO priority " + std::to_string(settings.priority) +
                          " (needs CAP_SYS_NICE or LimitRTPRIO)",
                      rc);
    }
    if (settings.cpu_affinity >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET(static_cast<unsigned>(settings.cpu_affinity), &set);
        if (const int rc = ::pthread_setaffinity_np(::pthread_self(), sizeof(set), &set); rc != 0) {
            failWithErrno("CPU affinity " + std::to_string(settings.cpu_affinity), rc);
        }
    }
    if (settings.cpu_latency_us >= 0) {
        result.cpu_latency = process::CpuLatencyRequest(settings.cpu_latency_us);
        if (!result.cpu_latency.held()) {
            fail("CPU latency request: " + result.cpu_latency.error() +
                 " (needs the udev rule systemd/60-haptic-cpu-latency.rules)");
        }
    }

    if (failures.empty()) {
        result.report =
            "real-time: mlockall, SCHED_FIFO " + std::to_string(settings.priority) +
            (settings.cpu_affinity >= 0 ? ", CPU " + std::to_string(settings.cpu_affinity)
                                        : std::string(", no CPU pinning")) +
            (settings.cpu_latency_us >= 0 ? ", CPU wake-up latency held at " +
                                                std::to_string(settings.cpu_latency_us) + " us"
                                          : std::string(", no CPU latency request"));
        return result;
    }
    if (settings.policy == RealtimePolicy::kEnforce) {
        result.ok = false;
        result.report = "real-time setup failed (" + failures +
                        "); run as root or with the systemd unit's limits, or pass "
                        "--realtime ignore for tests";
    } else {
        result.report = "real-time setup skipped by --realtime ignore (" + failures + ")";
    }
    return result;
}

PeriodicTimer::PeriodicTimer(std::int64_t period_ns) noexcept : period_ns_(period_ns) {}

void PeriodicTimer::start() noexcept {
    deadline_ = fromNs(common::monotonicNowNs() + period_ns_);
}

std::int64_t PeriodicTimer::deadlineNs() const noexcept {
    return toNs(deadline_);
}

std::int64_t PeriodicTimer::waitNext() noexcept {
    while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline_, nullptr) == EINTR) {
    }
    const std::int64_t now = common::monotonicNowNs();
    const std::int64_t deadline = toNs(deadline_);
    std::int64_t next = deadline + period_ns_;
    if (now >= next) {
        const std::int64_t behind = (now - deadline) / period_ns_;
        skipped_ += static_cast<std::uint64_t>(behind);
        next = deadline + (behind + 1) * period_ns_;
    }
    deadline_ = fromNs(next);
    return now > deadline ? now - deadline : 0;
}

}  // namespace haptic::daemon
