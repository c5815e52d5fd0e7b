#!/usr/bin/env bash
# Builds the libFuzzer targets with Debian's clang (ASan + UBSan + libFuzzer) in build/fuzz
# and runs each for RUNS inputs (default 1 000 000) from a fixed seed. Any crash, sanitizer
# report or invariant trap makes it exit non-zero, with the crashing input saved in
# build/fuzz/artifacts/.
#
#   tests/drivers/fuzz/run_fuzz.sh            # 1M inputs per target (the documented run)
#   tests/drivers/fuzz/run_fuzz.sh 20000      # the short run CI does
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)
RUNS=${1:-1000000}
BUILD=${HAPTIC_FUZZ_BUILD:-$ROOT/build/fuzz}
command -v clang++ >/dev/null || { echo "run_fuzz: clang++ missing (Debian package clang)" >&2; exit 1; }

if [[ ! -f $BUILD/build.ninja ]]; then
  CC=clang CXX=clang++ cmake -S "$ROOT" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Debug \
    -DHAPTIC_SANITIZE=address -DHAPTIC_FUZZ=ON >/dev/null
fi
TARGETS=(fuzz_exoskeleton_frames fuzz_thimble_frames fuzz_udp_datagram)
ninja -C "$BUILD" -j2 "${TARGETS[@]}"
mkdir -p "$BUILD/artifacts"
for target in "${TARGETS[@]}"; do
  echo "=== $target: $RUNS inputs"
  start=$SECONDS
  log=$BUILD/artifacts/$target.log
  status=0
  UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1" ASAN_OPTIONS="detect_leaks=1" \
    "$BUILD/tests/drivers/fuzz/$target" -runs="$RUNS" -seed=1 -max_len=4096 \
    -artifact_prefix="$BUILD/artifacts/$target-" -print_final_stats=1 >"$log" 2>&1 || status=$?
  grep -E "^(Done|stat::number_of_executed_units|stat::peak_rss|SUMMARY)|ERROR" "$log" || true
  if ((status != 0)); then
    tail -40 "$log" >&2
    echo "run_fuzz: $target failed (exit $status); log and crashing input in $BUILD/artifacts" >&2
    exit "$status"
  fi
  echo "=== $target: no crash or sanitizer report in $RUNS inputs ($((SECONDS - start)) s)"
done
