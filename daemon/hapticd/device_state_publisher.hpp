#pragma once

// Publishes each device's DeviceState on iceoryx from a non-RT thread. The RT thread only
// stores a snapshot per device per tick into a SeqLock (never waits); iceoryx publishing takes
// a process-shared mutex inside RouDi's shared memory, which the RT thread must not touch.
// This thread polls the snapshots every `period` (1 ms: ~1 kHz, at least the 500 Hz the sim
// needs) and publishes each new one once.

#include <atomic>
#include <chrono>
#include <memory>
#include <thread>
#include <vector>

#include "haptic/daemon/seqlock.hpp"
#include "haptic/msgs/messages.hpp"
#include "iceoryx_posh/popo/publisher.hpp"

namespace haptic::hapticd {

using DeviceStateSnapshot = daemon::SeqLock<msgs::DeviceState>;

class DeviceStatePublisher {
  public:
    // publishers[i] publishes snapshots[i]; both outlive this object.
    DeviceStatePublisher(std::vector<iox::popo::Publisher<msgs::DeviceState>*> publishers,
                         const std::vector<std::unique_ptr<DeviceStateSnapshot>>& snapshots,
                         std::chrono::nanoseconds period);
    ~DeviceStatePublisher();
    DeviceStatePublisher(const DeviceStatePublisher&) = delete;
    DeviceStatePublisher& operator=(const DeviceStatePublisher&) = delete;

    [[nodiscard]] std::uint64_t published() const noexcept {
        return published_.load(std::memory_order_relaxed);
    }

  private:
    void run();

    std::vector<iox::popo::Publisher<msgs::DeviceState>*> publishers_;
    const std::vector<std::unique_ptr<DeviceStateSnapshot>>& snapshots_;
    std::chrono::nanoseconds period_;
    std::atomic<bool> stop_{false};
    std::atomic<std::uint64_t> published_{0};
    std::thread thread_;
};

}  // namespace haptic::hapticd
