#include "benchmark_runner.hpp"

#include <benchmark/benchmark.h>

#include "provenance.hpp"

namespace haptic::bench {

int runGoogleBenchmarks(int argc, char** argv) {
    printProvenance(argc, argv);
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) {
        return 1;
    }
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}

}  // namespace haptic::bench
