// main() of the Google Benchmark programs without start-up work of their own.
#include "benchmark_runner.hpp"

int main(int argc, char** argv) {
    return haptic::bench::runGoogleBenchmarks(argc, argv);
}
