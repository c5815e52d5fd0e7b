#pragma once

#include <sys/types.h>

#include <cstdint>
#include <optional>
#include <string>

namespace haptic::testing {

// How many of process `pid`'s open file descriptors refer to `file` (/proc/<pid>/fd); 0 when
// the process is gone or its descriptors cannot be read.
int openCount(pid_t pid, const std::string& file);

// Whether process `pid` has `file` open.
bool holdsOpen(pid_t pid, const std::string& file);

// The four-byte binary value a PM QoS file such as /dev/cpu_dma_latency reads back (for the
// kernel's device, the lowest request any holder makes), or nothing if fewer than four bytes
// could be read.
std::optional<std::int32_t> readCpuLatencyUs(const std::string& file);

}  // namespace haptic::testing
