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
// loop on purpose never calls this.

#include <string>

namespace haptic::testing {

inline constexpr int kMaxAttempts = 3;

// Records the first "loop stalled" fault line of `hapticd_log`, if any, unless hapticd is no
// longer running (it crashed or exited: that failure stands) or its log holds a sanitizer's
// report.
void noteFailureAfterLoopStall(const std::string& hapticd_log, bool hapticd_running);

}  // namespace haptic::testing
