#pragma once

namespace haptic::bench {

// What BENCHMARK_MAIN() does, after the provenance lines (provenance.hpp): Google Benchmark's
// own flags, then every registered benchmark. Returns main()'s exit status (1 on an unknown
// flag). For programs that need start-up work of their own before the run.
int runGoogleBenchmarks(int argc, char** argv);

}  // namespace haptic::bench
