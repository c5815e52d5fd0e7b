#pragma once

#include <string>
#include <string_view>

namespace haptic::process {

// One logging setup for every executable. Under systemd (JOURNAL_STREAM names our stderr)
// records go to the journal with their priority; otherwise to stderr with a timestamp.
// The RT thread never logs: it pushes events through a lock-free queue that a non-RT
// thread drains.
void setupLogging(std::string_view program_name, std::string_view level);

// True when stderr is connected to the systemd journal.
bool runningUnderJournal();

// Valid names for setupLogging's level.
inline constexpr std::string_view kLogLevels = "trace, debug, info, warn, error";

}  // namespace haptic::process
