#include "haptic/daemon/daemon_core.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace haptic::daemon {
namespace {
// The last quarter of the sim timeout is the fade-out window.
constexpr double kFadeFraction = 0.25;

// A command the hardware E-stop input forbids now, with the reason; nullptr when allowed.
const char* blockedByHardwareEstop(msgs::CommandKind kind, HardwareEstop input) noexcept {
    if (kind == msgs::CommandKind::kClearFault) {
        if (input == HardwareEstop::kPressed) {
            return "the hardware E-stop is pressed; release it, then clear";
        }
        if (input == HardwareEstop::kSilent) {
            return "the E-stop relay is silent (wiring, power or bus); it must report released "
                   "before clear";
        }
    }
    if (kind == msgs::CommandKind::kEnable && input == HardwareEstop::kAwaitingFirstStatus) {
        return "waiting for the E-stop relay's first status";
    }
    return nullptr;
}
}  // namespace

DaemonCore::DaemonCore(CoreSettings settings, std::vector<DeviceDescriptor> devices)
    : settings_(std::move(settings)),
      machine_(settings_.known_methods, settings_.rendering_method),
      statistics_(settings_.rate_hz),
      window_ticks_(static_cast<std::uint64_t>(std::max(1.0, settings_.rate_hz))),
      // At least 100 periods: over a window of a few, one late wake-up would halve the rate.
      rate_window_ns_(
          std::max(settings_.overrun_window_ns,
                   kRateWindowPeriods * static_cast<std::int64_t>(1e9 / settings_.rate_hz))) {
    devices_.reserve(devices.size());
    for (auto& descriptor : devices) {
        devices_.push_back(DeviceSlot{std::move(descriptor)});
    }
}

void DaemonCore::markStarted(std::int64_t now_ns) noexcept {
    started_ns_ = now_ns;
    last_tick_ns_ = now_ns;
    last_snapshot_ns_ = now_ns;
    machine_.started();
}

void DaemonCore::setHardwareEstop(HardwareEstop input, std::string_view relay) noexcept {
    const bool engaged = input == HardwareEstop::kPressed || input == HardwareEstop::kSilent;
    // A new engagement, or pressed turning silent (or back), is recorded; one that lasts is not.
    if (engaged && input != hardware_estop_ && machine_.state() != msgs::DaemonState::kInit) {
        (void)machine_.apply(msgs::CommandKind::kEstop, {});
        char message[msgs::kShortTextCapacity];  // no allocation on the RT thread
        const int length = static_cast<int>(relay.size());
        if (input == HardwareEstop::kPressed) {
            std::snprintf(message, sizeof(message), "E-stop pressed (relay %.*s)", length,
                          relay.data());
            machine_.raiseFault(kFaultEstopPressed, "estop", message);
        } else {
            std::snprintf(message, sizeof(message),
                          "E-stop relay silent (%.*s): treated as pressed", length, relay.data());
            machine_.raiseFault(kFaultEstopRelaySilent, "estop", message);
        }
    }
    if (machine_.state() != msgs::DaemonState::kInit) {
        hardware_estop_ = input;
    }
}

CommandOutcome DaemonCore::applyCommand(const msgs::HapticCommand& command, std::int64_t now_ns,
                                        msgs::HapticCommandReply& reply) noexcept {
    const char* blocked = blockedByHardwareEstop(command.kind, hardware_estop_);
    // Clearing a fault whose cause a device still shows would only bring it back next tick,
    // after a reply saying the daemon is IDLE: refuse it and say what stands.
    if (blocked == nullptr && command.kind == msgs::CommandKind::kClearFault) {
        for (const auto& slot : devices_) {
            if (slot.report.standing_fault != 0) {
                std::snprintf(refusal_, sizeof(refusal_),
                              "device '%s' still shows the cause of fault %u; clear once it "
                              "has gone (hapticctl status)",
                              slot.descriptor.name.c_str(),
                              static_cast<unsigned>(slot.report.standing_fault));
                blocked = refusal_;
                break;
            }
        }
    }
    const bool was_rendering = machine_.rendering();
    const CommandOutcome outcome = blocked != nullptr
                                       ? CommandOutcome{false, blocked}
                                       : machine_.apply(command.kind, command.argument.view());
    // Leaving RENDERING, or entering it, starts the enable's fade-in afresh: two commands
    // taken in one tick (disable then enable) must not skip it.
    if (outcome.accepted && (!was_rendering || !machine_.rendering())) {
        for (auto& slot : devices_) {
            slot.armed = 0.0;
        }
    }
    // An accepted enable (also while RENDERING) is the operator's re-arm.
    if (outcome.accepted && command.kind == msgs::CommandKind::kEnable) {
        for (auto& slot : devices_) {
            slot.awaiting_enable = false;
            slot.fed_while_rendering = false;
        }
    }
    reply = msgs::HapticCommandReply{};
    reply.header.seq = ++reply_seq_;
    reply.header.stamp_ns = now_ns;
    reply.header.source_id.assign("hapticd");
    reply.request_id = command.request_id;
    reply.accepted = outcome.accepted;
    reply.message.assign(outcome.reason);
    return outcome;
}

namespace {

// a - b, saturated: stamps come from another process and may be anything positive.
std::int64_t saturatingDifference(std::int64_t a, std::int64_t b) noexcept {
    std::int64_t difference = 0;
    if (__builtin_sub_overflow(a, b, &difference)) {
        return a > b ? std::numeric_limits<std::int64_t>::max()
                     : std::numeric_limits<std::int64_t>::min();
    }
    return difference;
}

}  // namespace

std::int64_t DaemonCore::relearnAfterNs() const noexcept {
    return std::max<std::int64_t>(2 * settings_.sim_rearm_after_ns, kMinRelearnAfterNs);
}

// A message renews the sim input only when its content is new:
// - its stamp is positive (a sim that stamps 0 or less has no clock to judge it by).
// - its seq advances. The same seq again is a duplicate or a replay, whatever its stamp. A seq
//   that goes back is a restarted sim (handsim counts from 1 again) only when its stamp is
//   later than the last accepted one (the sim host's CLOCK_MONOTONIC does not go back); else
//   it is an old message replayed.
// - it is neither older than the sim timeout nor stamped more than that ahead. Over iceoryx
//   the sim runs on this host and stamps with our CLOCK_MONOTONIC: its age is now minus its
//   stamp. Over DDS it may run on another host, whose monotonic clock is not ours, so its age
//   is the one-way delay relative to the quickest message seen from this sim: arrival minus
//   stamp, less the smallest arrival minus stamp so far. That smallest value may creep up by
//   kClockDriftAllowance of the elapsed time; a restart starts it afresh. Until
//   kLearningMessages have come since it was (re)learnt, the median of their offsets stands
//   for it instead. A stamp far ahead of it is refused, so that one corrupt or stepped stamp
//   cannot become the quickest message and make every later one read as delayed.
// Over DDS only: content refused as not newer or stamped ahead that forms a stream of its own (seq
// advancing from message to message) for relearnAfterNs() is a sim whose clock really changed (its
// host rebooted, its clock was stepped): it is then taken, and its clock learnt afresh. By then
// the input has been lost for longer than sim_rearm_after_ns, so the force returns only after an
// operator's `enable`. After a silence that long the clock is learnt afresh too, rather than
// allowing it that much drift.
InputRejection DaemonCore::freshness(const DeviceSlot& slot, const msgs::MessageHeader& header,
                                     std::int64_t now_ns, Freshness& out) const noexcept {
    out = Freshness{slot.clock_offset_ns, slot.other_stream_since_ns, slot.other_stream_seq,
                    slot.clock_learning};
    if (header.stamp_ns <= 0) {
        return InputRejection::kBadStamp;
    }
    const std::int64_t offset_ns = saturatingDifference(now_ns, header.stamp_ns);
    const auto byDelay = [this](std::int64_t delay_ns) {
        if (delay_ns > settings_.sim_timeout_ns) {
            return InputRejection::kDelayed;
        }
        return delay_ns < -settings_.sim_timeout_ns ? InputRejection::kStampAhead
                                                    : InputRejection::kNone;
    };
    const bool not_newer =
        slot.has_header && (header.seq == slot.last_seq ||
                            (header.seq < slot.last_seq && header.stamp_ns <= slot.last_stamp_ns));
    if (settings_.sim_transport == msgs::SimTransport::kIceoryx) {
        // Shared memory: the sim runs on this host and stamps with this CLOCK_MONOTONIC, so
        // its age is absolute (ahead by up to a tick: it may stamp after our tick began).
        return not_newer ? InputRejection::kNotNewer : byDelay(offset_ns);
    }
    const auto learnAfresh = [&] {
        out = Freshness{offset_ns, -1, 0, ClockLearning{{offset_ns}, 1}};
        return InputRejection::kNone;
    };
    if (!slot.has_header) {
        return learnAfresh();
    }
    InputRejection verdict = InputRejection::kNone;
    if (not_newer) {
        verdict = InputRejection::kNotNewer;
    } else if (header.seq < slot.last_seq ||
               saturatingDifference(now_ns, slot.last_heard_ns) > relearnAfterNs()) {
        // A restarted sim (its clock may be another host's), or the first message after a
        // silence (no valid message at all, refused ones included: a path slower for good
        // must not pass for a silence).
        return learnAfresh();
    } else if (out.learning.count < kLearningMessages) {
        // Still learning: judged against the median of the offsets so far, its own included,
        // so that one corrupt stamp among the first cannot set the clock.
        out.learning.offsets[out.learning.count++] = offset_ns;
        auto sorted = out.learning.offsets;
        for (std::size_t i = 1; i < out.learning.count; ++i) {  // at most 5: insertion sort
            for (std::size_t j = i; j > 0 && sorted[j] < sorted[j - 1]; --j) {
                std::swap(sorted[j], sorted[j - 1]);
            }
        }
        out.clock_offset_ns = sorted[out.learning.count / 2];
        verdict = byDelay(saturatingDifference(offset_ns, out.clock_offset_ns));
        if (verdict == InputRejection::kNone) {
            return verdict;
        }
    } else {
        const auto drift_ns = static_cast<std::int64_t>(
            kClockDriftAllowance * static_cast<double>(std::max<std::int64_t>(
                                       0, saturatingDifference(now_ns, slot.last_accepted_ns))));
        const std::int64_t allowed_offset_ns = slot.clock_offset_ns + drift_ns;
        verdict = byDelay(saturatingDifference(offset_ns, allowed_offset_ns));
        if (verdict == InputRejection::kNone) {
            out.clock_offset_ns = std::min(offset_ns, allowed_offset_ns);
            out.other_stream_since_ns = -1;
            return verdict;
        }
    }
    // Refused. Content that only looks old (delayed) never forms a stream to adopt: a slower
    // path serves old content; a restarted sim re-learns its clock anyway.
    if (verdict == InputRejection::kDelayed) {
        out.other_stream_since_ns = -1;
        return verdict;
    }
    const bool continues = slot.other_stream_since_ns >= 0 && header.seq > slot.other_stream_seq;
    out.other_stream_since_ns = continues ? slot.other_stream_since_ns : now_ns;
    out.other_stream_seq = header.seq;
    if (continues && saturatingDifference(now_ns, slot.other_stream_since_ns) >= relearnAfterNs()) {
        return learnAfresh();
    }
    return verdict;
}

InputRejection DaemonCore::account(DeviceSlot& slot, InputRejection reason,
                                   const msgs::MessageHeader& header,
                                   std::int64_t now_ns) noexcept {
    Freshness judged{slot.clock_offset_ns, slot.other_stream_since_ns, slot.other_stream_seq,
                     slot.clock_learning};
    if (reason == InputRejection::kNone) {
        reason = freshness(slot, header, now_ns, judged);
        slot.last_heard_ns = now_ns;
    }
    // What the sim's clock was learnt to be, refused messages included (they count while it
    // is being learnt, and towards a stream of their own).
    slot.clock_offset_ns = judged.clock_offset_ns;
    slot.clock_learning = judged.learning;
    slot.other_stream_since_ns = judged.other_stream_since_ns;
    slot.other_stream_seq = judged.other_stream_seq;
    if (reason == InputRejection::kNone) {
        ++slot.received;
        slot.last_accepted_ns = now_ns;
        slot.last_seq = header.seq;
        slot.last_stamp_ns = header.stamp_ns;
        slot.has_header = true;
    } else {
        ++slot.rejected;
        ++slot.rejected_by[static_cast<std::size_t>(reason)];
    }
    return reason;
}

InputRejection DaemonCore::offerConstraintSet(std::size_t device,
                                              const msgs::ConstraintSet& message,
                                              std::int64_t now_ns) noexcept {
    DeviceSlot& slot = devices_[device];
    return admit(slot, validate(message, slot.descriptor.name, slot.descriptor.joint_count),
                 message, slot.constraint_set, slot.has_constraint_set, now_ns);
}

InputRejection DaemonCore::offerContactSurface(std::size_t device,
                                               const msgs::ContactSurface& message,
                                               std::int64_t now_ns) noexcept {
    DeviceSlot& slot = devices_[device];
    return admit(slot, validate(message, slot.descriptor.name), message, slot.contact_surface,
                 slot.has_contact_surface, now_ns);
}

double DaemonCore::ageMs(const DeviceSlot& slot, std::int64_t now_ns) const noexcept {
    if (slot.last_accepted_ns < 0) {
        return std::numeric_limits<double>::infinity();
    }
    return static_cast<double>(now_ns - slot.last_accepted_ns) * 1e-6;
}

void DaemonCore::update(std::int64_t now_ns, const TickTiming& timing) noexcept {
    // A stalled thread (debugger, VM hiccup) must not turn into one big ramp step: the ramp
    // advances at most one nominal period per tick.
    const double period_s = 1.0 / settings_.rate_hz;
    const double dt_s =
        std::clamp(static_cast<double>(now_ns - last_tick_ns_) * 1e-9, 0.0, period_s);
    const std::int64_t gap_ns = now_ns - last_tick_ns_;
    last_tick_ns_ = now_ns;
    // Only a device that hears us can time out on our silence: with none online (hapticd may
    // start before the devices) a stall has no one to endanger and is only counted as an
    // overrun by the loop statistics.
    bool any_online = false;
    for (const auto& slot : devices_) {
        any_online =
            any_online || (slot.report.status_bits &
                           static_cast<std::uint32_t>(msgs::DeviceStatusBit::kOnline)) != 0;
    }
    if (settings_.stall_limit_ns > 0 && gap_ns > settings_.stall_limit_ns && any_online) {
        last_stall_end_ns_ = now_ns;
        char message[msgs::kShortTextCapacity];  // no allocation on the RT thread
        std::snprintf(message, sizeof(message),
                      "loop stalled %.1f ms (limit %.1f ms); devices safe by their timeout",
                      static_cast<double>(gap_ns) * 1e-6,
                      static_cast<double>(settings_.stall_limit_ns) * 1e-6);
        machine_.raiseFault(kFaultLoopStalled, "hapticd", message);
    }
    countOverrun(now_ns, timing, any_online);
    checkRate(now_ns, any_online);
    const double timeout_ms = static_cast<double>(settings_.sim_timeout_ns) * 1e-6;
    const double fade_in_s = std::max(1e-9, static_cast<double>(settings_.fade_in_ns) * 1e-9);

    const double rearm_after_ms = static_cast<double>(settings_.sim_rearm_after_ns) * 1e-6;
    bool late = false;
    for (auto& slot : devices_) {
        const double age_ms = ageMs(slot, now_ns);
        // Re-arm policy: an outage longer than sim_rearm_after_ns is the operator's to end.
        // Input that has never been fresh since the enable (the sim starting after it) is not
        // an outage.
        if (!machine_.rendering()) {
            slot.fed_while_rendering = false;
            slot.awaiting_enable = false;
        } else {
            slot.fed_while_rendering = slot.fed_while_rendering || age_ms < timeout_ms;
            if (slot.fed_while_rendering && settings_.sim_rearm_after_ns > 0 &&
                age_ms > rearm_after_ms) {
                slot.awaiting_enable = true;
            }
        }
        // Full force up to 3/4 of the timeout, zero at the timeout. Starting the fade late
        // keeps normal sim jitter (a 100 Hz sim delivers every ~10 ms) from modulating force.
        const double fade_start_ms = (1.0 - kFadeFraction) * timeout_ms;
        const double target =
            slot.awaiting_enable
                ? 0.0
                : std::clamp(1.0 - (age_ms - fade_start_ms) / (kFadeFraction * timeout_ms), 0.0,
                             1.0);
        // Falling follows the target at once; rising is rate limited so force never steps up.
        slot.fade = std::min(target, slot.fade + dt_s / fade_in_s);
        slot.armed = machine_.rendering() ? std::min(1.0, slot.armed + dt_s / fade_in_s) : 0.0;
        late = late || (target > 0.0 && target < 1.0);
    }
    // A sim that delivers slower than the fade start modulates the force at its own rate
    // (the demo's 60 Hz scene did); counted so that status can say so.
    late_input_ticks_ += late ? 1U : 0U;

    statistics_.add(timing);
    if (statistics_.windowCount() >= window_ticks_) {
        statistics_.closeWindow(last_window_);
    }
}

void DaemonCore::countOverrun(std::int64_t now_ns, const TickTiming& timing,
                              bool any_online) noexcept {
    const std::size_t limit = std::min<std::size_t>(settings_.overrun_limit, kMaxOverrunLimit);
    const double work_us = timing.read_us + timing.compute_us + timing.write_us;
    // Only a device that hears us is endangered by late commands (as for a stall).
    if (limit == 0 || !any_online || !(work_us > 1e6 / settings_.rate_hz)) {
        return;
    }
    // Raised once until an operator clears it; counted afresh after the clear (another fault
    // raised since the clear does not keep it latched).
    if (overrun_fault_latched_ && !faultListed(kFaultLoopOverrunning)) {
        overrun_fault_latched_ = false;
        overrun_count_ = 0;
    }
    // The ring holds the times of the last `limit` overruns, the oldest where the next goes.
    overrun_times_ns_[overrun_next_] = now_ns;
    overrun_next_ = (overrun_next_ + 1) % limit;
    overrun_count_ = std::min(overrun_count_ + 1, limit);
    if (overrun_count_ < limit || overrun_fault_latched_ ||
        now_ns - overrun_times_ns_[overrun_next_] > settings_.overrun_window_ns) {
        return;
    }
    char message[msgs::kShortTextCapacity];  // no allocation on the RT thread
    std::snprintf(message, sizeof(message),
                  "loop overrunning: %zu ticks past the %.0f us period within %.0f ms", limit,
                  1e6 / settings_.rate_hz, static_cast<double>(settings_.overrun_window_ns) * 1e-6);
    machine_.raiseFault(kFaultLoopOverrunning, "hapticd", message);
    overrun_fault_latched_ = true;
}

bool DaemonCore::faultListed(std::uint32_t code) const noexcept {
    for (std::size_t i = 0; i < machine_.faultCount(); ++i) {
        if (machine_.fault(i).code == code) {
            return true;
        }
    }
    return false;
}

void DaemonCore::checkRate(std::int64_t now_ns, bool any_online) noexcept {
    if (settings_.overrun_limit == 0 || settings_.overrun_window_ns <= 0 || !any_online) {
        rate_window_start_ns_ = -1;
        return;
    }
    // A window opens with a device online, and again after a stall, which is its own fault.
    if (rate_window_start_ns_ < 0 || last_stall_end_ns_ > rate_window_start_ns_) {
        rate_window_start_ns_ = now_ns;
        rate_window_ticks_ = 0;
        return;
    }
    ++rate_window_ticks_;
    const std::int64_t elapsed_ns = now_ns - rate_window_start_ns_;
    if (elapsed_ns < rate_window_ns_) {
        return;
    }
    const double rate_hz =
        static_cast<double>(rate_window_ticks_) * 1e9 / static_cast<double>(elapsed_ns);
    rate_window_start_ns_ = now_ns;
    rate_window_ticks_ = 0;
    // Raised once until an operator clears it (another fault raised meanwhile, say 111 of the
    // same slow loop, does not keep it latched).
    slow_fault_latched_ = slow_fault_latched_ && faultListed(kFaultLoopTooSlow);
    if (slow_fault_latched_ || !(rate_hz < 0.5 * settings_.rate_hz)) {
        return;
    }
    char message[msgs::kShortTextCapacity];  // no allocation on the RT thread
    std::snprintf(message, sizeof(message), "loop too slow: %.0f Hz over %.0f ms (rate %.0f Hz)",
                  rate_hz, static_cast<double>(elapsed_ns) * 1e-6, settings_.rate_hz);
    machine_.raiseFault(kFaultLoopTooSlow, "hapticd", message);
    slow_fault_latched_ = true;
}

void DaemonCore::fillDeviceState(std::size_t device, std::int64_t now_ns,
                                 msgs::DeviceState& out) noexcept {
    DeviceSlot& slot = devices_[device];
    out = msgs::DeviceState{};
    out.header.seq = ++slot.state_seq;
    out.header.stamp_ns = now_ns;
    out.header.source_id.assign(slot.descriptor.name);
    out.joint_count = slot.descriptor.joint_count;
    out.actuator_count = slot.descriptor.actuator_count;
    // Without a runtime's report the sensed values stay zero and the device is offline and
    // in its safe state (the report's defaults).
    const DeviceReport& report = slot.report;
    out.joint_position_rad = report.joint_position_rad;
    out.joint_velocity_rad_per_s = report.joint_velocity_rad_per_s;
    out.actuator_position = report.actuator_position;
    out.actuator_force = report.actuator_force;
    out.platform_position_m = report.platform_position_m;
    out.platform_orientation_wxyz = report.platform_orientation_wxyz;
    std::uint32_t bits = report.status_bits;
    if (machine_.rendering() && slot.fade > 0.0 &&
        (bits & static_cast<std::uint32_t>(msgs::DeviceStatusBit::kSafeState)) == 0) {
        bits |= static_cast<std::uint32_t>(msgs::DeviceStatusBit::kRendering);
    }
    if (slot.fade < 1.0) {
        bits |= static_cast<std::uint32_t>(msgs::DeviceStatusBit::kStaleSimInput);
    }
    out.status_bits = bits;
}

std::uint64_t DaemonCore::rejectedCount(std::size_t device, InputRejection reason) const noexcept {
    return devices_[device].rejected_by[static_cast<std::size_t>(reason)];
}

void DaemonCore::fillTelemetry(std::size_t device, std::uint64_t tick, std::int64_t now_ns,
                               const TickTiming& timing,
                               msgs::TelemetrySample& out) const noexcept {
    out = msgs::TelemetrySample{};
    out.tick = tick;
    out.stamp_ns = now_ns;
    out.device_index = static_cast<std::uint16_t>(device);
    const DeviceReport& report = devices_[device].report;
    out.device_kind = report.kind;
    out.exoskeleton = report.exoskeleton;
    out.thimble = report.thimble;
    out.tick_work_us = timing.read_us + timing.compute_us + timing.write_us;
    out.read_us = timing.read_us;
    out.write_us = timing.write_us;
    out.wakeup_latency_us = timing.wakeup_latency_us;
    // The tracker sample behind the input this tick rendered (for the tracker-to-force latency).
    const DeviceSlot& slot = devices_[device];
    if (slot.has_constraint_set) {
        out.tracking = slot.constraint_set.tracking;
    } else if (slot.has_contact_surface) {
        out.tracking = slot.contact_surface.tracking;
    }
}

bool DaemonCore::snapshotDue(std::int64_t now_ns) const noexcept {
    return now_ns - last_snapshot_ns_ >= settings_.status_period_ns;
}

void DaemonCore::fillStatus(std::int64_t now_ns, msgs::HapticStatus& out) noexcept {
    out = msgs::HapticStatus{};
    out.header.seq = ++status_seq_;
    out.header.stamp_ns = now_ns;
    out.header.source_id.assign("hapticd");
    out.state = machine_.state();
    out.rendering_method = machine_.method();
    out.version.assign(settings_.version);
    out.config_digest.assign(settings_.config_digest);
    out.uptime_s = static_cast<double>(now_ns - started_ns_) * 1e-9;
    // Percentiles cover the last full one-second window; counters are live.
    out.loop = last_window_;
    statistics_.fillCounters(out.loop);

    std::uint64_t received = 0;
    std::uint64_t rejected = 0;
    double newest_age_ms = std::numeric_limits<double>::infinity();
    for (const auto& slot : devices_) {
        msgs::DeviceStatus status;
        status.device_id.assign(slot.descriptor.name);
        status.kind = slot.descriptor.kind;
        status.state = slot.report.run_state;
        status.last_frame_age_ms = slot.report.last_frame_age_ms;
        status.awaiting_enable = slot.awaiting_enable;
        status.can = slot.report.can;
        out.devices.push_back(status);
        received += slot.received;
        rejected += slot.rejected;
        for (std::size_t reason = 1; reason < slot.rejected_by.size(); ++reason) {
            out.sim_link.rejected_by_reason[reason - 1] += slot.rejected_by[reason];
        }
        newest_age_ms = std::min(newest_age_ms, ageMs(slot, now_ns));
    }

    for (std::size_t i = 0; i < machine_.faultCount(); ++i) {
        out.faults.push_back(machine_.fault(i));
    }

    const double window_s = static_cast<double>(now_ns - last_snapshot_ns_) * 1e-9;
    out.sim_link.transport = settings_.sim_transport;
    out.sim_link.connected = newest_age_ms <= static_cast<double>(settings_.sim_timeout_ns) * 1e-6;
    out.sim_link.age_ms = std::isfinite(newest_age_ms) ? newest_age_ms : -1.0;
    out.sim_link.rate_hz =
        window_s > 0.0 ? static_cast<double>(received - received_at_last_snapshot_) / window_s
                       : 0.0;
    out.sim_link.received = received;
    out.sim_link.rejected = rejected;
    out.sim_link.late_input_ticks = late_input_ticks_;

    received_at_last_snapshot_ = received;
    last_snapshot_ns_ = now_ns;
}

}  // namespace haptic::daemon
