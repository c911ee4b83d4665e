#!/usr/bin/env bash
# POV-Ray peer benchmark (docs/performance.md, "Ray tracer vs POV-Ray"):
# renders the primitive/CSG showcase with `testbed render` and with POV-Ray
# 3.7 at the same resolution, samples per pixel, area-light samples, ray
# depth and thread count, times both in the same run and prints the ratio
# ours / POV-Ray (the issue's goal: <= 0.7). The POV-Ray scene is written
# from the MID file by tools/bench/mid2pov.py (same objects, materials,
# lights and camera; see its header for the differences), into OUT.
#
#   tools/bench/povray-showcase.sh [OUT]          (default OUT: /tmp/povray-showcase)
#
# Environment:
#   TESTBED  the testbed binary (default: configure and build build/bench,
#            Release)
#   SCENE    the MID scene (default scenes/showcase.mid)
#   R        POV-Ray's antialiasing grid: +A0.0 +AM1 +R$R +J makes every
#            pixel R x R jittered samples plus the shared corner sample,
#            so ours gets --spp R*R+1 (default R = 2: 5 samples per pixel)
#   LIGHT_SAMPLES  area-light samples per shading point, a square (default 4:
#            POV-Ray's 2 x 2 area_light grid)
#   THREADS  thread counts to compare (default "1 2": POV-Ray +WT, ours --threads)
#   RUNS     timed runs per command (default 3; the median is reported)
#
# Timing: hyperfine when installed (its median wall-clock time and mean
# user + system CPU time), else RUNS runs of /usr/bin/time (medians). The
# times are whole-process: parsing, building the acceleration structure,
# rendering and writing the PNG, for both programs. On a shared machine the
# CPU-seconds figure is the one to compare (it is less disturbed by other
# processes than wall-clock time).
# Needs: povray (tools/setup.sh --bench), python3, GNU time or hyperfine.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
out=${1:-/tmp/povray-showcase}
scene=${SCENE:-$root/scenes/showcase.mid}
R=${R:-2}
light_samples=${LIGHT_SAMPLES:-4}
threads=${THREADS:-1 2}
runs=${RUNS:-3}
max_depth=5

command -v povray >/dev/null || { echo "povray-showcase: povray not found (tools/setup.sh --bench)" >&2; exit 1; }
if [[ -z "${TESTBED:-}" ]]; then
  cmake -S "$root" -B "$root/build/bench" -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$root/build/bench" -j2 --target testbed >/dev/null
  TESTBED=$root/build/bench/testbed
fi
mkdir -p "$out"
pov=$out/scene.pov
"$root/tools/bench/mid2pov.py" "$scene" --light-samples "$light_samples" --max-depth "$max_depth" > "$pov"
read -r width height < <(sed -n 's,^// resolution \([0-9]*\) x \([0-9]*\)$,\1 \2,p' "$pov")
spp=$((R * R + 1))

# Prints "WALL CPU" (seconds) for the command in "$@".
timeit() {
  if command -v hyperfine >/dev/null; then
    hyperfine --runs "$runs" --warmup 0 --style none --export-json "$out/hf.json" -- "$(printf '%q ' "$@")" >/dev/null 2>&1
    python3 -c 'import json,sys; r=json.load(open(sys.argv[1]))["results"][0]; print(r["median"], r["user"]+r["system"])' "$out/hf.json"
  else
    local t=()
    for ((i = 0; i < runs; i++)); do
      t+=("$( { /usr/bin/time -f '%e %U %S' "$@" >/dev/null 2>/dev/null; } 2>&1 | tail -1)")
    done
    printf '%s\n' "${t[@]}" | python3 -c 'import sys,statistics as s; r=[l.split() for l in sys.stdin]; print(s.median(float(a[0]) for a in r), s.median(float(a[1])+float(a[2]) for a in r))'
  fi
}

echo "povray-showcase: $scene, ${width}x${height}, $spp samples/pixel (POV +R$R), $light_samples area-light samples, depth $max_depth"
echo "povray-showcase: $(povray --version 2>&1 | grep -m1 "^POV-Ray"); $($TESTBED --version 2>&1 | head -1)"
echo "povray-showcase: load before: $(uptime)"
# POV-Ray's sample count, from its statistics (one untimed run at 2 threads).
povray +I"$pov" +O"$out/povray.png" +W"$width" +H"$height" +A0.0 +AM1 +R"$R" +J +WT2 -D -V +FN \
  2> "$out/povray.log" >/dev/null
pov_samples=$(awk '/^Pixels:/ {print $2 + $4}' "$out/povray.log")
echo "povray-showcase: camera rays: POV-Ray $pov_samples, ours $((spp * width * height))"
"$TESTBED" render "$scene" -o "$out/testbed.png" --spp "$spp" --light-samples "$light_samples" \
  --max-depth "$max_depth" --exposure 0 --threads 2 >/dev/null 2>&1

printf '%-8s %12s %12s %12s %12s %10s %10s\n' threads "ours wall" "POV wall" "ours CPU" "POV CPU" "wall x" "CPU x"
for t in $threads; do
  read -r ow oc < <(timeit "$TESTBED" render "$scene" -o "$out/testbed-t$t.png" --spp "$spp" \
    --light-samples "$light_samples" --max-depth "$max_depth" --exposure 0 --threads "$t")
  read -r pw pc < <(timeit povray +I"$pov" +O"$out/povray-t$t.png" +W"$width" +H"$height" \
    +A0.0 +AM1 +R"$R" +J +WT"$t" -D -V -GA +FN)
  python3 -c 'import sys; t,ow,pw,oc,pc=sys.argv[1:]; ow,pw,oc,pc=map(float,(ow,pw,oc,pc)); print(f"{t:<8} {ow:12.2f} {pw:12.2f} {oc:12.2f} {pc:12.2f} {ow/pw:10.2f} {oc/pc:10.2f}")' \
    "$t" "$ow" "$pw" "$oc" "$pc"
done
echo "povray-showcase: load after: $(uptime)"
echo "povray-showcase: images: $out/testbed.png $out/povray.png (same scene; compare by eye)"
