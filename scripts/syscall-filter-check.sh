#!/usr/bin/env bash
# Do the units' SystemCallFilter=@system-service sets allow every system call RouDi, hapticd
# and handsim make? Runs the demo (scripts/demo.sh, closed loop, rendering) with the three
# under strace, then compares the calls they made with the set systemd-analyze expands.
# Not part of CI (a minute, and it needs strace). Usage: scripts/syscall-filter-check.sh
# Exit 0: every call allowed; 1: some are not (listed); 2: the run or the traces failed.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
for tool in strace systemd-analyze; do
  command -v "$tool" >/dev/null || { echo "syscall-filter-check: $tool not installed" >&2; exit 2; }
done
# It kills the RouDi it traced and removes iceoryx's files: never with another RouDi running
# (an installed service's, or the demo's).
if pgrep -x iox-roudi >/dev/null; then
  echo "syscall-filter-check: an iox-roudi is running (pid $(pgrep -x iox-roudi)); stop it first" >&2
  exit 2
fi
work=$(mktemp -d /tmp/haptic-syscalls.XXXX)
demo="$ROOT/scripts/.demo-under-strace.sh"
trap 'rm -f "$demo"' EXIT
# The demo's own command lines, each behind strace (-f: every thread).
sed -e "s|^setsid iox-roudi -c|setsid strace -f -qq -o $work/roudi.trace iox-roudi -c|" \
    -e "s|^setsid \"\$HAPTICD\" --realtime|setsid strace -f -qq -o $work/hapticd.trace \"\$HAPTICD\" --realtime|" \
    -e "s|^setsid \"\$HANDSIM\" --tracking-topic|setsid strace -f -qq -o $work/handsim.trace \"\$HANDSIM\" --tracking-topic|" \
    "$ROOT/scripts/demo.sh" >"$demo"
chmod +x "$demo"
# strace does not pass the demo's SIGTERM on, so the demo kills what it traced at the end and
# reports stale iceoryx files; they are cleaned below.
"$demo" --duration 12 --record 6 >"$work/demo.log" 2>&1 || true
pkill -9 -x iox-roudi 2>/dev/null || true  # only the traced one: none ran before
# shellcheck source=scripts/iceoryx-paths.sh
source "$ROOT/scripts/iceoryx-paths.sh"
group=$(id -gn) || group=$(id -g)  # a gid without a name in the group database
mapfile -t iceoryx_files < <(iceoryx_paths "$group")
rm -f "${iceoryx_files[@]}"
fastdds shm clean >/dev/null 2>&1 || true

expand() {  # a systemd syscall set, recursively
  systemd-analyze syscall-filter "$1" | awk 'NR > 1 && !/^ *#/ && NF { print $1 }' |
    while read -r item; do
      if [[ $item == @* ]]; then expand "$item"; else echo "$item"; fi
    done
}
expand @system-service | sort -u >"$work/allowed"
status=0
for name in roudi hapticd handsim; do
  trace="$work/$name.trace"
  if [[ ! -s $trace ]]; then
    echo "syscall-filter-check: no trace of $name (see $work/demo.log)" >&2
    exit 2
  fi
  sed -E 's/^[0-9]+ +//; s/^<\.\.\. ([a-z0-9_]+) resumed>.*/\1(/' "$trace" |
    grep -oE '^[a-z_0-9]+\(' | tr -d '(' | sort -u >"$work/$name.used"
  refused=$(comm -23 "$work/$name.used" "$work/allowed" | tr '\n' ' ')
  echo "$name: $(wc -l <"$work/$name.used") distinct system calls; outside @system-service: ${refused:-none}"
  [[ -z $refused ]] || status=1
done
echo "traces in $work"
exit $status
