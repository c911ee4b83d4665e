#!/usr/bin/env bash
# Speed versus error of the renderers (issue 16): raytrace (Whitted),
# radiosity, hybrid (interpolated and gather) and path, each at a ladder of
# budgets, against a converged path-traced reference.
#
#   tools/bench/methods-error.sh [options]        (--help: the options)
#
# For each scene (default: scenes/cornell-box-spheres.mid and
# scenes/cornell-box.mid, at --res x --res pixels):
#   1. the reference: `testbed render --method path` at --ref-spp samples per
#      pixel (seed 1000003, so it shares no samples with the ladder's path
#      renders), cached under --cache by the scene text, the resolution, the
#      spp and `testbed --version`; or the image given by --reference;
#   2. every rung of every method's ladder, as a whole process under GNU
#      time (loading, BVH, the radiosity pass, the ray-tracing pass, writing:
#      what a user waits for), then `testbed compare --json` against the
#      reference: relMSE (mean (a-b)^2 / (b^2 + 0.01)) and RMSE over R, G, B;
#   3. OUT/methods-error.csv, one row per render:
#        scene,method,mode,budget,seconds,cpu_seconds,relMSE,RMSE
#      (seconds: wall clock of the process; cpu_seconds: user + system);
#   4. OUT/methods-error-SCENE.png and .svg (gnuplot): relMSE and RMSE
#      against CPU seconds, log-log, one curve per method and mode;
#   5. on standard output: the table, and the equal-time ratios: for each
#      hybrid render, the Whitted and the path tracer's relMSE at the same
#      CPU time (log-log interpolation along their curves) over the hybrid's.
#
# The ladders. raytrace: spp. path: spp. radiosity: element size (--max-edge)
# and unshot threshold, the image at 4 rays per pixel. hybrid: the radiosity
# pass's element size together with the ray-tracing pass's spp (the radiosity
# pass is a fixed cost that a finer mesh raises). gather: the same with 16
# gather rays. --quick: 32 x 32 pixels, a 512-spp reference, two or three
# rungs per method: checks the script (tests/bench: bench_methods_error_quick);
# its figures mean little.
#
# --check: exit 1 unless, on each scene holding "spheres" in its name, the
# hybrid's relMSE (both modes) at its largest budget is below the Whitted ray
# tracer's at its largest budget (the Whitted tracer has no indirect diffuse
# light at all), and every error is finite.
#
# CPU seconds are the comparable figure on a shared machine: wall times
# follow what the other processes do. Figures are valid on an idle machine
# only; the script prints the load average before and after.
#
# Environment: TESTBED (default build/release/testbed, built Release when
# missing), TMPDIR.
# Exit status: 0 done (and --check passed), 1 a render or check failed, 2 usage.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)

usage() {
    cat <<EOF
usage: tools/bench/methods-error.sh [options]

Renders raytrace, radiosity, hybrid (interpolated, gather) and path at a
ladder of budgets on the spheres Cornell box and the Cornell box, measures
relMSE and RMSE against a converged path-traced reference, and writes
OUT/methods-error.csv and OUT/methods-error-SCENE.{png,svg} (error against
CPU seconds, log-log).

  --out DIR          where the CSV and the plots go (default: methods-error)
  --scenes LIST      comma-separated scene names of scenes/ (default:
                     cornell-box-spheres,cornell-box)
  --res N            image width and height (default 96; --quick 32)
  --ref-spp N        the reference's samples per pixel (default 4096, 8 times the path ladder's
                     largest; --quick 512)
  --reference IMG    use IMG as the reference (one scene only) instead of rendering one
  --cache DIR        reference cache (default: build/methods-error-cache)
  --threads N        threads of every render (default 2)
  --methods LIST     comma-separated subset of raytrace,path,radiosity,hybrid,gather
  --quick            tiny sizes and short ladders: checks the script, figures mean little
  --check            exit 1 unless the hybrid beats Whitted at the largest budget on the spheres box
  --no-plot          no gnuplot plots
  -h, --help         this help

TESTBED selects the binary (default build/release/testbed, built Release if
missing). Exit status: 0 done, 1 a render or the check failed, 2 usage.
EOF
}

out=methods-error scenes=cornell-box-spheres,cornell-box res="" ref_spp="" reference="" cache=""
threads=2 methods=raytrace,path,radiosity,hybrid,gather quick=0 check=0 plot=1
while [[ $# -gt 0 ]]; do
    case $1 in
        --out|--scenes|--res|--ref-spp|--reference|--cache|--threads|--methods)
            [[ $# -ge 2 ]] || { echo "methods-error: $1 needs a value" >&2; exit 2; }
            v=$2
            case $1 in
                --out) out=$v ;; --scenes) scenes=$v ;; --res) res=$v ;; --ref-spp) ref_spp=$v ;;
                --reference) reference=$v ;; --cache) cache=$v ;; --threads) threads=$v ;; --methods) methods=$v ;;
            esac
            shift ;;
        --quick) quick=1 ;;
        --check) check=1 ;;
        --no-plot) plot=0 ;;
        -h|--help) usage; exit 0 ;;
        *) echo "methods-error: unknown option '$1' (see --help)" >&2; exit 2 ;;
    esac
    shift
done
(( quick )) && : "${res:=32}" "${ref_spp:=512}"
: "${res:=96}" "${ref_spp:=4096}"
[[ $res =~ ^[0-9]+$ && $res -ge 4 ]] || { echo "methods-error: --res must be an integer >= 4" >&2; exit 2; }
[[ $ref_spp =~ ^[0-9]+$ && $ref_spp -ge 1 ]] || { echo "methods-error: --ref-spp must be a positive integer" >&2; exit 2; }
[[ $threads =~ ^[0-9]+$ && $threads -ge 1 ]] || { echo "methods-error: --threads must be a positive integer" >&2; exit 2; }
IFS=, read -r -a scene_list <<<"$scenes"
IFS=, read -r -a method_list <<<"$methods"
for m in "${method_list[@]}"; do
    case $m in raytrace|path|radiosity|hybrid|gather) ;;
        *) echo "methods-error: unknown method '$m' (raytrace, path, radiosity, hybrid, gather)" >&2; exit 2 ;;
    esac
done
for s in "${scene_list[@]}"; do
    [[ -f $root/scenes/$s.mid ]] || { echo "methods-error: no scene scenes/$s.mid" >&2; exit 2; }
done
if [[ -n $reference ]]; then
    [[ ${#scene_list[@]} -eq 1 ]] || { echo "methods-error: --reference needs exactly one scene (--scenes)" >&2; exit 2; }
    [[ -f $reference ]] || { echo "methods-error: no reference image '$reference'" >&2; exit 2; }
    reference=$(cd "$(dirname "$reference")" && pwd)/$(basename "$reference")
fi
[[ -x /usr/bin/time ]] || { echo "methods-error: needs GNU time (/usr/bin/time; apt-get install time)" >&2; exit 1; }
(( plot == 0 )) || command -v gnuplot >/dev/null || { echo "methods-error: needs gnuplot (or --no-plot)" >&2; exit 1; }

if [[ -n "${TESTBED:-}" ]]; then
    TB=$TESTBED
else
    TB=$root/build/release/testbed
    if [[ ! -x "$TB" ]]; then
        echo "methods-error: building $TB (Release)"
        cmake -S "$root" -B "$root/build/release" -DCMAKE_BUILD_TYPE=Release >/dev/null
        cmake --build "$root/build/release" -j "$(nproc)" --target testbed >/dev/null
    fi
fi
[[ -x "$TB" ]] || { echo "methods-error: $TB is not an executable" >&2; exit 2; }
: "${cache:=$root/build/methods-error-cache}"
mkdir -p "$out" "$cache"
out=$(cd "$out" && pwd)
export OMP_WAIT_POLICY=passive   # spinning OpenMP waits distort shared-core timings

work=$(mktemp -d "${TMPDIR:-/tmp}/methods-error.XXXXXX")
trap 'rm -rf "$work"' EXIT

# The ladders: method|mode|budget|options. Budgets name what grows.
ladder() {
    if (( quick )); then
        case $1 in
            raytrace) printf '%s\n' "raytrace|whitted|1 spp|--spp 1" "raytrace|whitted|4 spp|--spp 4" ;;
            path) printf '%s\n' "path|path|1 spp|--spp 1" "path|path|4 spp|--spp 4" "path|path|16 spp|--spp 16" ;;
            radiosity) printf '%s\n' "radiosity|radiosity|edge 160, 1%|--max-edge 160 --threshold 0.01" ;;
            hybrid) printf '%s\n' "hybrid|interpolated|edge 160, 1 spp|--max-edge 160 --threshold 0.01 --spp 1" \
                                  "hybrid|interpolated|edge 80, 4 spp|--max-edge 80 --threshold 0.01 --spp 4" ;;
            gather) printf '%s\n' "hybrid|gather|edge 160, 1 spp|--max-edge 160 --threshold 0.01 --spp 1 --hybrid-mode gather" \
                                  "hybrid|gather|edge 80, 4 spp|--max-edge 80 --threshold 0.01 --spp 4 --hybrid-mode gather" ;;
        esac
        return
    fi
    local n
    case $1 in
        raytrace) for n in 1 4 16 64; do echo "raytrace|whitted|$n spp|--spp $n"; done ;;
        path) for n in 1 4 16 64 256 512; do echo "path|path|$n spp|--spp $n"; done ;;
        radiosity)
            printf '%s\n' "radiosity|radiosity|edge 160, 1%|--max-edge 160 --threshold 0.01" \
                          "radiosity|radiosity|edge 80, 1%|--max-edge 80 --threshold 0.01" \
                          "radiosity|radiosity|edge 40, 0.3%|--max-edge 40 --threshold 0.003" ;;
        hybrid)
            printf '%s\n' "hybrid|interpolated|edge 160, 1 spp|--max-edge 160 --threshold 0.01 --spp 1" \
                          "hybrid|interpolated|edge 80, 4 spp|--max-edge 80 --threshold 0.01 --spp 4" \
                          "hybrid|interpolated|edge 40, 16 spp|--max-edge 40 --threshold 0.003 --spp 16" \
                          "hybrid|interpolated|edge 40, 64 spp|--max-edge 40 --threshold 0.003 --spp 64" ;;
        gather)
            printf '%s\n' "hybrid|gather|edge 160, 1 spp|--max-edge 160 --threshold 0.01 --spp 1 --hybrid-mode gather" \
                          "hybrid|gather|edge 80, 4 spp|--max-edge 80 --threshold 0.01 --spp 4 --hybrid-mode gather" \
                          "hybrid|gather|edge 40, 16 spp|--max-edge 40 --threshold 0.003 --spp 16 --hybrid-mode gather" ;;
    esac
}

# scene_at NAME: the scene with its camera at res x res (the bundled scenes are square).
scene_at() {
    awk -v r="$res" '/resolution = \[[0-9]+ [0-9]+\]/ { sub(/\[[0-9]+ [0-9]+\]/, "[" r " " r "]") } { print }' \
        "$root/scenes/$1.mid" >"$work/$1.mid"
    grep -q "resolution = \\[$res $res\\]" "$work/$1.mid" || { echo "methods-error: $1: no camera resolution to set" >&2; return 1; }
    echo "$work/$1.mid"
}

# run LOG CMD...: CMD under GNU time (wall, user, system into LOG.time); output to LOG.
run() {
    local log=$1
    shift
    echo "  \$ $(printf '%q ' "$@" | sed "s|$TB|testbed|g; s|$work/||g; s|$root/||g")"
    if ! /usr/bin/time -o "$log.time" -f '%e %U %S' "$@" >"$log" 2>&1; then
        echo "methods-error: failed: $*" >&2
        tail -n 20 "$log" | sed 's/^/    | /' >&2
        return 1
    fi
}

# compare IMG REF: "relMSE RMSE" over R, G, B.
compare() {
    "$TB" compare "$1" "$2" --json >"$work/cmp.json" || { echo "methods-error: compare $1 failed" >&2; return 1; }
    python3 -c 'import json, sys; a = json.load(open(sys.argv[1]))["all"]
print(repr(a["relmse"]) if a["relmse"] is not None else "nan", repr(a["rmse"]) if a["rmse"] is not None else "nan")' \
        "$work/cmp.json"
}

version=$("$TB" --version 2>&1 | head -n 1)
echo "methods-error: $(date -u '+%Y-%m-%d %H:%M UTC'), $version, $(nproc) cores, $threads threads, ${res}x${res}$( (( quick )) && echo ', --quick: figures mean little')"
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
csv=$out/methods-error.csv
echo "scene,method,mode,budget,seconds,cpu_seconds,relMSE,RMSE" >"$csv.tmp"

for s in "${scene_list[@]}"; do
    f=$(scene_at "$s")
    echo
    echo "=== $s (${res}x${res})"
    if [[ -n $reference ]]; then
        ref=$reference ref_desc="given"
        echo "reference: $ref (given)"
    else
        key=$( { cat "$f"; echo "res=$res spp=$ref_spp seed=1000003 $version"; } | sha256sum | cut -c1-16)
        ref=$cache/$s-${res}px-${ref_spp}spp-$key.pfm ref_desc="path, $ref_spp spp"
        if [[ -f $ref ]]; then
            echo "reference: $ref (cached)"
        else
            echo "reference: rendering $ref (path, $ref_spp spp)"
            # passes of at most 256 spp keep the accumulation in small steps
            passes=$(( (ref_spp + 255) / 256 )) per=$(( ref_spp < 256 ? ref_spp : 256 ))
            (( passes * per == ref_spp )) || { echo "methods-error: --ref-spp above 256 must be a multiple of 256" >&2; exit 2; }
            run "$work/ref.log" "$TB" render "$f" --method path --spp "$per" --passes "$passes" --seed 1000003 \
                --threads "$threads" -o "$work/ref.pfm"
            read -r w u sy <"$work/ref.log.time"
            echo "  reference took $w s wall, $(awk -v u="$u" -v s="$sy" 'BEGIN { print u + s }') s CPU"
            mv "$work/ref.pfm" "$ref"
        fi
    fi
    for m in "${method_list[@]}"; do
        while IFS='|' read -r method mode budget opts; do
            img=$work/img.pfm
            rm -f "$img"
            # shellcheck disable=SC2086 # opts holds options
            run "$work/r.log" "$TB" render "$f" --method "$method" $opts --threads "$threads" -o "$img"
            read -r w u sy <"$work/r.log.time"
            read -r rel rmse < <(compare "$img" "$ref")
            cpu=$(awk -v u="$u" -v s="$sy" 'BEGIN { printf "%.2f", u + s }')
            printf '    %-12s %-13s %-18s %7.2f s wall %7.2f s CPU  relMSE %-10.4g RMSE %.4g\n' \
                "$method" "$mode" "$budget" "$w" "$cpu" "$rel" "$rmse"
            echo "$s,$method,$mode,\"$budget\",$w,$cpu,$rel,$rmse" >>"$csv.tmp"
        done < <(ladder "$m")
    done
done
mv "$csv.tmp" "$csv"
echo
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "methods-error: wrote $csv"

# The table, the equal-time ratios and the check.
status=0
python3 - "$csv" "$check" <<'EOF' || status=1
import csv, math, sys
rows = list(csv.DictReader(open(sys.argv[1])))
check = sys.argv[2] == "1"
bad = []
for r in rows:
    for k in ("seconds", "cpu_seconds", "relMSE", "RMSE"):
        r[k] = float(r[k])
        if not math.isfinite(r[k]) or r[k] < 0:
            bad.append(f"{r['scene']} {r['method']} {r['mode']} {r['budget']}: {k} = {r[k]}")

def curve(scene, mode):
    """(CPU s, relMSE) in budget order (the CSV's), and sorted by time (ties kept in budget order)."""
    c = [(r["cpu_seconds"], r["relMSE"]) for r in rows if r["scene"] == scene and r["mode"] == mode]
    return c, sorted(c, key=lambda x: x[0])

def at(c, t):
    """relMSE of curve c at CPU time t, log-log interpolation; None outside its span."""
    if not c or t < c[0][0] or t > c[-1][0]:
        return None
    for (t0, e0), (t1, e1) in zip(c, c[1:]):
        if t0 <= t <= t1:
            if t1 == t0 or e0 <= 0 or e1 <= 0 or t0 <= 0:
                return e0
            f = math.log(t / t0) / math.log(t1 / t0)
            return math.exp(math.log(e0) + f * (math.log(e1) - math.log(e0)))
    return c[-1][1]

scenes = list(dict.fromkeys(r["scene"] for r in rows))
print()
print("| scene | method | mode | budget | wall s | CPU s | relMSE | RMSE |")
print("| --- | --- | --- | --- | --- | --- | --- | --- |")
for r in rows:
    print(f"| {r['scene']} | {r['method']} | {r['mode']} | {r['budget']} | {r['seconds']:.2f} | {r['cpu_seconds']:.2f} "
          f"| {r['relMSE']:.4g} | {r['RMSE']:.4g} |")
print()
print("Equal CPU time: relMSE of the Whitted and the path tracer at each hybrid render's CPU time, over the hybrid's")
print("(Whitted: beyond its largest budget its error stays at its floor, so its last value is used there;")
print("path: log-log interpolation along its curve, '-' outside the span it was measured over).")
print()
print("| scene | hybrid mode | budget | CPU s | hybrid relMSE | Whitted relMSE | Whitted / hybrid | path relMSE | path / hybrid |")
print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
for s in scenes:
    (wb, wh), (_, pa) = curve(s, "whitted"), curve(s, "path")
    for r in rows:
        if r["scene"] != s or r["method"] != "hybrid":
            continue
        t, e = r["cpu_seconds"], r["relMSE"]
        # past its slowest render the Whitted error stays at its largest budget's (its floor)
        w = None if not wh else (at(wh, t) if t <= wh[-1][0] else wb[-1][1])
        p = at(pa, t)
        fmt = lambda v: "-" if v is None else f"{v:.4g}"
        ratio = lambda v: "-" if v is None or e <= 0 else f"{v / e:.2f}"
        print(f"| {s} | {r['mode']} | {r['budget']} | {t:.2f} | {e:.4g} | {fmt(w)} | {ratio(w)} | {fmt(p)} | {ratio(p)} |")
if bad:
    print("methods-error: errors not finite or negative:\n  " + "\n  ".join(bad), file=sys.stderr)
    sys.exit(1)
if check:
    failed = False
    checked = 0
    for s in scenes:
        if "spheres" not in s:
            continue
        wh = [r for r in rows if r["scene"] == s and r["mode"] == "whitted"]
        if not wh:
            print(f"methods-error: --check needs the raytrace ladder on {s}", file=sys.stderr)
            sys.exit(1)
        w = wh[-1]
        for mode in ("interpolated", "gather"):
            hy = [r for r in rows if r["scene"] == s and r["mode"] == mode]
            if not hy:
                continue
            h = hy[-1]
            checked += 1
            ok = h["relMSE"] < w["relMSE"]
            print(f"check {s}: hybrid {mode} ({h['budget']}) relMSE {h['relMSE']:.4g} "
                  f"{'<' if ok else 'NOT <'} Whitted ({w['budget']}) {w['relMSE']:.4g}: {'ok' if ok else 'FAILED'}")
            failed |= not ok
    if not checked:
        print("methods-error: --check found no spheres scene with a hybrid ladder", file=sys.stderr)
        sys.exit(1)
    sys.exit(1 if failed else 0)
EOF

if (( plot )); then
    for s in "${scene_list[@]}"; do
        # one data block per method and mode, in the CSV's order
        python3 - "$csv" "$s" >"$work/plot.dat" <<'EOF'
import csv, sys
rows = [r for r in csv.DictReader(open(sys.argv[1])) if r["scene"] == sys.argv[2]]
names = {"whitted": "raytrace (Whitted)", "path": "path", "radiosity": "radiosity",
         "interpolated": "hybrid interpolated", "gather": "hybrid gather"}
for mode in dict.fromkeys(r["mode"] for r in rows):
    print(f'"{names.get(mode, mode)}"')
    for r in rows:
        if r["mode"] == mode:
            print(r["cpu_seconds"], r["relMSE"], r["RMSE"])
    print()
    print()
EOF
        nblocks=$(grep -c '^"' "$work/plot.dat")
        for term in png svg; do
            if [[ $term == png ]]; then t="pngcairo size 1200,520 font ',10'"; else t="svg size 1200,520 font 'sans,12'"; fi
            gnuplot <<EOF
set terminal $t
set output '$out/methods-error-$s.$term'
set multiplot layout 1,2 title "Error against a converged path-traced reference ($ref_desc): $s, ${res}x${res}" noenhanced
set xlabel 'CPU seconds (user + system, whole process, $threads threads)'
set logscale xy
set grid
set style data linespoints
set key top right noenhanced
set ylabel 'relMSE'
plot for [i=0:$((nblocks - 1))] '$work/plot.dat' index i using 1:2 title columnheader(1) lw 2 pt 7
set ylabel 'RMSE'
set key off
plot for [i=0:$((nblocks - 1))] '$work/plot.dat' index i using 1:3 title columnheader(1) lw 2 pt 7
unset multiplot
EOF
        done
        echo "methods-error: wrote $out/methods-error-$s.png and .svg"
    done
fi
exit $status
