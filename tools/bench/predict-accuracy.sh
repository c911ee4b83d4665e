#!/bin/sh
# The accuracy of `testbed predict` (docs/predict.md): calibrates, then for
# every held-out case (the bundled scenes and generated scenes of sizes and
# seeds the calibration does not use; raytrace, path and radiosity) runs
# `testbed predict --json` and the real `testbed render` under GNU time, and
# writes the table (CSV + Markdown) and a log-log plot of predicted against
# measured with the +-25% band (PNG + SVG). The work columns check the pilot:
# the predicted rays (closest-hit plus occlusion; radiosity: shots) over the
# render's own counters (--stats); a time miss with a work ratio near 1 is
# the costs', one with the work ratio off is the pilot's.
#
#   tools/bench/predict-accuracy.sh [--testbed PATH] [--set default|long|quick]
#                                   [--out DIR] [--work DIR] [--only raytrace|path|radiosity]
#
# Defaults: build/ci/testbed, the default calibration set, docs/ (files
# predict-accuracy.{csv,md,png,svg}), a temporary work folder.
set -eu

here=$(cd "$(dirname "$0")/../.." && pwd)
tb="$here/build/ci/testbed"
set_name=default
out="$here/docs"
work=""
only=""
while [ $# -gt 0 ]; do
    case "$1" in
    --testbed) tb=$2; shift 2 ;;
    --set) set_name=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    --only) only=$2; shift 2 ;;
    -h | --help)
        sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'
        exit 0 ;;
    *) echo "predict-accuracy.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
    esac
done
[ -x "$tb" ] || { echo "predict-accuracy.sh: no testbed at $tb (build it, or give --testbed)" >&2; exit 2; }
command -v /usr/bin/time >/dev/null || { echo "predict-accuracy.sh: needs GNU time (/usr/bin/time)" >&2; exit 2; }
if [ -z "$work" ]; then
    work=$(mktemp -d "${TMPDIR:-/tmp}/predict-accuracy-XXXXXX")
    trap 'rm -rf "$work"' EXIT
fi
mkdir -p "$work" "$out"
export TB_NO_PROGRESS=1
export OMP_WAIT_POLICY=passive # spinning OpenMP waits distort timings on shared cores

load_before=$(cut -d' ' -f1-3 /proc/loadavg)
echo "predict-accuracy: calibrating (--set $set_name)" >&2
"$tb" calibrate --set "$set_name" -o "$work/costs.json" --runs "$work/calibration-runs.csv" >&2

# Held-out generated scenes: sizes and seeds (7) the calibration does not use (it uses seed 1).
"$tb" generate grid --count 120 --seed 7 -o "$work/grid-120.mid"
"$tb" generate csg --count 40 --seed 7 -o "$work/csg-40.mid"
"$tb" generate mesh --count 30 --seed 7 -o "$work/mesh-30.mid"
"$tb" generate grid --count 12 --seed 7 -o "$work/grid-12.mid"

# case: name|scene|method|options
cases="$work/cases.txt"
: >"$cases"
for s in cornell-box cornell-box-spheres materials radiosity-room showcase; do
    echo "$s|$here/scenes/$s.mid|raytrace|" >>"$cases"
    echo "$s|$here/scenes/$s.mid|path|--spp 4" >>"$cases"
done
for s in cornell-box cornell-box-spheres radiosity-room; do
    echo "$s|$here/scenes/$s.mid|radiosity|" >>"$cases"
done
for g in grid-120 csg-40 mesh-30; do
    echo "gen $g|$work/$g.mid|raytrace|" >>"$cases"
    echo "gen $g|$work/$g.mid|path|--spp 2" >>"$cases"
done
echo "gen grid-12|$work/grid-12.mid|radiosity|--max-edge 2" >>"$cases"
[ -z "$only" ] || { grep "|$only|" "$cases" >"$cases.only" || true; mv "$cases.only" "$cases"; }

csv="$work/rows.csv"
echo "case,method,options,predicted_s,measured_s,ratio_s,predicted_mib,measured_mib,ratio_mem,pilot_s,predicted_work,measured_work,ratio_work" >"$csv"
n=0
while IFS='|' read -r name scene method opts; do
    n=$((n + 1))
    echo "predict-accuracy: [$n] $name $method $opts" >&2
    # shellcheck disable=SC2086
    "$tb" predict "$scene" --method "$method" $opts --costs "$work/costs.json" --json >"$work/p.json"
    # shellcheck disable=SC2086
    /usr/bin/time -f '%e %M' -o "$work/time.txt" "$tb" render "$scene" --method "$method" $opts \
        -o "$work/out.png" --stats "$work/stats.json" >/dev/null 2>"$work/render.err" ||
        { echo "predict-accuracy: the render failed:" >&2; cat "$work/render.err" >&2; exit 1; }
    python3 - "$work/p.json" "$work/time.txt" "$name" "$method" "$opts" "$work/stats.json" >>"$csv" <<'EOF'
import json, sys
p = json.load(open(sys.argv[1]))
wall, kib = open(sys.argv[2]).read().split()[-2:]
wall, mib = float(wall), float(kib) / 1024.0
pm = p["peak_rss_bytes"] / 1048576.0
s = json.load(open(sys.argv[6]))
if sys.argv[4] == "radiosity":
    pw, mw = p["radiosity_shots"], s["shots"]
else:
    pw = p["statistics"]["rays"] + p["statistics"]["occlusion_rays"]
    mw = s["counters"]["BVH/rays"] + s["counters"]["BVH/occlusion rays"]
print('"%s",%s,"%s",%.4g,%.4g,%.3f,%.1f,%.1f,%.3f,%.3g,%.6g,%.6g,%.3f' % (sys.argv[3], sys.argv[4], sys.argv[5],
      p["seconds"], wall, p["seconds"] / wall, pm, mib, pm / mib, p["pilot_seconds"], pw, mw, pw / mw if mw else 0))
EOF
done <"$cases"
load_after=$(cut -d' ' -f1-3 /proc/loadavg)

cp "$csv" "$out/predict-accuracy.csv"
python3 - "$csv" "$out/predict-accuracy.md" "$load_before" "$load_after" "$set_name" <<'EOF'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
def mark(r):
    return "" if 0.75 <= r <= 1.25 else " **miss**"
with open(sys.argv[2], "w") as f:
    f.write("| case | method | options | predicted s | measured s | ratio | predicted MiB | measured MiB | ratio "
            "| work ratio |\n")
    f.write("|---|---|---|---:|---:|---:|---:|---:|---:|---:|\n")
    for r in rows:
        rs, rm = float(r["ratio_s"]), float(r["ratio_mem"])
        f.write("| %s | %s | %s | %s | %s | %.2f%s | %s | %s | %.2f%s | %.2f |\n" % (
            r["case"], r["method"], r["options"] or "", r["predicted_s"], r["measured_s"], rs, mark(rs),
            r["predicted_mib"], r["measured_mib"], rm, mark(rm), float(r["ratio_work"])))
    ts = sum(0.75 <= float(r["ratio_s"]) <= 1.25 for r in rows)
    ms = sum(0.75 <= float(r["ratio_mem"]) <= 1.25 for r in rows)
    f.write("\nWithin +-25%%: time %d of %d, memory %d of %d (calibration set `%s`; load average "
            "%s before, %s after).\n" % (ts, len(rows), ms, len(rows), sys.argv[5], sys.argv[3], sys.argv[4]))
EOF
# gnuplot: time and memory against measured, log-log, with y = x and the +-25% band
awk -F, 'NR > 1 { print $5, $4, $2 }' "$csv" >"$work/time.dat"
awk -F, 'NR > 1 { print $8, $7, $2 }' "$csv" >"$work/mem.dat"
for term in "pngcairo size 1100,500" "svg size 1100,500"; do
    ext=png; case "$term" in svg*) ext=svg ;; esac
    gnuplot <<EOF
set terminal $term
set output "$out/predict-accuracy.$ext"
set multiplot layout 1,2 title "testbed predict: predicted against measured (load average $load_before before, $load_after after)"
set logscale xy
set key top left
set grid
band(x) = x
set title "wall time"
set xlabel "measured (s)"
set ylabel "predicted (s)"
set xrange [0.05:5000]
set yrange [0.05:5000]
plot band(x)*1.25 with lines lt 0 title "+-25%", band(x)*0.75 with lines lt 0 notitle, x with lines lc rgb "gray" notitle, \
     "< grep raytrace $work/time.dat" using 1:2 with points pt 7 title "raytrace", \
     "< grep path $work/time.dat" using 1:2 with points pt 5 title "path", \
     "< grep radiosity $work/time.dat" using 1:2 with points pt 9 title "radiosity"
set title "peak resident memory"
set xlabel "measured (MiB)"
set ylabel "predicted (MiB)"
set xrange [5:5000]
set yrange [5:5000]
plot band(x)*1.25 with lines lt 0 title "+-25%", band(x)*0.75 with lines lt 0 notitle, x with lines lc rgb "gray" notitle, \
     "< grep raytrace $work/mem.dat" using 1:2 with points pt 7 title "raytrace", \
     "< grep path $work/mem.dat" using 1:2 with points pt 5 title "path", \
     "< grep radiosity $work/mem.dat" using 1:2 with points pt 9 title "radiosity"
unset multiplot
EOF
done
cat "$out/predict-accuracy.md"
