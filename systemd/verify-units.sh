#!/usr/bin/env bash
# Checks the generated systemd units: `systemd-analyze verify` (syntax, unknown keys,
# dependencies, executables) plus the properties hapticd relies on (docs/systemd.md).
# Usage: verify-units.sh UNIT_DIR INSTALL_BINDIR HAPTICD_DIR HANDSIM_DIR SIM_LINK
# Exit 0 pass, 1 fail, 77 systemd-analyze not installed (ctest reports SKIPPED).
set -euo pipefail
units=$1 install_bindir=$2 hapticd_dir=$3 handsim_dir=$4 sim_link=$5
max_exposure=4.0  # systemd-analyze security: "OK" is below 4.5 (MEDIUM up to 6.9)

if ! command -v systemd-analyze >/dev/null; then
    echo "systemd-analyze not found: cannot verify the units" >&2
    exit 77
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp "$units"/*.service "$work"/
# verify requires every ExecStart binary to exist: point the installed paths at the build.
sed -i -E "s#^(ExecStart|ExecStartPre)=${install_bindir}/hapticd #\1=${hapticd_dir}/hapticd #" "$work"/hapticd.service
sed -i -E "s#^(ExecStart|ExecStartPre)=${install_bindir}/handsim #\1=${handsim_dir}/handsim #" "$work"/handsim.service

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
require hapticd.service 'ExecStartPre=.*/hapticd --config .*/daemon.yaml --check' 'a configuration error stops the start'
require handsim.service 'ExecStartPre=.*/handsim --config .*/sim.yaml --check' 'a configuration error stops the start'
require hapticd.service 'Type=notify' 'READY=1 after the RT loop runs'
require hapticd.service 'WatchdogSec=[0-9]+m?s' 'pinged only while the RT loop ticks'
require hapticd.service 'LimitRTPRIO=[0-9]+' 'SCHED_FIFO'
require hapticd.service 'LimitMEMLOCK=infinity' 'mlockall'
require hapticd.service 'Restart=(on-failure|always|on-watchdog|on-abnormal)' 'restart policy'
reject() {  # unit, regex, why
    if grep -Eq "^$2\$" "$work/$1"; then
        echo "$1: has '$2' ($3)" >&2
        status=1
    fi
}
for unit in hapticd.service handsim.service; do
    require $unit "ExecStart=.* --sim-link $sim_link" 'the unit runs the sim link it was made for'
    if [[ $sim_link == iceoryx ]]; then
        require $unit 'BindsTo=iox-roudi.service' 'a RouDi restart orphans iceoryx clients'
        require $unit 'After=iox-roudi.service.*' 'start after RouDi'
    else
        reject $unit '(BindsTo|Requires|Wants)=.*iox-roudi.*' 'over DDS a RouDi restart must not stop it'
        reject $unit 'After=.*iox-roudi.*' 'over DDS it does not wait for RouDi'
    fi
done
require iox-roudi.service 'Restart=on-failure' 'restart policy'
# Not root: each service its own user, one group for iceoryx's memory (haptic.sysusers.conf).
require iox-roudi.service 'User=iox-roudi' 'not root'
require hapticd.service 'User=hapticd' 'not root'
require handsim.service 'User=handsim' 'not root'
for unit in iox-roudi.service hapticd.service handsim.service; do
    require $unit 'Group=haptic-ipc' 'iceoryx gives its memory and socket to RouDi'"'"'s group'
    require $unit 'CapabilityBoundingSet=' 'no capabilities: SCHED_FIFO and mlockall come from the limits'
    require $unit 'NoNewPrivileges=yes' 'sandbox'
    require $unit 'ProtectSystem=strict' 'read-only file system'
    require $unit 'ReadWritePaths=/dev/shm /tmp' 'iceoryx shared memory and sockets'
done
reject hapticd.service 'RestrictRealtime=yes' 'the RT loop needs SCHED_FIFO'
require handsim.service 'RestrictRealtime=yes' 'handsim is soft real-time'
# The exposure score of systemd's own assessment (0 safe .. 10 unsafe); 9.6 with no sandbox.
export SYSTEMD_COLORS=0
if grep -q -- '--offline' <<<"$(systemd-analyze security --help 2>&1)"; then
    for unit in iox-roudi.service hapticd.service handsim.service; do
        score=$(cd "$work" && { systemd-analyze security --offline=true --no-pager "./$unit" 2>&1 || true; } |
                sed -n 's/.*Overall exposure level for [^:]*: \([0-9.]*\).*/\1/p')
        echo "$unit: exposure $score"
        if [[ -z $score ]] || awk -v s="$score" -v max="$max_exposure" 'BEGIN { exit !(s > max) }'; then
            echo "$unit: exposure level '$score' above $max_exposure" >&2
            status=1
        fi
    done
fi
for unit in "$work"/*.service; do
    if grep -Eq '^PrivateTmp=(yes|true)' "$unit"; then
        echo "$(basename "$unit"): PrivateTmp hides RouDi's /tmp socket" >&2
        status=1
    fi
done
[[ $status -eq 0 ]] && echo "systemd units verified ($sim_link sim link): $(cd "$work" && echo *.service)"
exit $status
