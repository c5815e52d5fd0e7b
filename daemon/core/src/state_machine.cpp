#include "haptic/daemon/state_machine.hpp"

#include <algorithm>

namespace haptic::daemon {

using msgs::CommandKind;
using msgs::DaemonState;

DaemonStateMachine::DaemonStateMachine(std::vector<std::string> known_methods,
                                       std::string_view initial_method)
    : known_methods_(std::move(known_methods)) {
    method_.assign(initial_method);
}

void DaemonStateMachine::started() noexcept {
    if (state_ == DaemonState::kInit) {
        state_ = DaemonState::kIdle;
    }
}

CommandOutcome DaemonStateMachine::setMethod(std::string_view name) noexcept {
    // While RENDERING the exoskeleton's channel blends into the new method within the force
    // rate limit (exoskeleton_channel.hpp); in FAULT or E-STOP nothing renders to switch.
    if (state_ != DaemonState::kIdle && state_ != DaemonState::kRendering) {
        return {false, "the rendering method can change only in IDLE or RENDERING"};
    }
    const bool known = std::any_of(known_methods_.begin(), known_methods_.end(),
                                   [&](const std::string& method) { return method == name; });
    if (!known) {
        return {false, "unknown rendering method"};
    }
    method_.assign(name);
    return {true, "rendering method changed"};
}

CommandOutcome DaemonStateMachine::apply(CommandKind kind, std::string_view argument) noexcept {
    if (state_ == DaemonState::kInit) {
        return {false, "the daemon is still initialising"};
    }
    switch (kind) {
        case CommandKind::kEstop:
            // E-stop is accepted in every running state, including FAULT and E-STOP itself.
            state_ = DaemonState::kEstop;
            return {true, "emergency stop: forces off until clear"};
        case CommandKind::kClearFault:
            if (state_ == DaemonState::kFault || state_ == DaemonState::kEstop) {
                state_ = DaemonState::kIdle;
                fault_count_ = 0;
                dropped_faults_ = 0;
                return {true, "cleared; daemon is IDLE, enable to render"};
            }
            return {false, "nothing to clear: no fault and no emergency stop"};
        case CommandKind::kEnable:
            if (state_ == DaemonState::kIdle) {
                state_ = DaemonState::kRendering;
                return {true, "rendering enabled"};
            }
            if (state_ == DaemonState::kRendering) {
                return {true, "already rendering"};
            }
            return {false, state_ == DaemonState::kFault
                               ? "a fault is latched; clear it before enabling"
                               : "emergency stop is active; clear it before enabling"};
        case CommandKind::kDisable:
            if (state_ == DaemonState::kRendering) {
                state_ = DaemonState::kIdle;
                return {true, "rendering disabled"};
            }
            if (state_ == DaemonState::kIdle) {
                return {true, "already idle"};
            }
            return {false, state_ == DaemonState::kFault
                               ? "a fault is latched; forces are already off, clear it instead"
                               : "emergency stop is active; forces are already off, clear it "
                                 "instead"};
        case CommandKind::kSetMethod:
            return setMethod(argument);
    }
    return {false, "unknown command"};
}

void DaemonStateMachine::raiseFault(std::uint32_t code, std::string_view device_id,
                                    std::string_view message) noexcept {
    if (fault_count_ < faults_.size()) {
        msgs::Fault& fault = faults_[fault_count_++];
        fault.code = code;
        fault.device_id.assign(device_id);
        fault.message.assign(message);
    } else {
        ++dropped_faults_;
    }
    if (state_ == DaemonState::kIdle || state_ == DaemonState::kRendering ||
        state_ == DaemonState::kInit) {
        state_ = DaemonState::kFault;
    }
}

}  // namespace haptic::daemon
