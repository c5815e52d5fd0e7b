#!/usr/bin/env bash
# Runs handsim on every shipped scene for a while at the scene's own rate and prints, per
# scene, the line handsim logs at exit: steps, rate held, step time p50/p99/max, and what the
# energy guard did (rescaled, substepped, frozen steps), then the CPU time handsim used. Not
# part of CI (4 x the duration).
#
#   scripts/handsim-scenes.sh [--duration 60] [--build build/release] [--scenes "thimble_only default"]
#                             [--helper-thread on|off] [--cpu-latency-us N]
#
# --helper-thread on|off runs every scene with solver.helper_thread set so (default: as each
# scene ships it), for comparing the two in one run (docs/benchmarks.md).
# --cpu-latency-us N runs handsim with sim.yaml's cpu_latency_us set to N (-1: no request;
# default: as shipped). Another process holding a lower request (a running hapticd) wins.
#
# Each run uses a copy of config/ whose sim.yaml names the scene (and, for the thimble scene,
# only the thimble), with --sim-link dds on its own DDS domain: no RouDi, no hapticd. Nothing
# else should run meanwhile: the step times are wall clock.
set -euo pipefail

duration=60
build=build/release
scenes="thimble_only default whole_hand grasp_box"
helper_thread=shipped
cpu_latency_us=shipped
while [[ $# -gt 0 ]]; do
    case "$1" in
        --duration) duration="$2"; shift 2 ;;
        --build) build="$2"; shift 2 ;;
        --scenes) scenes="$2"; shift 2 ;;
        --helper-thread) helper_thread="$2"; shift 2 ;;
        --cpu-latency-us) cpu_latency_us="$2"; shift 2 ;;
        *) echo "usage: $0 [--duration S] [--build DIR] [--scenes \"NAME ...\"] [--helper-thread on|off] [--cpu-latency-us N]" >&2; exit 2 ;;
    esac
done

root="$(cd "$(dirname "$0")/.." && pwd)"
# Checked before the first run, not a scene's duration into them.
for scene in $scenes; do
    [[ -f "$root/config/scenes/$scene.yaml" ]] || { echo "no scene config/scenes/$scene.yaml" >&2; exit 2; }
done
[[ $helper_thread =~ ^(shipped|on|off)$ ]] || { echo "--helper-thread on or off, not '$helper_thread'" >&2; exit 2; }
[[ $cpu_latency_us =~ ^(shipped|-1|[0-9]+)$ ]] || { echo "--cpu-latency-us -1 or a number of us, not '$cpu_latency_us'" >&2; exit 2; }
handsim="$root/$build/sim/handsim/handsim"
[[ -x "$handsim" ]] || { echo "$handsim not built" >&2; exit 1; }
work="$(mktemp -d /tmp/handsim-scenes.XXXX)"
echo "# $(date -u +%FT%TZ) $(git -C "$root" rev-parse --short HEAD) $(nproc) cores, load $(cut -d' ' -f1 /proc/loadavg)"
echo "# $0 --duration $duration --build $build --scenes \"$scenes\" --helper-thread $helper_thread --cpu-latency-us $cpu_latency_us; logs in $work"

# `time` below prints user, system and real seconds with a decimal point whatever the locale.
LC_ALL=C
TIMEFORMAT='%U %S %R'
domain=90
for scene in $scenes; do
    copy="$work/$scene"
    cp -r "$root/config" "$copy"
    sed -i "s|^scene: .*|scene: scenes/$scene.yaml|" "$copy/sim.yaml"
    case $helper_thread in
        shipped) ;;
        on|off)
            value=$([[ $helper_thread == on ]] && echo true || echo false)
            yaml="$copy/scenes/$scene.yaml"
            sed -i '/^  helper_thread:/d' "$yaml"
            if grep -q '^solver:' "$yaml"; then
                sed -i "/^solver:/a\\  helper_thread: $value" "$yaml"
            else
                printf 'solver:\n  helper_thread: %s\n' "$value" >> "$yaml"
            fi ;;
    esac
    if [[ "$scene" == thimble_only ]]; then
        sed -i '/^  - devices\/exoskeleton.yaml/d' "$copy/sim.yaml"
    fi
    if [[ $cpu_latency_us != shipped ]]; then
        sed -i "s/^cpu_latency_us: [-0-9]*/cpu_latency_us: $cpu_latency_us/" "$copy/sim.yaml"
        grep -q "^cpu_latency_us: $cpu_latency_us\b" "$copy/sim.yaml" || { echo "sim.yaml has no cpu_latency_us line" >&2; exit 1; }
    fi
    domain=$((domain + 1))
    # The CPU time handsim used (user, system; all its threads) beside the wall-clock steps:
    # a helper thread that polls costs CPU that a step's time does not show.
    { time "$handsim" -c "$copy/sim.yaml" --sim-link dds --dds-domain "$domain" \
        --duration "$duration" > "$work/$scene.log" 2>&1; } 2> "$work/$scene.cpu" || {
        echo "$scene: handsim failed, see $work/$scene.log" >&2
        exit 1
    }
    read -r user_s system_s real_s < "$work/$scene.cpu"
    cpu=$(awk -v u="$user_s" -v s="$system_s" -v r="$real_s" \
        'BEGIN { printf "CPU %.1f s user + %.1f s system in %.1f s (%.0f %% of one core)", u, s, r, 100 * (u + s) / r }')
    echo "$scene: $(grep -E 'steps in .* s \(' "$work/$scene.log" | tail -1 | sed -E 's/^.*\] //'); $cpu"
done
