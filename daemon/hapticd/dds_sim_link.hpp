#pragma once

// The sim link over DDS (sim_link.transport: dds), for a sim on another host.
//
// Sim -> daemon: one non-RT thread waits on every device's DDS reader, converts each sample
// to its iceoryx twin and leaves the newest per device in a SeqLock. The RT thread takes it
// from there with one bounded, allocation-free attempt per tick and never touches DDS.
// Nothing is validated here: the RT core validates every message it is offered and counts
// the rejects. Only what cannot become a twin at all (a sequence longer than the twin's
// capacity, an enum out of range) is dropped here, counted and logged.
//
// Daemon -> sim: the RT thread stores each tick's DeviceState in a SeqLock; the same non-RT
// thread writes the newest one to DDS at most once per publish period (the sim reads the
// latest state once per step, 60-200 Hz, so 1 kHz on the wire would only load the link).
//
// With this link hapticd needs no RouDi: nothing else in the daemon uses iceoryx.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "ConstraintSetPubSubTypes.h"
#include "ContactSurfacePubSubTypes.h"
#include "DeviceStatePubSubTypes.h"
#include "haptic/daemon/seqlock.hpp"
#include "haptic/ipc/dds_participant.hpp"
#include "haptic/msgs/messages.hpp"

namespace eprosima::fastdds::dds {
class GuardCondition;
}

namespace haptic::hapticd {

struct SimLinkDevice {
    std::string name;
    msgs::DeviceKind kind{msgs::DeviceKind::kExoskeleton};
};

class DdsSimLink {
  public:
    // Creates the readers and writers (throws ipc::IpcError if DDS refuses one). The thread
    // starts with start().
    DdsSimLink(ipc::DdsParticipant& participant, std::vector<SimLinkDevice> devices,
               std::chrono::nanoseconds state_publish_period = std::chrono::milliseconds(5));
    ~DdsSimLink();
    DdsSimLink(const DdsSimLink&) = delete;
    DdsSimLink& operator=(const DdsSimLink&) = delete;

    void start();
    void stop();

    // RT side, one consumer thread: noexcept, no allocation, no waiting. Returns the newest
    // message not taken before, or nullptr (none new, or the writer was mid-store: the next
    // tick takes it). The pointer stays valid until the next take for that device.
    const msgs::ConstraintSet* takeConstraintSet(std::size_t device) noexcept;
    const msgs::ContactSurface* takeContactSurface(std::size_t device) noexcept;
    void storeDeviceState(std::size_t device, const msgs::DeviceState& state) noexcept;

    // Counters for logs and tests (any thread).
    [[nodiscard]] std::uint64_t received(std::size_t device) const noexcept;
    [[nodiscard]] std::uint64_t unconvertible() const noexcept {
        return unconvertible_.load(std::memory_order_relaxed);
    }
    [[nodiscard]] std::uint64_t statesPublished() const noexcept {
        return states_published_.load(std::memory_order_relaxed);
    }
    [[nodiscard]] std::size_t deviceCount() const noexcept { return devices_.size(); }

  private:
    struct Device;

    void run();
    void drain(Device& device);
    void publishStates(std::chrono::steady_clock::time_point now);

    std::vector<std::unique_ptr<Device>> devices_;
    std::chrono::nanoseconds state_publish_period_;
    std::unique_ptr<eprosima::fastdds::dds::GuardCondition> stop_condition_;
    std::atomic<bool> stop_requested_{false};
    std::atomic<std::uint64_t> unconvertible_{0};
    std::atomic<std::uint64_t> states_published_{0};
    std::thread thread_;
};

}  // namespace haptic::hapticd
