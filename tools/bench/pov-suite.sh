#!/usr/bin/env bash
# POV-Ray suite (docs/performance.md, "Ray tracer vs POV-Ray"): renders each
# POV-style scene of tools/bench/pov/ (a MID file and its POV-Ray twin,
# written by tools/bench/mid2pov.py) with `testbed render` and with POV-Ray
# 3.7 at the same resolution, samples per pixel, area-light samples, depth
# and thread count; times whole processes and prints, per scene, ours /
# POV-Ray on user CPU time and on wall time, then the suite's MAX ratio (the
# worst case, which the goal <= 0.7 is judged by).
#
#   tools/bench/pov-suite.sh [--only a,b] [--instructions] [OUT]
#   tools/bench/pov-suite.sh --check [OUT]
#
# --check does not time: it verifies that every committed .pov is what
# mid2pov.py writes from its .mid, then renders both at 200 x 150 (same
# samples and depth) and compares the images with `testbed compare`; a scene
# fails when the mean SSIM over R, G, B is below POV_SSIM_MIN (default 0.85)
# or the relative difference of the mean pixel values exceeds POV_MEAN_TOL
# (default 0.1). The bound is loose on purpose: the two renderers sample
# the pixel and the area lights with different random points, and differ by
# design in a few places (see docs/performance.md). Without povray, --check
# verifies the .pov files only and exits 77 (skipped).
#
# Environment:
#   TESTBED  the testbed binary (default: configure and build build/bench,
#            Release)
#   R        POV-Ray's antialiasing grid: +A0.0 +AM1 +R$R +J makes every
#            pixel R x R jittered samples plus the shared corner sample, so
#            ours gets --spp R*R+1 (default 2: 5 samples per pixel)
#   LIGHT_SAMPLES  area-light samples per shading point, a square (default 4:
#            POV-Ray's 2 x 2 area_light grid)
#   THREADS  thread count for both (default 1)
#   ADC      ours' --adc-bailout (default 0.00392156862745098 = 1/255, the
#            adc_bailout the .pov files state: POV-Ray's default adaptive
#            depth control); ADC=0 traces every ray of ours to the depth
#            limit (POV-Ray still bails out)
#   SUITE    the folder of scene pairs (default tools/bench/pov)
#   BASELINE another testbed binary (e.g. a Release build of main), timed
#            in the same run: the last column is its user CPU / POV-Ray's,
#            so a change is judged within one run on a shared machine (a
#            build without --adc-bailout runs without it)
#   RUNS     timed runs per command (default 3; medians are reported)
#
# Timing: /usr/bin/time (GNU time) per run, wall and user CPU seconds of the
# whole process (parse, acceleration structure, render, PNG) for both
# programs; the medians of RUNS runs. --instructions also counts our
# process's instructions (perf stat -e instructions), which do not depend on
# the machine's load. The load average is printed before and after.
# Needs: povray (tools/setup.sh --bench), python3, GNU time.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
suite=${SUITE:-$root/tools/bench/pov}
scenes_all="classic area glass quadrics csg mirror-room"
only=""
check=0
instr=0
out=""
while [[ $# -gt 0 ]]; do
  case $1 in
    --only) only=$2; shift 2 ;;
    --check) check=1; shift ;;
    --instructions) instr=1; shift ;;
    -h|--help) sed -n '2,/^set -e/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    -*) echo "pov-suite: unknown option $1" >&2; exit 2 ;;
    *) out=$1; shift ;;
  esac
done
out=${out:-/tmp/pov-suite}
scenes=$scenes_all
if [[ -n $only ]]; then
  scenes=${only//,/ }
  for s in $scenes; do
    [[ -f $suite/$s.mid ]] || { echo "pov-suite: no scene $s (have: $scenes_all)" >&2; exit 2; }
  done
fi
R=${R:-2}
light_samples=${LIGHT_SAMPLES:-4}
threads=${THREADS:-1}
runs=${RUNS:-3}
max_depth=5
adc=${ADC:-0.00392156862745098}
spp=$((R * R + 1))

have_povray=1
command -v povray >/dev/null || have_povray=0
if [[ $check == 0 ]]; then
  [[ $have_povray == 1 ]] || { echo "pov-suite: povray not found (tools/setup.sh --bench)" >&2; exit 1; }
  [[ -x /usr/bin/time ]] || { echo "pov-suite: GNU time not found (tools/setup.sh --bench)" >&2; exit 1; }
fi
if [[ -z "${TESTBED:-}" ]]; then
  cmake -S "$root" -B "$root/build/bench" -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$root/build/bench" -j2 --target testbed >/dev/null
  TESTBED=$root/build/bench/testbed
fi
mkdir -p "$out"

pov_args() {  # POV-Ray's options for scene file $1 at $2 x $3, output $4
  echo +I"$1" +O"$4" +W"$2" +H"$3" +A0.0 +AM1 +R"$R" +J +WT"$threads" -D -V -GA +FN
}

if [[ $check == 1 ]]; then
  fail=0
  for s in $scenes; do
    # mid2pov names its input in the header: run from the root for the same text.
    # mid2pov names its input in the header: the path as committed.
    cp "$suite/$s.mid" "$out/$s.mid"
    (cd "$out" && python3 "$root/tools/bench/mid2pov.py" "$s.mid" --light-samples "$light_samples" \
      --max-depth "$max_depth") | sed "1s,from $s.mid;,from tools/bench/pov/$s.mid;," > "$out/$s.regen.pov"
    if ! cmp -s "$out/$s.regen.pov" "$suite/$s.pov"; then
      echo "pov-suite: $s.pov is not what mid2pov.py writes from $s.mid (regenerate it:" \
        "tools/bench/mid2pov.py tools/bench/pov/$s.mid > tools/bench/pov/$s.pov)"
      fail=1
      continue
    fi
    if [[ $have_povray == 0 ]]; then
      echo "pov-suite: $s.pov matches $s.mid (povray not installed: images not compared)"
      continue
    fi
    sed 's/^\( *resolution = \)\[[0-9]* [0-9]*\]/\1[200 150]/' "$suite/$s.mid" > "$out/$s.small.mid"
    "$TESTBED" render "$out/$s.small.mid" -o "$out/$s.ours.png" --spp "$spp" --light-samples "$light_samples" \
      --max-depth "$max_depth" --adc-bailout "$adc" --exposure 0 --threads 0 >/dev/null 2>"$out/$s.ours.log"
    # shellcheck disable=SC2046
    povray $(pov_args "$suite/$s.pov" 200 150 "$out/$s.pov.png") +WT2 >/dev/null 2>&1
    "$TESTBED" compare "$out/$s.ours.png" "$out/$s.pov.png" --json > "$out/$s.compare.json"
    python3 - "$s" "$out/$s.ours.png" "$out/$s.pov.png" "$out/$s.compare.json" \
      "${POV_SSIM_MIN:-0.85}" "${POV_MEAN_TOL:-0.1}" <<'EOF' || fail=1
import json, sys, zlib, struct
name, a, b, cj, ssim_min, mean_tol = sys.argv[1:]
r = json.load(open(cj))
ssim = r["all"]["ssim"]

def mean_png(path):
    # Mean 8-bit value of an RGB/RGBA PNG (filters undone), no dependencies.
    data = open(path, "rb").read()
    pos, idat = 8, b""
    w = h = bpp = None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and ctype in (2, 6), (path, depth, ctype)
            bpp = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw = zlib.decompress(idat)
    stride = w * bpp
    prev = bytearray(stride)
    total = 0
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            left = line[i - bpp] if i >= bpp else 0
            up = prev[i]
            ul = prev[i - bpp] if i >= bpp else 0
            if f == 1: line[i] = (line[i] + left) & 255
            elif f == 2: line[i] = (line[i] + up) & 255
            elif f == 3: line[i] = (line[i] + (left + up) // 2) & 255
            elif f == 4:
                p = left + up - ul
                pa, pb, pc = abs(p - left), abs(p - up), abs(p - ul)
                line[i] = (line[i] + (left if pa <= pb and pa <= pc else up if pb <= pc else ul)) & 255
        total += sum(line[i] for i in range(stride) if i % bpp < 3)
        prev = line
    return total / (w * h * 3)

ma, mb = mean_png(a), mean_png(b)
rel = abs(ma - mb) / max(mb, 1.0)
ok = ssim >= float(ssim_min) and rel <= float(mean_tol)
print(f"pov-suite: {name:12s} SSIM {ssim:.3f} (>= {ssim_min}), mean ours {ma:.1f} POV-Ray {mb:.1f} "
      f"(rel. diff. {rel:.3f} <= {mean_tol}): {'ok' if ok else 'FAIL'}")
sys.exit(0 if ok else 1)
EOF
  done
  [[ $fail == 0 && $have_povray == 0 ]] && exit 77
  exit $fail
fi

# Prints "WALL USER" (medians over RUNS runs, seconds) for the command in "$@".
timeit() {
  local t=()
  for ((i = 0; i < runs; i++)); do
    /usr/bin/time -o "$out/time.txt" -f '%e %U' "$@" >/dev/null 2>&1
    t+=("$(tail -1 "$out/time.txt")")
  done
  printf '%s\n' "${t[@]}" | python3 -c 'import sys,statistics as s; r=[l.split() for l in sys.stdin]; print(s.median(float(a[0]) for a in r), s.median(float(a[1]) for a in r))'
}

echo "pov-suite: $spp samples/pixel (POV +A0.0 +AM1 +R$R +J), $light_samples area-light samples, depth $max_depth, ours --adc-bailout $adc, $threads thread(s), $runs runs (medians)"
echo "pov-suite: $(povray --version 2>&1 | grep -m1 "^POV-Ray"); $($TESTBED --version 2>&1 | head -1)"
echo "pov-suite: load before: $(uptime)"
hdr=$(printf '%-12s %9s %9s %9s %9s %8s %8s' scene "ours wall" "POV wall" "ours CPU" "POV CPU" "CPU x" "wall x")
[[ $instr == 1 ]] && hdr="$hdr $(printf '%14s' 'ours instr')"
[[ -n ${BASELINE:-} ]] && hdr="$hdr $(printf '%8s' 'base x')"
echo "$hdr"
rows=$out/rows.txt
: > "$rows"
for s in $scenes; do
  read -r width height < <(sed -n 's,^// resolution \([0-9]*\) x \([0-9]*\)$,\1 \2,p' "$suite/$s.pov")
  ours=("$TESTBED" render "$suite/$s.mid" -o "$out/$s.ours.png" --spp "$spp" --light-samples "$light_samples"
    --max-depth "$max_depth" --adc-bailout "$adc" --exposure 0 --threads "$threads")
  # shellcheck disable=SC2207
  pov=(povray $(pov_args "$suite/$s.pov" "$width" "$height" "$out/$s.pov.png"))
  read -r ow ou < <(timeit "${ours[@]}")
  read -r pw pu < <(timeit "${pov[@]}")
  line=$(python3 -c 'import sys; s,ow,pw,ou,pu=sys.argv[1:]; ow,pw,ou,pu=map(float,(ow,pw,ou,pu)); print(f"{s:<12} {ow:9.2f} {pw:9.2f} {ou:9.2f} {pu:9.2f} {ou/pu:8.2f} {ow/pw:8.2f}")' \
    "$s" "$ow" "$pw" "$ou" "$pu")
  if [[ $instr == 1 ]]; then
    n=$(perf stat -x, -e instructions "${ours[@]}" 2>&1 >/dev/null | awk -F, '/instructions/ {print $1}')
    line="$line $(printf '%14s' "$n")"
  fi
  if [[ -n ${BASELINE:-} ]]; then
    base=("$BASELINE" "${ours[@]:1}")
    base[4]=$out/$s.base.png
    if ! "$BASELINE" render --help 2>&1 | grep -q -- --adc-bailout; then
      base=("${base[@]:0:11}" "${base[@]:13}") # a build before --adc-bailout: every ray traced
    fi
    read -r _ bu < <(timeit "${base[@]}")
    line="$line $(python3 -c 'import sys; print(f"{float(sys.argv[1]) / float(sys.argv[2]):8.2f}")' "$bu" "$pu")"
  fi
  echo "$line"
  echo "$line" >> "$rows"
done
awk -v base="${BASELINE:-}" '{ if ($6 > m) { m = $6; w = $1 } if ($7 > mw) mw = $7; if ($NF > mb) mb = $NF }
  END { printf "MAX ratio (user CPU): %.2f (%s); MAX wall ratio: %.2f", m, w, mw
        if (base != "") printf "; baseline MAX (user CPU): %.2f", mb
        printf "\n" }' "$rows"
echo "pov-suite: load after: $(uptime)"
echo "pov-suite: images in $out (SCENE.ours.png, SCENE.pov.png)"
