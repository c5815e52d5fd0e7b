#pragma once

#include <atomic>
#include <chrono>

namespace haptic::process {

// SIGINT/SIGTERM set a flag that every loop polls; no work happens in the handler.
void installShutdownHandlers();
bool shutdownRequested() noexcept;
void requestShutdown() noexcept;

// Sleeps up to `duration`, waking early on shutdown. Returns false when shutdown was asked.
bool sleepUnlessShutdown(std::chrono::nanoseconds duration);

}  // namespace haptic::process
