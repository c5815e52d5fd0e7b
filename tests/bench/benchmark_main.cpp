// main() of the Google Benchmark programs: the provenance lines first (provenance.hpp), then
// Google Benchmark's own flags and run, as BENCHMARK_MAIN() would.
#include <benchmark/benchmark.h>

#include "provenance.hpp"

int main(int argc, char** argv) {
    haptic::bench::printProvenance(argc, argv);
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) {
        return 1;
    }
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
