#!/usr/bin/env bash
# The soft hand's speed/accuracy trade (#20), as docs/benchmarks.md publishes it: runs
# softhand_tradeoff (every level x Newton iterations x PCG cap x time step under handsim's
# real-time limits, against a converged reference), then writes into OUT_DIR
#   tradeoff.csv     one row per setting (columns: tests/bench/softhand_tradeoff.cpp)
#   pareto.md        the settings on a Pareto front and the shipped ones, as a Markdown table
#   pareto.png       step CPU time p99 against the error: every setting, the front and the
#                    shipped scene's point, for the press force, the contact area (thimble
#                    scene) and the fingertip position (exoskeleton scene)
# A setting is on a front when no setting with a lower CPU p99 has a lower error. CPU time,
# because on a shared 2-vCPU machine the wall time of a step varies 1.5-3x with the
# neighbours; both are in the CSV.
#
#   scripts/softhand-tradeoff.sh [--out DIR] [--csv EXISTING.csv] [-- softhand_tradeoff flags]
# A few minutes on the 2-core machine (144 settings: 3 min 28 s on 2026-11-27). --csv
# replots a saved run. Needs a Release build (scripts/test.sh builds one) and gnuplot.
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${BUILD_DIR:-$HERE/build/release}"
OUT=""
CSV_IN=""
while [[ $# -gt 0 ]]; do
    case "$1" in
        --out) OUT="$2"; shift 2 ;;
        --csv) CSV_IN="$2"; shift 2 ;;
        --) shift; break ;;
        -h|--help) sed -n '2,16p' "$0"; exit 0 ;;
        *) echo "softhand-tradeoff.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
    esac
done
OUT="${OUT:-$(mktemp -d /tmp/softhand-tradeoff.XXXX)}"
mkdir -p "$OUT"
command -v gnuplot > /dev/null || { echo "softhand-tradeoff.sh: gnuplot missing (apt install gnuplot-nox)" >&2; exit 1; }

if [[ -n "$CSV_IN" ]]; then
    cp "$CSV_IN" "$OUT/tradeoff.csv"
else
    ninja -C "$BUILD" -j2 softhand_tradeoff > /dev/null
    "$BUILD/tests/bench/softhand_tradeoff" "$@" | tee "$OUT/tradeoff.csv"
fi

# The shipped points: thimble_only.yaml (fingertip, level 1, handsim's default 1 Newton
# iteration, cap 30, 200 Hz) and default.yaml (finger, level 1, 2 Newton iterations, cap 30,
# 100 Hz).
SHIPPED_PRESS="press,1,1,30,5"
SHIPPED_FLEX="flex,1,2,30,10"

# Columns: 1 scene 2 level 3 nodes 4 newton 5 pcg_cap 6 dt_ms 7 p50_us 8 p99_us 9 cpu_p50_us
# 10 cpu_p99_us 11 press_err 12 force_err 13 area_err 14 tip_err_mm 15 angle_err_deg
# 16 rescaled 17 zeroed 18 solver (pcg, or ldlt with PCG cap 0; older runs have no column 18)
# The fronts: "<name> <scene> <error column>". A thimble renders a force and a contact
# surface, so the press scene has a front for each: the coarsest mesh has the least force error
# of some settings and no contact area to speak of.
FRONTS=("force press 11" "area press 13" "tip flex 14")
grep -v '^#' "$OUT/tradeoff.csv" | tail -n +2 > "$OUT/rows.csv"
for scene in press flex; do
    grep "^$scene," "$OUT/rows.csv" > "$OUT/all-$scene.csv" || true
    key=$([[ $scene == press ]] && echo "$SHIPPED_PRESS" || echo "$SHIPPED_FLEX")
    awk -F, -v k="$key" '($1","$2","$4","$5","$6) == k' "$OUT/rows.csv" > "$OUT/shipped-$scene.csv"
done
for front in "${FRONTS[@]}"; do
    read -r name scene column <<< "$front"
    sort -t, -k10,10g "$OUT/all-$scene.csv" |
        awk -F, -v c="$column" 'BEGIN { best = 1e300 } $c < best { best = $c; print }' \
        > "$OUT/front-$name.csv"
done

{
    echo "| scene | level | nodes | Newton | PCG cap (solver) | dt (ms) | CPU p50 (ms) | CPU p99 (ms) | wall p99 (ms) | press-force err | force err (cycle) | contact-area err | tip err (mm) | pitch err (deg) | rescaled | on the front of |"
    echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    for scene in press flex; do
        shipped=$([[ $scene == press ]] && echo "$SHIPPED_PRESS" || echo "$SHIPPED_FLEX")
        for front in "${FRONTS[@]}"; do
            read -r name front_scene column <<< "$front"
            if [[ $front_scene == "$scene" ]]; then
                sed "s/\$/,$name/" "$OUT/front-$name.csv"
            fi
        done > "$OUT/marks-$scene.csv"
        awk -F, -v shipped="$shipped" \
            'NR == FNR { key = $1","$2","$4","$5","$6
                         if (key in fronts) fronts[key] = fronts[key] ", " $NF; else fronts[key] = $NF
                         next }
             { key = $1","$2","$4","$5","$6
               if (!(key in fronts) && key != shipped) next
               mark = (key in fronts) ? fronts[key] : "none"
               if (key == shipped) mark = mark " (shipped)"
               # The flexing finger meets the table late: no force to compare in its first 0.2 s.
               press = $1 == "press" ? sprintf("%.1f %%", 100 * $11) : "-"
               cap = $5 == 0 ? "none: LDLT" : $5
               printf "| %s | %s | %s | %s | %s | %s | %.2f | %.2f | %.2f | %s | %.1f %% | %.1f %% | %.3f | %.2f | %.1f %% | %s |\n",
                   $1, $2, $3, $4, cap, $6, $9 / 1000, $10 / 1000, $8 / 1000, press, 100 * $12,
                   100 * $13, $14, $15, 100 * $16, mark }' \
            "$OUT/marks-$scene.csv" <(sort -t, -k10,10g "$OUT/all-$scene.csv")
    done
} > "$OUT/pareto.md"

# Labels: level L, Newton iterations N, PCG cap c (or LDLT, the direct solver), time step.
# panel <front name> <scene> <y expression> <y label> <title> <shipped scene file>: one plot.
panel() {
    local x='($10/1000)' label='(sprintf("L%d N%d %s %dms", $2, $4, $5 == 0 ? "LDLT" : sprintf("c%d", $5), $6))'
    echo "set ylabel \"$4\""
    echo "set title \"$5\""
    echo "plot \"$OUT/all-$2.csv\" using $x:$3 with points pt 7 ps 0.6 lc rgb \"#bbbbbb\" title \"every setting\", \\"
    echo "     \"$OUT/front-$1.csv\" using $x:$3 with linespoints pt 7 ps 1 lc rgb \"#1f77b4\" title \"Pareto front\", \\"
    echo "     \"$OUT/front-$1.csv\" using $x:$3:$label with labels offset 0,1 font \",8\" notitle, \\"
    echo "     \"$OUT/shipped-$2.csv\" using $x:$3 with points pt 9 ps 2 lc rgb \"#d62728\" title \"shipped: ${6//_/\\\\_}\""
}
{
    echo 'set terminal pngcairo size 1800,620 font ",11"'
    echo "set output \"$OUT/pareto.png\""
    echo 'set datafile separator ","'
    echo "set multiplot layout 1,3 title \"Soft-hand step under handsim's real-time limits: CPU time p99 against error (scripts/softhand-tradeoff.sh; level L, Newton iterations N, PCG cap c or LDLT, time step)\""
    echo 'set logscale xy'
    echo 'set grid'
    echo 'set key top right'
    echo 'set xlabel "step CPU time p99 (ms)"'
    panel force press '(100*$11)' "press-force error, first 0.2 s (%)" \
        "thimble scene (fingertip press): force" thimble_only.yaml
    panel area press '(100*$13)' "contact-area error (%)" \
        "thimble scene (fingertip press): contact area" thimble_only.yaml
    panel tip flex '($14)' "fingertip position error (mm)" \
        "exoskeleton scene (finger flex): fingertip position" default.yaml
    echo 'unset multiplot'
} | gnuplot
echo "softhand-tradeoff.sh: $OUT/tradeoff.csv, $OUT/pareto.md, $OUT/pareto.png"
