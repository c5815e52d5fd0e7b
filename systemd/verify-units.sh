#!/usr/bin/env bash
# Checks the generated systemd units: `systemd-analyze verify` (syntax, unknown keys,
# dependencies, executables) plus the properties hapticd relies on (README "Running on real
# hardware"). Usage: verify-units.sh UNIT_DIR INSTALL_BINDIR HAPTICD_DIR HANDSIM_DIR
# Exit 0 pass, 1 fail, 77 systemd-analyze not installed (ctest reports SKIPPED).
set -euo pipefail
units=$1 install_bindir=$2 hapticd_dir=$3 handsim_dir=$4

if ! command -v systemd-analyze >/dev/null; then
    echo "systemd-analyze not found: cannot verify the units" >&2
    exit 77
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp "$units"/*.service "$work"/
# verify requires every ExecStart binary to exist: point the installed paths at the build.
sed -i "s#^ExecStart=${install_bindir}/hapticd #ExecStart=${hapticd_dir}/hapticd #" "$work"/hapticd.service
sed -i "s#^ExecStart=${install_bindir}/handsim #ExecStart=${handsim_dir}/handsim #" "$work"/handsim.service

status=0
if ! output=$(cd "$work" && systemd-analyze verify ./*.service 2>&1) || [[ -n $output ]]; then
    echo "systemd-analyze verify reported:" >&2
    echo "$output" >&2
    status=1
fi

require() {  # unit, regex, why
    if ! grep -Eq "^$2\$" "$work/$1"; then
        echo "$1: missing '$2' ($3)" >&2
        status=1
    fi
}
require hapticd.service 'Type=notify' 'READY=1 after the RT loop runs'
require hapticd.service 'WatchdogSec=[0-9]+m?s' 'pinged only while the RT loop ticks'
require hapticd.service 'LimitRTPRIO=[0-9]+' 'SCHED_FIFO'
require hapticd.service 'LimitMEMLOCK=infinity' 'mlockall'
require hapticd.service 'Restart=(on-failure|always|on-watchdog|on-abnormal)' 'restart policy'
require hapticd.service 'BindsTo=iox-roudi.service' 'a RouDi restart orphans iceoryx clients'
require hapticd.service 'After=iox-roudi.service.*' 'start after RouDi'
require handsim.service 'BindsTo=iox-roudi.service' 'a RouDi restart orphans iceoryx clients'
require iox-roudi.service 'Restart=on-failure' 'restart policy'
for unit in "$work"/*.service; do
    if grep -Eq '^PrivateTmp=(yes|true)' "$unit"; then
        echo "$(basename "$unit"): PrivateTmp hides RouDi's /tmp socket" >&2
        status=1
    fi
done
[[ $status -eq 0 ]] && echo "systemd units verified: $(cd "$work" && echo *.service)"
exit $status
