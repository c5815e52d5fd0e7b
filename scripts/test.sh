#!/usr/bin/env bash
# The README's test command. On a fresh machine it installs the Debian packages, then builds
# and runs every test in a Release build and an ASan+UBSan build, and the threaded tests
# (ctest label `threaded`: the exchanges between hapticd's RT thread and the rest) in a TSan
# build.
#
#   scripts/test.sh              all three (what CI runs)
#   scripts/test.sh release      only the Release build
#   scripts/test.sh asan         only the ASan+UBSan build
#   scripts/test.sh tsan         only the TSan build of the threaded tests
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$ROOT/scripts/install-deps.sh"

variants=("$@")
if ((${#variants[@]} == 0)); then
  variants=(release asan tsan)
fi

run_variant() {
  local variant=$1 build_type sanitize
  case "$variant" in
    release) build_type=Release; sanitize="" ;;
    asan) build_type=Debug; sanitize=address ;;
    tsan) build_type=Debug; sanitize=thread ;;
    *) echo "test.sh: unknown variant '$variant' (release, asan, tsan)" >&2; exit 2 ;;
  esac
  local build="$ROOT/build/$variant"
  echo "=== $variant: configure and build in $build"
  local start=$SECONDS
  cmake -S "$ROOT" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=$build_type -DHAPTIC_SANITIZE=$sanitize >/dev/null
  # TSan: only the threaded tests. The processes' own threads talk through Fast DDS and
  # iceoryx, which Debian ships uninstrumented, so TSan cannot judge them.
  local targets=() selection=()
  if [[ $variant == tsan ]]; then
    targets=(daemon_core_test softhand_helper_thread_test)
    selection=(-L threaded)
  fi
  ninja -C "$build" -j2 "${targets[@]}"
  echo "=== $variant: built in $((SECONDS - start)) s; running tests"
  start=$SECONDS
  # Leak checking stays on; the suppressions name only third-party singletons.
  ASAN_OPTIONS="detect_leaks=1:abort_on_error=0" \
  LSAN_OPTIONS="suppressions=$ROOT/tests/sanitizer/lsan.supp:print_suppressions=0" \
  UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1" \
  TSAN_OPTIONS="suppressions=$ROOT/tests/sanitizer/tsan.supp" \
    ctest --test-dir "$build" --output-on-failure --no-tests=error -j2 --timeout 300 "${selection[@]}"
  echo "=== $variant: tests passed in $((SECONDS - start)) s"
  # Tests that passed only on a later attempt print nothing above; a rising count is a sign of
  # an RT regression, not only of the VM (tests/integration/loop_stall_retry.hpp).
  local log="$build/Testing/Temporary/LastTest.log" retries
  retries=$(grep -c '^\[ RETRY    \]' "$log" 2>/dev/null || true)
  echo "=== $variant: ${retries:-0} attempt(s) rerun after a loop stall of hapticd"
  grep '^\[ RETRY    \]' "$log" 2>/dev/null | sed 's/^/    /' || true
}

# Short libFuzzer run of the CAN frame decoders with the sanitizer build (the 1M-input run is
# documented in docs/drivers.md). Before the ctest runs, so ctest's summary closes the log.
if [[ " ${variants[*]} " == *" asan "* ]]; then
  "$ROOT/tests/drivers/fuzz/run_fuzz.sh" 20000
fi

for variant in "${variants[@]}"; do
  run_variant "$variant"
done
