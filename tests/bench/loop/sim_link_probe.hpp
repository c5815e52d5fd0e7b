#pragma once

// The sim -> daemon latency probe: hapticd's own take path (the iceoryx subscriber options of
// daemon_app.cpp, or the DdsSimLink class) polled by a 1 kHz absolute-time loop with the
// daemon's real-time settings, against a real handsim process. Latency per message = the
// tick time it was taken at - its header stamp (CLOCK_MONOTONIC in both processes, so the
// sim must run on this host). It runs in its own process (the benchmark re-executes itself),
// so its iceoryx registration ends before RouDi stops.

#include <string>

#include "haptic/config/daemon.hpp"

namespace haptic::bench {

enum class ProbeTransport { kIceoryx, kDds };

// The tick's phase relative to the sim's is fixed within one run, so the tick latency of a
// run is the delivery latency plus a wait of 0-1 ms that depends on that phase. The probe
// therefore also measures delivery alone: a second subscriber to the exoskeleton's messages,
// woken by the transport (iceoryx WaitSet, DDS wait_for_unread_message).
//
// Runs for `duration_s` (the first 0.5 s, which may hold a stale history sample, is not
// counted) and prints two lines, "probe <count> <p50> <p99> <p99.9> <max>" (taken by the
// tick) and "delivery ..." (the same for delivery), in microseconds. Returns the exit code.
int runSimLinkProbe(const config::DaemonConfig& cfg, ProbeTransport transport, double duration_s);

}  // namespace haptic::bench
