#pragma once

// What changed between two status snapshots, as journal lines. The RT thread never logs, so
// hapticd's non-RT thread compares each snapshot it publishes with the last one and logs
// these: `journalctl -u hapticd` then says why the daemon went to FAULT or E-STOP, and when.
// Not on the RT path (it builds strings).

#include <string>
#include <vector>

#include "haptic/msgs/messages.hpp"

namespace haptic::daemon {

struct JournalLine {
    enum class Level { kInfo, kWarning, kError };
    Level level{Level::kInfo};
    std::string text;
};

// `before` is null for the first snapshot: then every fault it holds is new, and its state is
// reported as the state hapticd starts in.
[[nodiscard]] std::vector<JournalLine> statusChanges(const msgs::HapticStatus* before,
                                                     const msgs::HapticStatus& after);

}  // namespace haptic::daemon
