#!/usr/bin/env bash
# The fixed paths iceoryx 2.0 creates for RouDi and for our two clients (runtime names hapticd
# and handsim). After an unclean exit they stay behind, owned by whoever ran the process, and
# keep the next RouDi or client from starting (docs/systemd.md). One list for everything that
# checks or removes them: scripts/demo.sh, scripts/syscall-filter-check.sh and the service
# users' test.
#
#   scripts/iceoryx-paths.sh GROUP                    prints them, one per line
#   source scripts/iceoryx-paths.sh; iceoryx_paths GROUP
#
# GROUP is RouDi's group: iceoryx names the shared memory segment of the data pools after it.
iceoryx_paths() {
  local group=${1:?iceoryx_paths: RouDi\'s group name}
  printf '%s\n' /tmp/roudi /tmp/roudi.lock /tmp/iox-unique-roudi.lock \
    /tmp/hapticd /tmp/hapticd.lock /tmp/handsim /tmp/handsim.lock \
    /dev/shm/iceoryx_mgmt "/dev/shm/$group"
}

if [[ "${BASH_SOURCE[0]}" == "$0" ]]; then
  set -euo pipefail
  [[ $# -eq 1 ]] || { echo "usage: $0 GROUP" >&2; exit 2; }
  iceoryx_paths "$1"
fi
