#include "haptic/process/shutdown.hpp"

#include <csignal>
#include <thread>

namespace haptic::process {
namespace {

std::atomic<bool> g_shutdown{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void onShutdownSignal(int /*signal*/) {
    g_shutdown.store(true);
}

}  // namespace

void installShutdownHandlers() {
    struct sigaction action {};
    action.sa_handler = onShutdownSignal;
    sigemptyset(&action.sa_mask);
    ::sigaction(SIGINT, &action, nullptr);
    ::sigaction(SIGTERM, &action, nullptr);
}

bool shutdownRequested() noexcept {
    return g_shutdown.load(std::memory_order_relaxed);
}

void requestShutdown() noexcept {
    g_shutdown.store(true);
}

bool sleepUnlessShutdown(std::chrono::nanoseconds duration) {
    constexpr std::chrono::milliseconds kSlice{20};
    const auto deadline = std::chrono::steady_clock::now() + duration;
    while (!shutdownRequested()) {
        const auto now = std::chrono::steady_clock::now();
        if (now >= deadline) {
            return true;
        }
        std::this_thread::sleep_for(std::min<std::chrono::nanoseconds>(kSlice, deadline - now));
    }
    return false;
}

}  // namespace haptic::process
