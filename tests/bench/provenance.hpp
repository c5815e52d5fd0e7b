#pragma once

namespace haptic::bench {

// Prints, before any result, what a row of docs/benchmarks.md needs to be reproduced: the exact
// command line, the UTC date and time, and the machine (host name, kernel, CPU count, CPU
// model). Lines start with "# " so result parsers and CSV readers can skip them.
void printProvenance(int argc, char** argv);

}  // namespace haptic::bench
