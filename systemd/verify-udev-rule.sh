#!/usr/bin/env bash
# Checks the CPU latency udev rule against this kernel and the sysusers.d file (udevadm has no
# offline check in systemd 252): the device it names exists under that name and subsystem, the
# group it gives the device is one sysusers.d creates, and the mode lets that group write.
# Exit 0 pass, 1 fail, 77 this kernel has no /dev/cpu_dma_latency (ctest reports SKIPPED).
set -euo pipefail
rule=$1
sysusers=$2
sys=/sys/class/misc/cpu_dma_latency
[[ -e $sys/uevent ]] || { echo "no $sys: cannot check $rule" >&2; exit 77; }
# value KEY OPERATOR: the key's value where the rule uses it with that operator (== matches,
# = assigns), else empty.
value() { grep -v '^#' "$rule" | grep -oE "(^|[ ,])$1$2\"[^\"]*\"" | head -1 | sed 's/.*"\(.*\)"/\1/' || true; }
status=0
check() { [[ "$2" == "$3" ]] || { echo "$rule: $1 is '$2', the kernel's is '$3'" >&2; status=1; }; }
check KERNEL "$(value KERNEL ==)" "$(sed -n 's/^DEVNAME=//p' "$sys/uevent")"
check SUBSYSTEM "$(value SUBSYSTEM ==)" "$(basename "$(readlink -f "$sys/subsystem")")"
group=$(value GROUP =)
grep -Eq "^g[[:space:]]+$group[[:space:]]" "$sysusers" ||
    { echo "$rule: GROUP '$group' is not a group $sysusers creates" >&2; status=1; }
for user in hapticd handsim; do
    grep -Eq "^u[[:space:]]+$user[[:space:]]+-:$group[[:space:]]" "$sysusers" ||
        { echo "$rule: $user is not in the group '$group' ($sysusers)" >&2; status=1; }
done
mode=$(value MODE =)
[[ $mode =~ ^0?[0-7][2367][0-7]$ ]] ||
    { echo "$rule: MODE '$mode' does not let the group write" >&2; status=1; }
exit $status
