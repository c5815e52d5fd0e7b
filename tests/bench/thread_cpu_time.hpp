#pragma once

// CPU time of the calling thread, for benchmarks that report it beside the wall time: on the
// shared 2-vCPU machine the wall time per step is 1.5-3x the CPU time.

#include <time.h>

namespace haptic::bench {

[[nodiscard]] inline double threadCpuUs() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return 1e6 * static_cast<double>(t.tv_sec) + 1e-3 * static_cast<double>(t.tv_nsec);
}

// CPU time of every thread of the process: with the soft hand's helper thread, what a step
// costs both cores together.
[[nodiscard]] inline double processCpuUs() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return 1e6 * static_cast<double>(t.tv_sec) + 1e-3 * static_cast<double>(t.tv_nsec);
}

}  // namespace haptic::bench
