#!/usr/bin/env bash
# The closed-loop soak (issue #17), not part of CI: the demo's full loop (RouDi, the virtual
# user, hapticd, handsim) for MINUTES minutes while stress-ng loads one of the two cores,
# telemetry recorded throughout. At the end it prints the closed-loop report of the whole run
# and the daemon's final state, and fails if a fault was latched or the state left RENDERING.
#
#   scripts/soak.sh [--minutes 10] [--cpu-workers 1]
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
MINUTES=10
WORKERS=1
while (($#)); do
  case "$1" in
    --minutes) MINUTES=$2; shift 2 ;;
    --cpu-workers) WORKERS=$2; shift 2 ;;
    -h|--help) sed -n '2,7p' "$0"; exit 0 ;;
    *) echo "soak.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
done

"$ROOT/scripts/install-deps.sh"
if ! command -v stress-ng >/dev/null; then
  SUDO=""; [[ $(id -u) -ne 0 ]] && SUDO=sudo
  $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq \
    --no-install-recommends stress-ng
fi

SECONDS_TOTAL=$((MINUTES * 60))
OUT=$(mktemp /tmp/haptic-soak.XXXXXX.log)
# The load runs a little longer than the loop and is stopped with it.
stress-ng --cpu "$WORKERS" --timeout "$((SECONDS_TOTAL + 60))s" --quiet &
STRESS_PID=$!
trap 'kill "$STRESS_PID" 2>/dev/null || true' EXIT
echo "soak: $MINUTES min of closed loop under stress-ng --cpu $WORKERS; demo output in $OUT"
status=0
"$ROOT/scripts/demo.sh" --duration "$SECONDS_TOTAL" --record "$((SECONDS_TOTAL - 5))" \
  >"$OUT" 2>&1 || status=$?
kill "$STRESS_PID" 2>/dev/null || true
LOGS=$(grep -o '/tmp/haptic-demo\.[A-Za-z0-9]*' "$OUT" | head -n 1)
echo "soak: demo exit $status; logs in $LOGS"
echo "--- closed-loop report of the whole run (hapticctl plot)"
tail -n +2 "$LOGS/plot.log" || true
echo "--- the daemon at the end"
final_state=$(grep 'State:' "$OUT" | tail -n 1)
final_faults=$(grep 'Faults:' "$OUT" | tail -n 1)
echo "$final_state"
echo "$final_faults"
if ((status != 0)) || [[ "$final_state" != *RENDERING* ]] || [[ "$final_faults" != *"Faults: none"* ]]; then
  echo "soak: FAILED (a process exited, the state left RENDERING or a fault latched)" >&2
  exit 1
fi
echo "soak: passed"
