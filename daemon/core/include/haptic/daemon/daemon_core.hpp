#pragma once

// The daemon's per-tick bookkeeping, free of I/O so tests and benchmarks drive it directly.
// hapticd's RT thread feeds it the messages it took from iceoryx (or DDS), calls update()
// once per tick and publishes what it fills in. Everything after construction is noexcept
// and allocation-free.
//
// State machine: see state_machine.hpp. Commands reach the core through applyCommand() on
// the RT thread (hapticd hands them over through a lock-free queue).

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "haptic/daemon/device_report.hpp"
#include "haptic/daemon/loop_statistics.hpp"
#include "haptic/daemon/sim_input_validation.hpp"
#include "haptic/daemon/state_machine.hpp"
#include "haptic/msgs/messages.hpp"

namespace haptic::daemon {

struct DeviceDescriptor {
    std::string name;
    msgs::DeviceKind kind{msgs::DeviceKind::kExoskeleton};
    std::uint16_t joint_count{0};
    std::uint16_t actuator_count{0};
};

// hapticd's own fault codes in haptic/status, next to the device link codes 100-105
// (runtime::DaemonFaultCode).
inline constexpr std::uint32_t kFaultLoopStalled = 110;
inline constexpr std::uint32_t kFaultLoopOverrunning = 111;
// The hardware E-stop input (DaemonCore::setHardwareEstop): its button pressed, or its relay
// silent for its timeout. Both hold E-STOP, recorded in the fault list.
inline constexpr std::uint32_t kFaultEstopPressed = 112;
inline constexpr std::uint32_t kFaultEstopRelaySilent = 113;
// hapticd's own loop ticking at less than half its rate over a whole overrun window while a
// device is online, its ticks not a stall apart: the period the devices' stability margins
// assume (1 / loop.rate_hz) is more than doubled. Part of the overrun policy.
inline constexpr std::uint32_t kFaultLoopTooSlow = 114;
// The rate check's window is at least this many periods, whatever loop.overrun_window_ms.
inline constexpr std::int64_t kRateWindowPeriods = 100;
// The most overruns a policy may count (loop.overrun_limit's upper bound).
inline constexpr std::size_t kMaxOverrunLimit = 1000;

// What the hardware E-stop input says this tick (daemon.yaml estop_relay).
enum class HardwareEstop : std::uint8_t {
    kNone,                 // no relay configured
    kReleased,             // the relay reports released
    kAwaitingFirstStatus,  // configured, not heard yet, within its timeout since start
    kPressed,              // the relay reports pressed
    kSilent,               // no valid status from the relay for its timeout
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
    // Names a set-method command may choose from (the configured method must be one).
    std::vector<std::string> known_methods;
    // A gap between ticks longer than this is hapticd's own fault (kFaultLoopStalled): by then
    // the devices have gone safe on their own command timeout, and what they report about it
    // is the stall's consequence, not their fault. hapticd sets it to the smallest
    // can.command_timeout_ms of its devices; 0 turns the check off.
    std::int64_t stall_limit_ns{0};
    // Re-arm policy: a device whose sim input, once fresh while RENDERING, is then older than
    // this renders again only after a new `enable` (DeviceStatus.awaiting_enable meanwhile);
    // a shorter outage fades out and back in by itself. 0 turns the policy off.
    std::int64_t sim_rearm_after_ns{0};
    // haptic/telemetry carries every Nth tick (loop.telemetry_decimation); 1 = every tick.
    std::uint32_t telemetry_decimation{1};
    // Overrun policy: `overrun_limit` ticks whose work (read + compute + write) ran past the
    // period within any `overrun_window_ns` raise kFaultLoopOverrunning while a device is
    // online: the loop still ticks, but its commands go out late too often to be trusted.
    // A single overrun only counts. Fewer than half the ticks `rate_hz` asks for over a
    // window raise kFaultLoopTooSlow (late wake-ups, which no tick's work shows). 0 turns
    // the policy off; at most kMaxOverrunLimit.
    std::uint32_t overrun_limit{0};
    std::int64_t overrun_window_ns{0};
    std::string version{};        // shown in the status
    std::string config_digest{};  // config::configurationDigest of what hapticd loaded
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

    // The newest accepted message of the device (nullptr before the first), and how many
    // have been accepted so far, so a renderer can tell a new message from the one it has.
    [[nodiscard]] const msgs::ConstraintSet* latestConstraintSet(
        std::size_t device) const noexcept {
        return devices_[device].has_constraint_set ? &devices_[device].constraint_set : nullptr;
    }
    [[nodiscard]] const msgs::ContactSurface* latestContactSurface(
        std::size_t device) const noexcept {
        return devices_[device].has_contact_surface ? &devices_[device].contact_surface : nullptr;
    }
    [[nodiscard]] std::uint64_t acceptedCount(std::size_t device) const noexcept {
        return devices_[device].received;
    }

    // The device runtime's report for this tick (driver state, bus, commanded output).
    void setDeviceReport(std::size_t device, const DeviceReport& report) noexcept {
        devices_[device].report = report;
    }
    [[nodiscard]] const DeviceReport& deviceReport(std::size_t device) const noexcept {
        return devices_[device].report;
    }

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

    // Whether this tick's telemetry is published (every telemetry_decimation-th tick,
    // starting with the first).
    [[nodiscard]] bool telemetryDue(std::uint64_t tick) const noexcept {
        return settings_.telemetry_decimation <= 1 || tick % settings_.telemetry_decimation == 0;
    }

    // One telemetry sample for the device at this tick: what the device report says was
    // commanded (the rendered force times outputGain(), after the safety stage).
    void fillTelemetry(std::size_t device, std::uint64_t tick, std::int64_t now_ns,
                       const TickTiming& timing, msgs::TelemetrySample& out) const noexcept;

    // Every status period, fills `out` and returns true.
    bool snapshotDue(std::int64_t now_ns) const noexcept;
    void fillStatus(std::int64_t now_ns, msgs::HapticStatus& out) noexcept;

    [[nodiscard]] msgs::DaemonState state() const noexcept { return machine_.state(); }
    [[nodiscard]] const DaemonStateMachine& stateMachine() const noexcept { return machine_; }

    // An operator command: applies it to the state machine and fills the reply.
    CommandOutcome applyCommand(const msgs::HapticCommand& command, std::int64_t now_ns,
                                msgs::HapticCommandReply& reply) noexcept;
    // When the loop last came back from a stall (kFaultLoopStalled), 0 if never.
    [[nodiscard]] std::int64_t lastStallEndNs() const noexcept { return last_stall_end_ns_; }

    // The hardware E-stop input, once per tick before the devices compute (DeviceRuntime), so
    // that a press takes the force off in the tick that reads it. Pressed or silent: E-STOP
    // (from any state but INIT), recorded once per engagement as kFaultEstopPressed or
    // kFaultEstopRelaySilent with `relay` (e.g. "0x0e0 on exo's bus") in the message, and
    // `clear` is refused while it lasts. Awaiting its first status: `enable` is refused.
    void setHardwareEstop(HardwareEstop input, std::string_view relay) noexcept;
    [[nodiscard]] HardwareEstop hardwareEstop() const noexcept { return hardware_estop_; }

    // A safety fault (device, bus, loop); latches FAULT. See DaemonStateMachine::raiseFault.
    void raiseFault(std::uint32_t code, std::string_view device_id,
                    std::string_view message) noexcept {
        machine_.raiseFault(code, device_id, message);
    }

    // The factor on the device's rendered force: the sim fade while RENDERING (and the ramp
    // from an enable, loop.fade_in_ms), 0 otherwise,
    // so IDLE, FAULT and E-STOP hold every device at zero force.
    [[nodiscard]] double outputGain(std::size_t device) const noexcept {
        return machine_.rendering() ? std::min(devices_[device].fade, devices_[device].armed) : 0.0;
    }
    // The device lost its sim input for longer than sim_rearm_after_ns while RENDERING and
    // waits for an operator's `enable` (its gain stays 0 until then).
    [[nodiscard]] bool awaitingEnable(std::size_t device) const noexcept {
        return devices_[device].awaiting_enable;
    }
    // The device itself was lost while RENDERING (its state stale longer than its heartbeat
    // timeout, or never heard): like a long sim outage, its force returns only after an
    // operator's `enable`. No effect outside RENDERING.
    void requireEnable(std::size_t device) noexcept {
        if (machine_.rendering()) {
            devices_[device].awaiting_enable = true;
        }
    }

  private:
    // The offsets (arrival minus stamp) of the first messages since the sim's clock was
    // (re)learnt; their median stands for it until there are kLearningMessages of them.
    static constexpr std::size_t kLearningMessages = 5;
    struct ClockLearning {
        std::array<std::int64_t, kLearningMessages> offsets{};
        std::size_t count{0};
    };
    struct DeviceSlot {
        DeviceDescriptor descriptor;
        std::int64_t last_accepted_ns{-1};
        // Header of the last accepted message: a message is fresh by its content, not by
        // when it arrived (see DaemonCore::freshness()).
        std::uint64_t last_seq{0};
        std::int64_t last_stamp_ns{0};
        // The smallest arrival minus stamp seen from this sim (its clock against ours).
        std::int64_t clock_offset_ns{0};
        ClockLearning clock_learning{};
        bool has_header{false};
        // Refused content forming a stream of its own since then (-1: none), and its last
        // seq (see DaemonCore::freshness()).
        std::int64_t other_stream_since_ns{-1};
        std::int64_t last_heard_ns{-1};  // the last valid message, whatever its freshness
        std::uint64_t other_stream_seq{0};
        std::uint64_t received{0};
        std::uint64_t rejected{0};
        std::array<std::uint64_t, static_cast<std::size_t>(InputRejection::kCount_)> rejected_by{};
        std::uint64_t state_seq{0};
        double fade{0.0};
        // 0 outside RENDERING, rising to 1 over loop.fade_in_ms after an enable: the force
        // fades in after an enable as after a sim outage (the sim fade alone is 1 in IDLE).
        double armed{0.0};
        bool fed_while_rendering{false};  // fresh input arrived since the last enable
        bool awaiting_enable{false};      // see CoreSettings::sim_rearm_after_ns
        DeviceReport report{};
        bool has_constraint_set{false};
        bool has_contact_surface{false};
        msgs::ConstraintSet constraint_set{};
        msgs::ContactSurface contact_surface{};
    };

    InputRejection account(DeviceSlot& slot, InputRejection reason,
                           const msgs::MessageHeader& header, std::int64_t now_ns) noexcept;
    // Accounts a validated message and keeps it in `stored` when it is accepted.
    template <class Message>
    InputRejection admit(DeviceSlot& slot, InputRejection validation, const Message& message,
                         Message& stored, bool& has_stored, std::int64_t now_ns) noexcept {
        const InputRejection reason = account(slot, validation, message.header, now_ns);
        if (reason == InputRejection::kNone) {
            stored = message;
            has_stored = true;
        }
        return reason;
    }
    // What freshness() learnt, for account() to keep.
    struct Freshness {
        std::int64_t clock_offset_ns;
        std::int64_t other_stream_since_ns;
        std::uint64_t other_stream_seq;
        ClockLearning learning;
    };
    // kNone, kBadStamp, kNotNewer, kDelayed or kStampAhead.
    [[nodiscard]] InputRejection freshness(const DeviceSlot& slot,
                                           const msgs::MessageHeader& header, std::int64_t now_ns,
                                           Freshness& out) const noexcept;
    // How fast the sim host's clock may run against ours: 500 ppm, the most the kernel slews
    // a clock by (adjtimex) while NTP corrects it; quartz itself is within 100.
    static constexpr double kClockDriftAllowance = 500e-6;
    // A silence, or refused content of a stream of its own, this long re-learns the sim's
    // clock: twice sim_rearm_after_ns (so the operator's `enable` is due), at least 1 s.
    static constexpr std::int64_t kMinRelearnAfterNs = 1'000'000'000;
    [[nodiscard]] std::int64_t relearnAfterNs() const noexcept;
    [[nodiscard]] double ageMs(const DeviceSlot& slot, std::int64_t now_ns) const noexcept;

    CoreSettings settings_;
    std::vector<DeviceSlot> devices_;
    DaemonStateMachine machine_;
    std::uint64_t reply_seq_{0};
    char refusal_[msgs::kShortTextCapacity]{};  // a command's refusal made up on the RT thread
    std::int64_t started_ns_{0};
    std::int64_t last_tick_ns_{0};
    std::int64_t last_stall_end_ns_{0};
    // When the last overrun_limit overruns happened (a ring, oldest at overrun_next_).
    std::array<std::int64_t, kMaxOverrunLimit> overrun_times_ns_{};
    std::size_t overrun_next_{0};
    std::size_t overrun_count_{0};
    bool overrun_fault_latched_{false};
    HardwareEstop hardware_estop_{HardwareEstop::kNone};
    void countOverrun(std::int64_t now_ns, const TickTiming& timing, bool any_online) noexcept;
    void checkRate(std::int64_t now_ns, bool any_online) noexcept;
    // Whether the fault list holds a fault with this code (hapticd's own latches re-arm once
    // an operator's clear has removed theirs).
    [[nodiscard]] bool faultListed(std::uint32_t code) const noexcept;
    // The rate check's window: its first tick (-1: none open) and the ticks since.
    std::int64_t rate_window_start_ns_{-1};
    std::uint64_t rate_window_ticks_{0};
    bool slow_fault_latched_{false};
    LoopStatisticsCollector statistics_;
    std::uint64_t window_ticks_;
    std::int64_t rate_window_ns_;  // fault 114's window
    msgs::LoopStatistics last_window_{};
    std::int64_t last_snapshot_ns_{0};
    std::uint64_t received_at_last_snapshot_{0};
    std::uint64_t late_input_ticks_{0};
    std::uint64_t status_seq_{0};
};

}  // namespace haptic::daemon
