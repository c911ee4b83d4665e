#!/usr/bin/env bash
# End-to-end scale runs (docs/performance.md, "Scale"; issue 19): a 10^7-object
# analytic scene (about 3 GB of MID from `testbed generate grid`) and about 10^7
# mesh triangles (`testbed generate mesh`), each generated into DIR, measured by
# `testbed bench scale` (parse, prepare, build, time to first pixel, peak RSS)
# and then rendered whole (1024x768, 1 spp) under GNU time (peak RSS) with
# --stats; the scenes are deleted afterwards. Minutes of run time and up to
# ~10 GB of memory: not part of the test suite, run it alone on the machine.
#
#   tools/bench/scale-10m.sh [DIR]          (default: $TMPDIR or /tmp)
#
# Environment:
#   TESTBED      the testbed binary (default: build/rel/testbed, a Release build)
#   GRID_COUNT   objects of the grid scene (default 10000000)
#   MESH_COUNT   objects of the mesh scene (default 14000: about 10^7 triangles)
#   KINDS        which runs (default "grid mesh")
#   THREADS      threads (default 2)
#   BENCH        0: skip `testbed bench scale` (one load per scene instead of two; the
#                render's Scene/load + Scene/accel build timers then stand for the time
#                to first pixel)
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
tb=${TESTBED:-$root/build/rel/testbed}
dir=${1:-${TMPDIR:-/tmp}}
threads=${THREADS:-2}
mkdir -p "$dir"
[ -x "$tb" ] || { echo "scale-10m.sh: no testbed binary at $tb (set TESTBED)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "scale-10m.sh: needs GNU time (/usr/bin/time)" >&2; exit 2; }

run() { # KIND COUNT
    local kind=$1 count=$2 mid="$dir/scale-10m-$1-$2.mid"
    echo "== $kind $count: load average $(cut -d' ' -f1-3 /proc/loadavg), $(nproc) cores, $(awk '/MemAvailable/ {printf "%.1f GiB available", $2 / 1048576}' /proc/meminfo)"
    if [ "${BENCH:-1}" != 0 ]; then
        "$tb" bench scale --kind "$kind" --counts "$count" --threads "$threads" --dir "$dir"
    fi
    /usr/bin/time -f "generate: %e s wall, %M KB peak" "$tb" generate "$kind" --count "$count" -o "$mid"
    ls -l "$mid" | awk '{printf "MID: %.2f GB\n", $5 / 1e9}'
    rm -f "$dir/scale-10m-$kind.json"
    /usr/bin/time -v "$tb" render "$mid" -o "$dir/scale-10m-$kind.png" --spp 1 --threads "$threads" \
        --stats "$dir/scale-10m-$kind.json" 2>"$dir/scale-10m-$kind.time" || echo "render FAILED (exit $?)"
    grep -E "Elapsed|Maximum resident|Exit status|User time|System time" "$dir/scale-10m-$kind.time"
    grep -v "^\s" "$dir/scale-10m-$kind.time" | grep -v "Command being timed" | head -5 || true
    python3 - "$dir/scale-10m-$kind.json" <<'PY' || true
import json, sys
d = json.load(open(sys.argv[1]))
c, t, m = d.get("counters", {}), d.get("timers", {}), d.get("memory", {})
for k in ("Scene/references", "Scene/triangle references", "Scene/polygons objects"):
    if k in c: print(f"{k}: {c[k]}")
for k, v in sorted(t.items()):
    if v.get("calls") and v.get("seconds", 0) > 0.5: print(f"timer {k}: {v['seconds']:.2f} s")
for k in ("Scene/memory", "Scene/memory of objects", "Scene/memory of meshes", "Scene/memory of acceleration"):
    if k in m: print(f"{k}: {m[k] / 2**20:.0f} MiB")
r = d.get("ratios", {})
for k in ("Scene/memory per object", "Scene/memory per triangle"):
    if k in r and r[k].get("ratio"): print(f"{k}: {r[k]['ratio']:.0f} B")
PY
    rm -f "$mid" "$dir/scale-10m-$kind.png"
    echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
}

for kind in ${KINDS:-grid mesh}; do
    case $kind in
    grid) run grid "${GRID_COUNT:-10000000}" ;;
    mesh) run mesh "${MESH_COUNT:-14000}" ;;
    *) echo "scale-10m.sh: unknown kind $kind" >&2; exit 2 ;;
    esac
done
