#include "haptic/daemon/status_journal.hpp"

#include <algorithm>

#include "haptic/msgs/names.hpp"

namespace haptic::daemon {
namespace {

// A latched fault is the same fault while its code and device stay; its message is written
// once, when it latches.
bool sameFault(const msgs::Fault& a, const msgs::Fault& b) {
    return a.code == b.code && a.device_id.view() == b.device_id.view();
}

bool holds(const msgs::HapticStatus& status, const msgs::Fault& fault) {
    return std::any_of(status.faults.begin(), status.faults.end(),
                       [&](const msgs::Fault& f) { return sameFault(f, fault); });
}

std::string describe(const msgs::Fault& fault) {
    std::string text = "[" + std::to_string(fault.code) + "] ";
    if (!fault.device_id.view().empty()) {
        text += std::string(fault.device_id.view()) + ": ";
    }
    return text + std::string(fault.message.view());
}

}  // namespace

std::vector<JournalLine> statusChanges(const msgs::HapticStatus* before,
                                       const msgs::HapticStatus& after) {
    using Level = JournalLine::Level;
    std::vector<JournalLine> lines;
    for (const msgs::Fault& fault : after.faults) {
        if (before == nullptr || !holds(*before, fault)) {
            lines.push_back({Level::kError, "fault " + describe(fault)});
        }
    }
    if (before != nullptr) {
        for (const msgs::Fault& fault : before->faults) {
            if (!holds(after, fault)) {
                lines.push_back({Level::kInfo, "fault cleared: " + describe(fault)});
            }
        }
    }
    if (before == nullptr || before->state != after.state) {
        const bool stopped =
            after.state == msgs::DaemonState::kFault || after.state == msgs::DaemonState::kEstop;
        std::string text = "state ";
        if (before != nullptr) {
            text += std::string(msgs::toString(before->state)) + " -> ";
        }
        text += msgs::toString(after.state);
        lines.push_back({stopped ? Level::kWarning : Level::kInfo, std::move(text)});
    }
    return lines;
}

}  // namespace haptic::daemon
