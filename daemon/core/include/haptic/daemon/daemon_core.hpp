#pragma once

// The daemon's per-tick bookkeeping, free of I/O so tests and benchmarks drive it directly.
// hapticd's RT thread feeds it the messages it took from iceoryx (or DDS), calls update()
// once per tick and publishes what it fills in. Everything after construction is noexcept
// and allocation-free.
//
// State machine (documented in full in README "Reading hapticctl status"):
//   INIT -> IDLE once every transport is up. RENDERING, FAULT (latched) and E-STOP arrive
//   with the runtime issue; until then the daemon stays IDLE and renders nothing.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "haptic/daemon/loop_statistics.hpp"
#include "haptic/daemon/sim_input_validation.hpp"
#include "haptic/msgs/messages.hpp"

namespace haptic::daemon {

struct DeviceDescriptor {
    std::string name;
    msgs::DeviceKind kind{msgs::DeviceKind::kExoskeleton};
    std::uint16_t joint_count{0};
    std::uint16_t actuator_count{0};
};

struct CoreSettings {
    double rate_hz{1000.0};
    std::int64_t sim_timeout_ns{20'000'000};
    // How long the fade back to full force takes once fresh sim data returns. Force never
    // steps up: it ramps at most this fast.
    std::int64_t fade_in_ns{100'000'000};
    std::int64_t status_period_ns{50'000'000};
    std::string rendering_method;
    msgs::SimTransport sim_transport{msgs::SimTransport::kIceoryx};
};

class DaemonCore {
  public:
    DaemonCore(CoreSettings settings, std::vector<DeviceDescriptor> devices);

    [[nodiscard]] std::size_t deviceCount() const noexcept { return devices_.size(); }
    [[nodiscard]] const DeviceDescriptor& device(std::size_t index) const noexcept {
        return devices_[index].descriptor;
    }

    void markStarted(std::int64_t now_ns) noexcept;

    // A new message from the sim for a device. Invalid ones are counted and dropped; returns
    // the reason (kNone when accepted).
    InputRejection offerConstraintSet(std::size_t device, const msgs::ConstraintSet& message,
                                      std::int64_t now_ns) noexcept;
    InputRejection offerContactSurface(std::size_t device, const msgs::ContactSurface& message,
                                       std::int64_t now_ns) noexcept;

    // Once per tick, after the inputs: ages, fades, statistics.
    void update(std::int64_t now_ns, const TickTiming& timing) noexcept;

    void fillDeviceState(std::size_t device, std::int64_t now_ns, msgs::DeviceState& out) noexcept;

    // 1 while the device's sim input is fresh, falling linearly to 0 over the last quarter of
    // the timeout, so rendered force reaches zero no later than the timeout. sim_timeout_ms
    // must therefore exceed about 1.5 sim periods (the 20 ms default suits sims >= 75 Hz).
    [[nodiscard]] double simFade(std::size_t device) const noexcept {
        return devices_[device].fade;
    }
    [[nodiscard]] std::uint64_t rejectedCount(std::size_t device,
                                              InputRejection reason) const noexcept;

    // Every status period, fills `out` and returns true.
    bool snapshotDue(std::int64_t now_ns) const noexcept;
    void fillStatus(std::int64_t now_ns, msgs::HapticStatus& out) noexcept;

    [[nodiscard]] msgs::DaemonState state() const noexcept { return state_; }

  private:
    struct DeviceSlot {
        DeviceDescriptor descriptor;
        std::int64_t last_accepted_ns{-1};
        std::uint64_t received{0};
        std::uint64_t rejected{0};
        std::array<std::uint64_t, static_cast<std::size_t>(InputRejection::kCount_)> rejected_by{};
        std::uint64_t state_seq{0};
        double fade{0.0};
    };

    InputRejection account(DeviceSlot& slot, InputRejection reason, std::int64_t now_ns) noexcept;
    [[nodiscard]] double ageMs(const DeviceSlot& slot, std::int64_t now_ns) const noexcept;

    CoreSettings settings_;
    std::vector<DeviceSlot> devices_;
    msgs::DaemonState state_{msgs::DaemonState::kInit};
    std::int64_t started_ns_{0};
    std::int64_t last_tick_ns_{0};
    LoopStatisticsCollector statistics_;
    std::uint64_t window_ticks_;
    msgs::LoopStatistics last_window_{};
    std::int64_t last_snapshot_ns_{0};
    std::uint64_t received_at_last_snapshot_{0};
    std::uint64_t status_seq_{0};
};

}  // namespace haptic::daemon
