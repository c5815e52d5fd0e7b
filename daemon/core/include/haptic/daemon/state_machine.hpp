#pragma once

// hapticd's state machine, free of I/O and allocation after construction, so the RT thread
// applies operator commands and faults directly and tests drive every transition.
//
//   INIT ──started──▶ IDLE ──enable──▶ RENDERING
//                      ▲  ◀──disable──    │
//                      │                  │ fault
//                    clear                ▼
//   any but INIT ─estop─▶ E-STOP   IDLE/RENDERING ──fault──▶ FAULT (latched)
//   E-STOP ──clear──▶ IDLE         FAULT ──clear──▶ IDLE
//
// - Only RENDERING sends force to the devices; every other state holds them safe.
// - FAULT is latched: the fault stays listed and the daemon stays safe until an operator
//   clears it, even if the cause is gone. Clearing re-arms to IDLE, never straight to
//   RENDERING: rendering always needs an explicit enable.
// - Re-arm after an outage (DaemonCore, CoreSettings::sim_rearm_after_ns, daemon.yaml
//   loop.sim_rearm_after_ms): while RENDERING, a device whose sim input was fresh and then
//   stayed stale for longer than that renders again only after a new `enable` (accepted while
//   RENDERING for exactly this), however fresh its input has become; a shorter outage fades out
//   and back in by itself. A device that goes offline while RENDERING raises a latched fault
//   (heartbeat lost), so it too comes back only through clear and enable.
// - E-STOP wins over everything and is left only by clear (then IDLE). A fault raised during
//   E-STOP is recorded but does not leave E-STOP.
// - The rendering method may change in IDLE and while RENDERING (the exoskeleton's channel
//   then blends into the new coupling within the force rate limit, so the finger feels no
//   step); not in FAULT or E-STOP.
// - Idempotent commands (enable while RENDERING, disable while IDLE, estop while E-STOP) are
//   accepted and change nothing. Every refusal carries a reason for the operator.

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "haptic/msgs/messages.hpp"
#include "haptic/msgs/names.hpp"  // toString(DaemonState), the name the journal and status use

namespace haptic::daemon {

struct CommandOutcome {
    bool accepted{false};
    // Static text, safe to copy on the RT thread.
    const char* reason{""};
};

class DaemonStateMachine {
  public:
    static constexpr std::size_t kMaxFaults = msgs::kMaxStatusFaults;

    // known_methods: the rendering methods a set-method command may name.
    DaemonStateMachine(std::vector<std::string> known_methods, std::string_view initial_method);

    [[nodiscard]] msgs::DaemonState state() const noexcept { return state_; }
    [[nodiscard]] const msgs::DeviceId& method() const noexcept { return method_; }
    [[nodiscard]] bool rendering() const noexcept {
        return state_ == msgs::DaemonState::kRendering;
    }

    // INIT -> IDLE once the loop runs. Ignored in any other state.
    void started() noexcept;

    // Applies an operator command; the state changes only when the outcome is accepted.
    CommandOutcome apply(msgs::CommandKind kind, std::string_view argument) noexcept;

    // A safety fault from a device or the loop: IDLE and RENDERING go to FAULT. The fault is
    // listed until cleared (the list keeps the first kMaxFaults; later ones are counted).
    void raiseFault(std::uint32_t code, std::string_view device_id,
                    std::string_view message) noexcept;

    [[nodiscard]] std::size_t faultCount() const noexcept { return fault_count_; }
    [[nodiscard]] const msgs::Fault& fault(std::size_t index) const noexcept {
        return faults_[index];
    }
    [[nodiscard]] std::uint64_t droppedFaults() const noexcept { return dropped_faults_; }

  private:
    CommandOutcome setMethod(std::string_view name) noexcept;

    std::vector<std::string> known_methods_;
    msgs::DaemonState state_{msgs::DaemonState::kInit};
    msgs::DeviceId method_{};
    std::array<msgs::Fault, kMaxFaults> faults_{};
    std::size_t fault_count_{0};
    std::uint64_t dropped_faults_{0};
};

}  // namespace haptic::daemon
