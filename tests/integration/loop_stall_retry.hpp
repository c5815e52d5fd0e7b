#pragma once

// A retry for the process tests, and only for one cause: this VM's host descheduling
// hapticd's SCHED_FIFO thread past the devices' 10 ms command timeout. hapticd then does what
// it must (latches fault 110, "loop stalled", devices safe by their own timeout), and the
// test's scenario cannot go on. A CI run lost a landing to it: three 13 ms stalls within one
// second, 0.9 s into DeviceSafetyTest.SimKilledWhileRenderingFadesTheForceToZeroAndOnlyAnEnable-
// BringsItBack, with the test's processes running alone (RUN_SERIAL).
//
// A fixture's TearDown hands hapticd's log to noteFailureAfterLoopStall() when its test
// failed. The test binary's main (loop_stall_retry.cpp) then runs the same tests again in a
// fresh process image, at most kMaxAttempts in all, printing why (scripts/test.sh counts
// the retries of a run from ctest's log). A failure without such a stall, with hapticd gone
// or a sanitizer's report in its log, or on the last attempt, stands; a test that stalls the
// loop on purpose never calls this. A test that ends hapticd itself (--duration) and judges
// its fail-stop hands the exited hapticd's log to noteFailureAfterFailStopStall() instead.

#include <optional>
#include <string>

namespace haptic::testing {

inline constexpr int kMaxAttempts = 3;

// Records the first "loop stalled" fault line of `hapticd_log`, if any, unless hapticd is no
// longer running (it crashed or exited: that failure stands) or its log holds a sanitizer's
// report.
void noteFailureAfterLoopStall(const std::string& hapticd_log, bool hapticd_running);

// The same for a test that ends hapticd on purpose and judges its fail-stop: records the line
// hapticd logs at exit when its loop stalled in its last ticks or its fail-stop ("fail-stop:
// loop stalled"), or the stall fault journaled before, if `hapticd_exit_code` is 0 and the log
// holds no sanitizer's report. A crash, a refused start or no stall line: the failure stands.
void noteFailureAfterFailStopStall(const std::string& hapticd_log,
                                   std::optional<int> hapticd_exit_code);

}  // namespace haptic::testing
