#!/usr/bin/env bash
# Checks the sysusers.d file with systemd-sysusers --dry-run on an empty root: it must parse
# and create the users the units name (User=, Group=) and the operator group.
# Exit 0 pass, 1 fail, 77 systemd-sysusers not installed (ctest reports SKIPPED).
set -euo pipefail
conf=$1
if ! command -v systemd-sysusers >/dev/null; then
    echo "systemd-sysusers not found: cannot check $conf" >&2
    exit 77
fi
root=$(mktemp -d)
trap 'rm -rf "$root"' EXIT
mkdir -p "$root/etc"
output=$(systemd-sysusers --dry-run --root="$root" "$conf" 2>&1)
status=0
for expected in "Creating group 'haptic' " "Creating group 'haptic-ipc' " \
                "Creating user 'iox-roudi' " "Creating user 'hapticd' " "Creating user 'handsim' "; do
    if ! grep -qF "$expected" <<<"$output"; then
        echo "$conf: systemd-sysusers does not report: $expected" >&2
        status=1
    fi
done
# Each service user's primary group is the shared one.
gid=$(sed -n "s/^Creating group 'haptic-ipc' with GID \([0-9]*\)\..*/\1/p" <<<"$output")
for user in iox-roudi hapticd handsim; do
    if ! grep -Eq "^Creating user '$user' .* with UID [0-9]+ and GID $gid\.$" <<<"$output"; then
        echo "$conf: $user's primary group is not haptic-ipc" >&2
        status=1
    fi
done
if grep -qiE "fail|error|ignoring" <<<"$output"; then
    echo "$conf: systemd-sysusers reported a problem" >&2
    status=1
fi
[[ $status -eq 0 ]] || echo "$output" >&2
[[ $status -eq 0 ]] && echo "sysusers verified: haptic, haptic-ipc; iox-roudi, hapticd, handsim in haptic-ipc"
exit $status
