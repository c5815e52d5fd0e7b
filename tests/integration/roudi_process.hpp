#pragma once

// The real iox-roudi for a process test: started with a roudi.toml and waited for until it
// answers on its socket.

#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "child_process.hpp"
#include "haptic/ipc/iceoryx_runtime.hpp"

namespace haptic::testing {

// Starts iox-roudi with `config` into `roudi` (replacing what it held: also a restart after
// RouDi was lost) and waits up to 10 s for it to answer; a test failure if it exits first or
// does not come up. `launcher` goes before the command (for example setpriv and its options).
inline void startRoudi(std::unique_ptr<ChildProcess>& roudi, const std::string& config,
                       std::vector<std::string> launcher = {}) {
    using namespace std::chrono_literals;
    for (const char* part : {IOX_ROUDI_EXECUTABLE, "-c", config.c_str(), "-l", "warning"}) {
        launcher.emplace_back(part);
    }
    roudi = std::make_unique<ChildProcess>(launcher, "roudi");
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (!ipc::probeRoudi().reachable) {
        ASSERT_TRUE(roudi->running()) << "iox-roudi exited: " << roudi->stderrText();
        ASSERT_LT(std::chrono::steady_clock::now(), deadline) << "iox-roudi did not come up";
        std::this_thread::sleep_for(20ms);
    }
}

}  // namespace haptic::testing
