#!/usr/bin/env bash
# Every benchmark of docs/performance.md, on this machine, in one command.
#
#   tools/bench/run-all.sh [--quick] [--only NAME[,NAME...]] [--out FILE.md]
#   tools/bench/run-all.sh --help
#
# Prints a header of machine facts, then per benchmark: the exact commands it
# runs, the 1-minute load average before and after, and its results as the
# markdown tables of docs/performance.md (the same titles, rows and columns:
# --out FILE also writes them, with the machine and load-average tables, ready
# to paste over the doc's MEASURE cells). Figures are valid only on an idle
# machine: before each benchmark the CPU time other processes use is sampled
# for 2 s (nothing of ours runs then; the load average would count our own
# previous benchmark); above RUN_ALL_IDLE_BUSY percent of all cores (default
# 10) the benchmark gets a loud warning and "figures not valid" in the table.
#
# Environment:
#   TESTBED  the testbed binary (default: build/release/testbed, configured and
#            built with CMAKE_BUILD_TYPE=Release when missing). The helpers of
#            the ff-cpu, radiosity and adaptive benchmarks (test programs
#            ff_table, radiosity_patches_bench, refine_bench) are taken from the
#            same build folder and built there when missing.
#   TMPDIR   scratch space (the MID benchmark writes files of up to 2 GB and
#            needs twice that free)
#
# Peers (tools/setup.sh --bench): Embree 3 (linked into testbed when CMake
# found it; `rays`), POV-Ray and hyperfine (`povray`), GNU time (/usr/bin/time:
# `mid`, `raytrace`, `radiosity`, `adaptive`), lavapipe or a GPU (`gpu`,
# `ff-kernel`, `vulkan-render`). A missing peer fails that benchmark with a
# message; the script goes on with the others and exits 1 at the end.
# Exit status: 0 every benchmark ran, 1 one or more failed, 2 usage error.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)

# name|what it measures (the order is the doc's order)
benchmarks=(
    "intersect|object-level ray queries (testbed bench intersect)"
    "tessellate|tessellation (testbed bench tessellate)"
    "accel|BVH, grid and list on synthetic triangles (testbed bench accel)"
    "trace|rays from a file through the Cornell box (testbed trace)"
    "gpu|Vulkan intersect kernel vs the CPU path (testbed bench gpu, testbed validate --bench)"
    "ff-kernel|form-factor kernel vs the CPU batch (testbed bench formfactor)"
    "vulkan-render|Vulkan ray tracer vs the CPU ray tracer (testbed render --backend vulkan)"
    "mid|MID reader throughput and memory (tools/bench/mid-throughput.sh)"
    "raytrace|the ray tracer on the Cornell box (testbed render)"
    "povray|ray tracer vs POV-Ray 3.7 on the showcase (tools/bench/povray-showcase.sh)"
    "rays|BVH vs Embree 3 (testbed bench rays --embree; height field; imported mesh)"
    "radiosity|radiosity solver: form-factor methods, patches, default element size"
    "ff-cpu|CPU form factors: ray casting, exact point form factor, hemicube (ff_table timing)"
    "adaptive|mesh refinement and radiosity --adapt"
    "dist|mpirun: 2 ranks x 1 thread vs 1 rank (tools/bench/dist-scaling.sh)"
    "methods-error|speed versus error of raytrace, radiosity, hybrid and path (tools/bench/methods-error.sh)"
)

usage() {
    cat <<EOF
usage: tools/bench/run-all.sh [--quick] [--only NAME[,NAME...]] [--out FILE.md]

Runs every benchmark of docs/performance.md on this machine and prints, per
benchmark, the commands, the load average before and after, and the results as
markdown tables (the doc's tables, row and column names included).

  --quick        tiny sizes: checks that the runner and every command work
                 (whole run < 2 minutes); the figures mean nothing
  --only NAMES   run only these benchmarks (comma-separated)
  --out FILE     also write the machine facts and every results table to FILE
                 (markdown, ready to paste into docs/performance.md)
  -h, --help     this help

Benchmarks:
EOF
    local b
    for b in "${benchmarks[@]}"; do
        printf '  %-14s %s\n' "${b%%|*}" "${b#*|}"
    done
    cat <<EOF

Figures are only valid on an idle machine: before each benchmark the CPU
time of other processes is sampled for 2 s, and the benchmark warns when it
is above RUN_ALL_IDLE_BUSY percent of all cores (default 10). TESTBED selects the binary
(default build/release/testbed, built with the Release configuration if
missing). Exit status: 0 all ran, 1 some failed (a missing peer included),
2 usage error.
EOF
}

quick=0 only="" out=""
while [[ $# -gt 0 ]]; do
    case $1 in
        --quick) quick=1 ;;
        --only)
            [[ $# -ge 2 ]] || { echo "run-all: --only needs a list of names" >&2; exit 2; }
            only=$2; shift ;;
        --only=*) only=${1#--only=} ;;
        --out)
            [[ $# -ge 2 ]] || { echo "run-all: --out needs a file" >&2; exit 2; }
            out=$2; shift ;;
        --out=*) out=${1#--out=} ;;
        -h|--help) usage; exit 0 ;;
        *) echo "run-all: unknown option '$1' (see --help)" >&2; exit 2 ;;
    esac
    shift
done

selected=()
if [[ -n "$only" ]]; then
    IFS=, read -r -a wanted <<<"$only"
    for w in "${wanted[@]}"; do
        found=0
        for b in "${benchmarks[@]}"; do [[ "${b%%|*}" == "$w" ]] && found=1; done
        (( found )) || { echo "run-all: no benchmark '$w' (see --help)" >&2; exit 2; }
        selected+=("$w")
    done
else
    for b in "${benchmarks[@]}"; do selected+=("${b%%|*}"); done
fi
if [[ -n "$out" ]]; then
    : >"$out" || { echo "run-all: cannot write '$out'" >&2; exit 2; }
    out=$(cd "$(dirname "$out")" && pwd)/$(basename "$out")
fi

# ---------------------------------------------------------------- the binary
if [[ -n "${TESTBED:-}" ]]; then
    TB=$TESTBED
    [[ -x "$TB" ]] || { echo "run-all: TESTBED=$TB is not an executable" >&2; exit 2; }
else
    TB=$root/build/release/testbed
    if [[ ! -x "$TB" ]]; then
        echo "run-all: building $TB (Release)"
        cmake -S "$root" -B "$root/build/release" -DCMAKE_BUILD_TYPE=Release >/dev/null
        cmake --build "$root/build/release" -j "$(nproc)" --target testbed >/dev/null
    fi
fi
TB=$(cd "$(dirname "$TB")" && pwd)/$(basename "$TB")
tbdir=$(dirname "$TB")
exec 3>&1   # commands are shown on fd 3, so they never mix with captured output
export OMP_WAIT_POLICY=passive   # spinning OpenMP waits distort shared-core timings

work=$(mktemp -d "${TMPDIR:-/tmp}/run-all.XXXXXX")
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/tables"
: >"$work/tables.list"
: >"$work/loads.tsv"

# ------------------------------------------------------------------ helpers
is_quick() { (( quick )); }
# busy_percent: the share of all cores' time spent busy during 2 s (iowait
# and idle excluded), while this script only sleeps: what others use.
cpu_sample() { awk '/^cpu / { print $2 + $3 + $4 + $7 + $8 + $9, $2 + $3 + $4 + $5 + $6 + $7 + $8 + $9; exit }' /proc/stat; }
busy_percent() {
    local b1 t1 b2 t2
    read -r b1 t1 < <(cpu_sample)
    sleep 2
    read -r b2 t2 < <(cpu_sample)
    awk -v b=$((b2 - b1)) -v t=$((t2 - t1)) 'BEGIN { printf "%.1f", (t > 0 ? 100 * b / t : 0) }'
}
idle_max=${RUN_ALL_IDLE_BUSY:-10}
loadavg() { cut -d' ' -f1-3 /proc/loadavg; }

# cmd ARGS...: prints the command (as a user would type it), then runs it,
# output to $log (the current benchmark's log). Fails with the log's tail.
cmd() {
    local shown
    shown=$(printf '%q ' "$@")
    echo "  \$ ${shown//$TB/testbed}" | sed "s|$root/||g; s|$work/|\$WORK/|g" >&3
    echo "\$ $shown" >>"$log"
    if ! "$@" >>"$log" 2>&1; then
        echo "run-all: command failed: $shown" >&2
        tail -n 25 "$log" | sed 's/^/    | /' >&2
        return 1
    fi
}

# last_output: the output of the last cmd (from its "$ " line to the end of the log).
last_output() { awk '/^\$ / { n = NR } { l[NR] = $0 } END { for (i = n + 1; i <= NR; i++) print l[i] }' "$log"; }

# table ID TITLE COL...: starts a results table of the current benchmark.
table() {
    local id=$1 title=$2
    shift 2
    cur_table=$work/tables/$bench.$id.md
    echo "$cur_table" >>"$work/tables.list"
    {
        echo "<!-- run-all.sh table: $bench/$id -->"
        echo "*$title*"
        echo
        local IFS='|'
        local h="$*"
        echo "| ${h//|/ | } |"
        local s="|"
        for _ in "$@"; do s+=" --- |"; done
        echo "$s"
    } >"$cur_table"
}
# row CELL...: one row of the current table.
row() {
    local IFS='|'
    local r="$*"
    echo "| ${r//|/ | } |" >>"$cur_table"
}
# rows: rows of the current table from tab-separated lines on stdin.
rows() {
    local line
    while IFS= read -r line; do
        [[ -n "$line" ]] && echo "| ${line//$'\t'/ | } |" >>"$cur_table"
    done
    return 0
}
note() { echo "$*" >>"$cur_table"; }

# need PROGRAM WHAT: fails the benchmark when PROGRAM is missing.
need() {
    command -v "$1" >/dev/null || { echo "run-all: $bench: $1 not found ($2)" >&2; return 1; }
}
need_gnu_time() {
    [[ -x /usr/bin/time ]] || { echo "run-all: $bench: /usr/bin/time not found (apt-get install time)" >&2; return 1; }
}

# helper NAME SUBDIR: path of a test program of the build (built if missing).
helper() {
    local p=$tbdir/tests/$2/$1
    if [[ ! -x "$p" && -f "$tbdir/CMakeCache.txt" ]]; then
        echo "  (building $1 in $tbdir)" >&3
        cmake --build "$tbdir" --target "$1" -j "$(nproc)" >>"$log" 2>&1 || true
    fi
    [[ -x "$p" ]] || { echo "run-all: $bench: needs $p (a test program: build $tbdir with TB_TESTS=ON)" >&2; return 1; }
    echo "$p"
}

# scene NAME: the scene file to use (--quick: a copy at 1/8 of the resolution).
scene() {
    local src=$root/scenes/$1.mid
    if is_quick; then
        local dst=$work/quick-$1.mid
        [[ -f "$dst" ]] || awk '/resolution = \[[0-9]+ [0-9]+\]/ {
                match($0, /\[[0-9]+ [0-9]+\]/); split(substr($0, RSTART + 1, RLENGTH - 2), r, " ")
                w = int(r[1] / 8); h = int(r[2] / 8); if (w < 8) w = 8; if (h < 8) h = 8
                sub(/\[[0-9]+ [0-9]+\]/, "[" w " " h "]") } { print }' "$src" >"$dst"
        echo "$dst"
    else
        echo "$src"
    fi
}

# timed OUT CMD...: cmd under GNU time; OUT gets "wall_s user_s sys_s max_rss_kb".
timed() {
    local o=$1
    shift
    cmd /usr/bin/time -o "$o" -f '%e %U %S %M' "$@"
}

# The height-field scene of tools/bench/rays-heightfield.py (N = 250: 125 002 triangles).
heightfield() {
    local f=$work/hf.mid
    [[ -f "$f" ]] || python3 "$root/tools/bench/rays-heightfield.py" "$(is_quick && echo 20 || echo 250)" >"$f"
    echo "$f"
}

# ------------------------------------------------------------- benchmarks
bench_intersect() {
    local rays=1000000
    is_quick && rays=20000
    cmd "$TB" bench intersect --rays "$rays" --seed 1
    table objects "Ray intersection, one thread ($rays rays per object)" \
        object "hit %" "closest Mrays/s" "any-hit Mrays/s"
    last_output | awk 'f && NF >= 4 { n = $1; for (i = 2; i <= NF - 3; i++) n = n " " $i
                                      printf "%s\t%s\t%s\t%s\n", n, $(NF-2), $(NF-1), $NF }
                       /^object / { f = 1 }' | rows
}

bench_tessellate() {
    local secs=1
    is_quick && secs=0.02
    cmd "$TB" bench tessellate --angle 0.05 --seconds "$secs"
    last_output | awk 'f && NF == 6 { print $1, $3, $5, $6 } /^kind / { f = 1 }' >"$work/tess-a"
    cmd "$TB" bench tessellate --angle 0.2 --edge 0.1 --seconds "$secs"
    last_output | awk 'f && NF == 6 { print $1, $3, $5, $6 } /^kind / { f = 1 }' >"$work/tess-b"
    table kinds "Tessellation, one thread" kind "--angle 0.05: faces" "meshes/s" "Mtris/s" \
        "--angle 0.2 --edge 0.1: faces" "meshes/s" "Mtris/s"
    awk 'NR == FNR { a[$1] = $2 "\t" $3 "\t" $4; next } { printf "%s\t%s\t%s\t%s\t%s\n", $1, a[$1], $2, $3, $4 }' \
        "$work/tess-a" "$work/tess-b" | rows
}

bench_accel() {
    local tris=1000,100000 rays=200000
    is_quick && tris=1000 rays=5000
    cmd "$TB" bench accel --tris "$tris" --rays "$rays" --threads 1,2 --seed 1
    table rates "BVH, grid and list ($rays rays per set)" scene N rays "BVH Mrays/s 1T" "BVH Mrays/s 2T" \
        "grid Mrays/s 1T" "grid Mrays/s 2T" "list Mrays/s 1T" "BVH steps / tests per ray" "grid steps / tests per ray"
    last_output | awk -v sizes="$tris" '
        BEGIN { split(sizes, sz, ",") }
        /^# / { h++; next }
        $1 == "soup" || $1 == "sphere" {
            k = $1 "\t" sz[int((h - 1) / 2) + 1] "\t" $3
            if (!(k in seen)) { seen[k] = 1; order[++n] = k }
            v[k, $4, $5] = $6
            if ($5 == 1) st[k, $4] = $9 " / " $10 }
        END { for (i = 1; i <= n; i++) { k = order[i]
                printf "%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n", k, v[k, "bvh", 1], v[k, "bvh", 2], v[k, "grid", 1],
                       v[k, "grid", 2], v[k, "list", 1], st[k, "bvh"], st[k, "grid"] } }' | rows
    table builds "Structures built" scene N "BVH and grid (nodes, depth, SAH cost, memory, build time)"
    last_output | awk -v sizes="$tris" 'BEGIN { split(sizes, sz, ",") }
        /^# / { h++; s = $0; sub(/^# /, "", s); name = s; sub(/,.*/, "", name); sub(/^[^:]*: /, "", s)
                printf "%s\t%s\t%s\n", name, sz[int((h - 1) / 2) + 1], s }' | rows
}

bench_trace() {
    local n=1000000 runs=3
    is_quick && n=20000 runs=1
    local rays=$work/rays.bin
    cmd python3 "$root/tests/render/trace_rays.py" random "$n" "$rays" --box 0 0 0 556 548.8 559.2 --seed 1
    table rates "testbed trace, $n random rays in the Cornell box (best of $runs)" accel threads \
        "Mrays/s (wall)" "Mrays per CPU second"
    local accel t r
    for accel in bvh grid; do
        for t in 1 2; do
            for ((r = 0; r < runs; r++)); do
                cmd "$TB" trace "$root/scenes/cornell-box.mid" --rays "$rays" --hits "$work/hits-$accel-$t.bin" \
                    --accel "$accel" --threads "$t" --stats "$work/trace.json"
                last_output | sed -n 's/.* s, \([0-9.]*\) Mrays\/s, \([0-9.]*\) Mrays per CPU second.*/\1 \2/p'
            done | awk -v a="$accel" -v t="$t" '$1 > w { w = $1 } $2 > c { c = $2 }
                END { if (w == "") exit 1; printf "%s\t%s\t%s\t%s\n", a, t, w, c }' | rows
        done
    done
    for f in "$work"/hits-*.bin; do
        cmp -s "$f" "$work/hits-bvh-1.bin" || { echo "run-all: trace: $f differs from hits-bvh-1.bin" >&2; return 1; }
    done
    echo "  (all HITS files identical)"
}

bench_gpu() {
    local rays=200000 repeat=3 vrays=1000000
    is_quick && rays=2000 repeat=1 vrays=2000
    table sets "testbed bench gpu: Vulkan intersect kernel (lavapipe or GPU) vs the CPU path, $rays rays, median of $repeat" \
        scene set rays "CPU path Mrays/s" "Vulkan Mrays/s" "kernel Mrays/s" "ratio Vulkan/CPU (wall)" \
        "ratio Vulkan/CPU (per CPU second)" disagree
    local s f
    for s in cornell-box hf radiosity-room showcase; do
        if [[ $s == hf ]]; then f=$(heightfield); else f=$(scene "$s"); fi
        cmd "$TB" bench gpu "$f" --rays "$rays" --repeat "$repeat"
        last_output | awk -v s="$s" '$1 ~ /^(primary|shadow|diffuse)$/ && NF >= 9 {
            printf "%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n", s, $1, $2, $3, $4, $5, $6, $8, $9 }' | rows
    done
    grep -m1 '^device:' "$log" | sed 's/^/  /'
    table validate "testbed validate --bench: the validate mix ($vrays rays), one run" \
        scene "CPU path Mrays/s" "Vulkan Mrays/s" "ratio Vulkan/CPU" "Vulkan path split"
    for s in cornell-box radiosity-room showcase; do
        cmd "$TB" validate "$(scene "$s")" --rays "$vrays" --bench
        last_output | awk -v s="$s" '
            /^ *cpu path / { c = $3 }
            /^ *vulkan path / { v = $3; sp = $0; sub(/^[^(]*\(/, "", sp); sub(/\)$/, "", sp) }
            /^ *ratio vulkan\/cpu/ { r = $3 }
            END { if (r == "") exit 1; printf "%s\t%s\t%s\t%s\t%s\n", s, c, v, r, sp }' | rows
    done
}

bench_ff-kernel() {
    local args=()
    is_quick && args=(--shooters 2 --samples 4 --repeat 1)
    cmd "$TB" bench formfactor "$root/scenes/cornell-box.mid" "${args[@]}"
    last_output | sed -n '1p' | sed 's/^/  /'
    table paths "testbed bench formfactor: Cornell box, best of runs" path "M form factors/s" \
        "M segments/s" "wall s" "process CPU s"
    last_output | awk '$1 == "cpu" || $1 == "vulkan" { printf "%s\t%s\t%s\t%s\t%s\n", $1, $2, $3, $4, $5 }' | rows
    table ratio "Form-factor kernel: ratios" figure value
    last_output | awk '
        /^kernel device time/ { printf "kernel device time, s\t%s\n", $4; printf "kernel M segments/s\t%s\n", $6 }
        /^ratio vulkan\/cpu:/ { printf "ratio Vulkan/CPU (wall clock)\t%s\n", $3; printf "ratio Vulkan/CPU (per CPU second)\t%s\n", $6 }
        /^largest relative difference/ { printf "largest relative difference\t%s\n", $7 }' | rows
}

bench_vulkan-render() {
    table scenes "Vulkan ray tracer vs the CPU ray tracer (wall seconds of the render, 2 threads)" \
        scene spp "CPU path s" "Vulkan s" "ratio CPU/Vulkan" "intersect + occlusion s" "shade s (kernel s)" "routed s"
    local entry s spp f cs vs line
    for entry in cornell-box:4 cornell-box-rgb:4 showcase:1 materials:1; do
        s=${entry%%:*} spp=${entry#*:}
        is_quick && spp=1
        f=$(scene "$s")
        cmd "$TB" render "$f" -o "$work/cpu.pfm" --spp "$spp" --backend cpu
        cs=$(last_output | sed -n 's/.* samples, \([0-9.]*\) s (.*/\1/p' | tail -1)
        cmd "$TB" render "$f" -o "$work/vk.pfm" --spp "$spp" --backend vulkan
        vs=$(last_output | sed -n 's/.* samples, \([0-9.]*\) s (.*/\1/p' | tail -1)
        line=$(last_output | grep -m1 'wavefront') || { echo "run-all: no Vulkan split printed" >&2; return 1; }
        [[ -n "$cs" && -n "$vs" ]] || { echo "run-all: no render time printed" >&2; return 1; }
        awk -v s="$s" -v spp="$spp" -v c="$cs" -v v="$vs" -v l="$line" 'BEGIN {
            io = l; sub(/.*intersect \+ occlusion /, "", io); sub(/ s,.*/, "", io)
            sh = l; sub(/.*, shade /, "", sh); sub(/ s \(kernel /, " (", sh); sub(/ s\).*/, ")", sh)
            ro = l; sub(/.*routed /, "", ro); sub(/ s.*/, "", ro)
            printf "%s\t%s\t%s\t%s\t%.2f\t%s\t%s\t%s\n", s, spp, c, v, c / v, io, sh, ro }' | rows
    done
}

bench_mid() {
    need_gnu_time
    local mesh=(0.2 1 2) grid=(0.2 1) repeat=3
    is_quick && mesh=(0.002) grid=(0.002) repeat=1
    table read "MID reader: testbed check of a generated file (best of $repeat reads; page cache)" kind "size GB" \
        bytes objects "read MB/s (wall)" "read MB/s per CPU s" "peak RSS read MiB" "peak RSS generate MiB" \
        "generate MB/s"
    cmd env TESTBED="$TB" TMPDIR="$work" REPEAT="$repeat" KIND=mesh "$root/tools/bench/mid-throughput.sh" "${mesh[@]}"
    last_output | awk '$1 == "mesh" && $2 ~ /^[0-9.]+$/ { printf "%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n", $1, $2, $3, $4, $9, $10, $11, $7, $6 }' | rows
    cmd env TESTBED="$TB" TMPDIR="$work" REPEAT="$repeat" KIND=grid "$root/tools/bench/mid-throughput.sh" "${grid[@]}"
    last_output | awk '$1 == "grid" && $2 ~ /^[0-9.]+$/ { printf "%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n", $1, $2, $3, $4, $9, $10, $11, $7, $6 }' | rows
}

bench_raytrace() {
    need_gnu_time
    local spp=16
    is_quick && spp=1
    local f t
    f=$(scene cornell-box)
    table cornell "Ray tracer: Cornell box, 512 x 512, 31 bands, $spp spp, 4 light samples, depth 5" threads \
        "camera rays" "shadow rays" "wall s" "CPU s (user + system)" "camera rays per CPU second"
    for t in 1 2; do
        timed "$work/rt.time" "$TB" render "$f" -o "$work/cb.png" --spp "$spp" --threads "$t" --stats "$work/cb.json"
        python3 - "$work/cb.json" "$work/rt.time" "$t" <<'EOF' | rows
import json, sys
c = json.load(open(sys.argv[1]))["counters"]
w, u, s, _ = open(sys.argv[2]).read().split()
cpu = float(u) + float(s)
cam = c["Raytrace/camera rays"]
print(f"{sys.argv[3]}\t{cam}\t{c['Raytrace/shadow rays']}\t{float(w):.2f}\t{cpu:.2f}\t{cam / max(cpu, 1e-9):.0f}")
EOF
    done
}

bench_povray() {
    need povray "POV-Ray: tools/setup.sh --bench"
    need hyperfine "tools/setup.sh --bench"
    local env=(TESTBED="$TB" RUNS=3)
    is_quick && env=(TESTBED="$TB" RUNS=1 SCENE="$(scene showcase)")
    cmd env "${env[@]}" "$root/tools/bench/povray-showcase.sh" "$work/povray"
    last_output | grep -E '^povray-showcase: (/|.*camera rays|POV-Ray)' | sed 's/^/  /'
    table showcase "Ray tracer vs POV-Ray 3.7: showcase, whole processes (hyperfine: median wall, mean CPU)" \
        threads "ours wall s" "POV-Ray wall s" "ours CPU s" "POV-Ray CPU s" "ours / POV-Ray (wall)" \
        "ours / POV-Ray (CPU)"
    last_output | awk 'f && NF == 7 && $1 ~ /^[0-9]+$/ { printf "%s\t%s\t%s\t%s\t%s\t%s\t%s\n", $1, $2, $3, $4, $5, $6, $7 }
                       /^threads / { f = 1 }' | rows
}

# rays_embree LABEL SCENE-or-"imported" ARGS...: one bench rays run, rows of the current table.
rays_embree() {
    local label=$1 what=$2
    shift 2
    if [[ $what == imported ]]; then
        cmd env TESTBED="$TB" HF_N="$(is_quick && echo 20 || echo 250)" sh "$root/tools/bench/rays-imported.sh" "$@"
    else
        cmd "$TB" bench rays "$what" "$@"
    fi
    last_output | awk -v s="$label" '
        $1 ~ /^(primary|shadow|diffuse)$/ && $4 ~ /^[0-9]+$/ && NF == 10 {
            if (!($1 in seen)) { seen[$1] = 1; order[++n] = $1 }
            if ($4 == 1) { rays[$1] = $2; hit[$1] = $3; o1[$1] = $5; e1[$1] = $6; r1[$1] = $7 } else r2[$1] = $7 }
        $2 == "scaling" { sc[$1] = $8 " (" $10 ")"; sub(/,/, "", sc[$1]) }
        $2 == "agreement:" { d[$1] = $3 }
        END { for (i = 1; i <= n; i++) { k = order[i]
                printf "%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n", s, k, rays[k], hit[k], o1[k], e1[k], r1[k],
                       (k in r2) ? r2[k] : "", (k in sc) ? sc[k] : "", d[k] } }'
}

bench_rays() {
    local args=(--repeat 7 --no-stats) sargs=(--rays 100000)
    is_quick && args=(--repeat 1 --min-time 0 --no-stats --rays 2000) sargs=()
    # Embree is a peer: without it --embree is a usage error.
    if ! "$TB" bench rays "$root/scenes/cornell-box.mid" --embree --rays 100 --repeat 1 --min-time 0 --threads 1 \
            >"$work/embree-check" 2>&1; then
        echo "run-all: rays: Embree 3 missing: this testbed was built without it (tools/setup.sh --bench," >&2
        echo "run-all: rays: then reconfigure the build): $(tail -n 1 "$work/embree-check")" >&2
        return 1
    fi
    grep -m1 '^Embree' "$work/embree-check" | sed 's/ scene built.*(/ (/; s/^/  /'
    local hf
    hf=$(heightfield)
    table embree "Ours vs Embree 3 single-ray (default flags), Mrays/s at 1 thread, ratios ours / Embree" \
        scene set rays "hit %" "ours Mrays/s 1T" "Embree Mrays/s 1T" "ratio 1T" "ratio 2T" "scaling ours (Embree)" \
        "rays that differ"
    { rays_embree "Cornell box" "$root/scenes/cornell-box.mid" --embree "${args[@]}"
      rays_embree "height field" "$hf" --embree "${args[@]}"
      rays_embree "showcase" "$root/scenes/showcase.mid" --embree "${args[@]}" "${sargs[@]}"
      rays_embree "imported height field" imported --embree "${args[@]}"; } | rows
    table modes "Ours / Embree at 1 thread with other Embree modes (primary / shadow / diffuse)" scene \
        "Embree max_isa=sse2" "Embree robust (RTC_SCENE_FLAG_ROBUST)"
    local s f sse robust extra
    for s in "Cornell box" "height field" showcase; do
        extra=()
        case $s in
            "Cornell box") f=$root/scenes/cornell-box.mid ;;
            "height field") f=$hf ;;
            showcase) f=$root/scenes/showcase.mid; extra=(${sargs[@]+"${sargs[@]}"}) ;;
        esac
        sse=$(rays_embree "$s" "$f" --embree --embree-config max_isa=sse2 --threads 1 "${args[@]}" ${extra[@]+"${extra[@]}"} |
            awk -F'\t' '{ r = r (r == "" ? "" : " / ") $7 } END { print r }')
        robust=$(rays_embree "$s" "$f" --embree-robust --threads 1 "${args[@]}" ${extra[@]+"${extra[@]}"} |
            awk -F'\t' '{ r = r (r == "" ? "" : " / ") $7 } END { print r }')
        row "$s" "$sse" "$robust"
    done
}

bench_radiosity() {
    need_gnu_time
    local edge=35 thr=0.01 refs=64 reft=1e-3
    is_quick && edge=150 thr=0.05 refs=16 reft=0.01
    local cb=$root/scenes/cornell-box.mid
    cmd "$TB" render "$cb" --method radiosity --max-edge "$edge" --samples "$refs" --threshold "$reft" --threads 2 \
        --patches "$work/ref.csv"
    table methods "Radiosity: spectral Cornell box, --max-edge $edge, to $thr unshot; error against a $refs-sample reference" \
        "form factors" threads "shots (N)" "solver s" "process wall s" "CPU s" "NRMSE (ambient)" "NRMSE (no ambient)"
    local entry label t a
    for entry in "ray cast, 4 samples|2|--formfactor raycast --samples 4" \
                 "ray cast, 4 samples|1|--formfactor raycast --samples 4" \
                 "ray cast, 16 samples|2|--formfactor raycast --samples 16" \
                 "hemicube 64|2|--formfactor hemicube --hemicube-res 64" \
                 "hemicube 128|2|--formfactor hemicube --hemicube-res 128" \
                 "hemicube 256|2|--formfactor hemicube --hemicube-res 256"; do
        IFS='|' read -r label t a <<<"$entry"
        # shellcheck disable=SC2086 # a holds options
        timed "$work/rad.time" "$TB" render "$cb" --method radiosity --max-edge "$edge" $a --threshold "$thr" \
            --threads "$t" --patches "$work/rad.csv" --report "$work/rad-report.csv" --reference "$work/ref.csv" \
            --stats "$work/rad.json"
        python3 - "$label" "$t" "$work/rad.json" "$work/rad.time" "$work/rad-report.csv" <<'EOF' | rows
import csv, json, sys
label, t, js, tm, rep = sys.argv[1:]
d = json.load(open(js))
w, u, s, _ = open(tm).read().split()
last = list(csv.DictReader(open(rep)))[-1]
print(f"{label}\t{t}\t{d['shots']} ({d['shots_per_element']:.2f})\t{d['seconds']:.2f}\t{float(w):.2f}\t"
      f"{float(u) + float(s):.2f}\t{100 * float(last['nrmse_ambient']):.2f}%\t{100 * float(last['nrmse']):.2f}%")
EOF
    done

    local pb
    pb=$(helper radiosity_patches_bench radiosity)
    if is_quick; then
        cmd env OMP_NUM_THREADS=2 "$pb" "$root/scenes/cornell-box-rgb.mid" 150 4 0.05 0 300
    else
        cmd env OMP_NUM_THREADS=2 "$pb" "$root/scenes/cornell-box-rgb.mid" 35 4 0.01 0 70 105 140 210
    fi
    table patches "Patches over elements: RGB Cornell box, elements --max-edge $edge, 4 samples, 2 threads" \
        "patch edge" elements patches "one level: shots, s, NRMSE" "two levels: shots (per N), s, NRMSE" \
        "time two / one"
    last_output | awk -F'|' 'NF == 6 && $1 ~ /^ *[0-9.]+ *$/ {
        for (i = 1; i <= 6; i++) gsub(/^ +| +$/, "", $i)
        printf "%s\t%s\t%s\t%s\t%s\t%s\n", $1 == "0" ? "none" : $1, $2, $3, $4, $5, $6 }' | rows

    table default "Default element size (bounding-box diagonal / 24), 16 samples, 0.3% unshot, 2 threads" \
        scene "max edge" elements "shots (N)" "solver s" "process wall s"
    local s extra=()
    is_quick && extra=(--max-shots 20)
    for s in cornell-box cornell-box-rgb showcase radiosity-room; do
        timed "$work/rad.time" "$TB" render "$(scene "$s")" --method radiosity -o "$work/rad.png" --threads 2 \
            --stats "$work/rad.json" "${extra[@]}"
        local me
        me=$(last_output | sed -n 's/.*elements (max edge \([0-9.e+-]*\).*/\1/p' | head -1)
        python3 - "$s" "$me" "$work/rad.json" "$work/rad.time" <<'EOF' | rows
import json, sys
s, me, js, tm = sys.argv[1:]
d = json.load(open(js))
w = open(tm).read().split()[0]
print(f"{s}\t{me}\t{d['elements']}\t{d['shots']} ({d['shots_per_element']:.2f})\t{d['seconds']:.2f}\t{float(w):.2f}")
EOF
    done
}

bench_ff-cpu() {
    local ff
    ff=$(helper ff_table formfactor)
    cmd env OMP_NUM_THREADS=1 "$ff" timing
    table timing "CPU form factors, one thread (ff_table timing; unit cube of 6 x 16 x 16 quads, 4096 receivers)" \
        "ff_table output"
    # ff_table prints its own markdown tables: they replace this placeholder table.
    { echo "<!-- run-all.sh table: $bench/timing -->"; last_output; } >"$cur_table"
}

bench_adaptive() {
    need_gnu_time
    local rb n=300 rounds=3 edge=100
    is_quick && n=60 rounds=2 edge=200
    rb=$(helper refine_bench mesh)
    cmd "$rb" "$n" "$rounds" 0.1
    table refine "Refinement: $n x $n quad grid, 10 % of the elements marked per round (CPU s, one core)" \
        round elements "red splits (graded, closure)" "green elements" seconds
    last_output | awk '
        /^create:/ { e = $2; s = $4; printf "create\t%s\t\t\t%s\n", e, s }
        /^round / { r = $2; sub(/:/, "", r); line = $0
            a = $3; b = $5; m = $0
            match(m, /[0-9]+ red splits: [0-9]+ graded, [0-9]+ closure; [0-9]+ green/)
            split(substr(m, RSTART, RLENGTH), p, /[ :;,]+/)
            t = $NF; sub(/s$/, "", t); if (t == "") t = $(NF - 1)
            printf "%s\t%s -> %s\t%s (%s, %s)\t%s\t%s\n", r, a, b, p[1], p[4], p[6], p[8], t }' | rows
    table radiosity "Radiosity with --adapt: RGB Cornell box, --max-edge $edge, 4 samples, 2 threads" \
        run "elements at the end" "shots in all" "adaptive rounds" "process wall s"
    local label extra
    for label in "without --adapt" "--adapt 0.1 --adapt-levels 2"; do
        extra=()
        [[ $label == --adapt* ]] && extra=(--adapt 0.1 --adapt-levels 2)
        timed "$work/ad.time" "$TB" render "$root/scenes/cornell-box-rgb.mid" --method radiosity --max-edge "$edge" \
            --samples 4 --threads 2 --patches "$work/ad.csv" --stats "$work/ad.json" "${extra[@]}"
        python3 - "$label" "$work/ad.json" "$work/ad.time" <<'EOF' | rows
import json, sys
label, js, tm = sys.argv[1:]
d = json.load(open(js))
print(f"{label}\t{d['elements']}\t{d['counters']['Radiosity/shots']}\t{d['adapt_rounds']}\t"
      f"{float(open(tm).read().split()[0]):.2f}")
EOF
    done
}

bench_dist() {
    need mpirun "Open MPI: tools/setup.sh"
    local q=()
    is_quick && q=(--quick)
    table scaling "Distributed: 1 rank x 1 thread vs 2 ranks x 1 thread (fastest of 3 runs, 1 with --quick; CPU = every process of the job)" \
        case "1 rank: wall / CPU s" "2 ranks: wall / CPU s" "speedup (wall)" "CPU cost of 2 ranks" "load before/after"
    cmd env TESTBED="$TB" "$root/tools/bench/dist-scaling.sh" "${q[@]}"
    last_output | awk -F' *[|] *' '/^[|] [a-z]+(-[a-z]+)+ [|] [0-9.]+ \// { printf "%s\t%s\t%s\t%s\t%s\t%s\n", $2, $3, $4, $5, $6, $7 }' | rows
}

bench_methods-error() {
    need_gnu_time
    need gnuplot "the plots of tools/bench/methods-error.sh"
    local q=()
    is_quick && q=(--quick)
    # the reference is cached in build/methods-error-cache (rendered once: minutes)
    cmd env TESTBED="$TB" bash "$root/tools/bench/methods-error.sh" "${q[@]}" --out "$work/methods-error"
    table renders "Speed versus error: every render against the converged path-traced reference (CPU s: user + system)" \
        scene method mode budget "wall s" "CPU s" relMSE RMSE
    python3 - "$work/methods-error/methods-error.csv" <<'PY' | rows
import csv, sys
for r in csv.DictReader(open(sys.argv[1])):
    print("\t".join([r["scene"], r["method"], r["mode"], r["budget"], r["seconds"], r["cpu_seconds"],
                     f"{float(r['relMSE']):.4g}", f"{float(r['RMSE']):.4g}"]))
PY
    table equal "Speed versus error: relMSE of the Whitted and the path tracer at each hybrid render's CPU time, over the hybrid's" \
        scene "hybrid mode" budget "CPU s" "hybrid relMSE" "Whitted relMSE" "Whitted / hybrid" "path relMSE" "path / hybrid"
    last_output | awk -F' [|] ' '/^[|] / && NF == 9 && $4 ~ /^[0-9.]+$/ { sub(/^[|] /, "", $1); sub(/ [|]$/, "", $9)
        printf "%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n", $1, $2, $3, $4, $5, $6, $7, $8, $9 }' | rows
}

# ------------------------------------------------------------------ header
version_of() { "$@" 2>&1 | head -n 1 || true; }
machine_facts() {
    local cpu cores tpc mem embree pov hf build vk gitd
    cpu=$(grep -m1 '^model name' /proc/cpuinfo | sed 's/.*: //')
    cores=$(nproc)
    tpc=$(lscpu 2>/dev/null | sed -n 's/^Thread(s) per core: *//p')
    mem=$(awk '/^MemTotal/ { printf "%.1f GiB", $2 / 1048576 }' /proc/meminfo)
    embree=$(dpkg-query -W -f '${Version}' libembree3-3 2>/dev/null || pkg-config --modversion embree3 2>/dev/null || echo "not found")
    pov=$(povray --version 2>&1 | grep -m1 '^POV-Ray' || echo "not found")
    hf=$(hyperfine --version 2>/dev/null || echo "not found")
    build=$(sed -n 's/^CMAKE_BUILD_TYPE:STRING=//p' "$tbdir/CMakeCache.txt" 2>/dev/null || true)
    vk=$("$TB" devices 2>/dev/null | sed -n 's/^\* [0-9]*  *//p' | head -n 1 || true)
    gitd=$(git -C "$root" describe --always --dirty 2>/dev/null || echo "not a git checkout")
    printf 'CPU\t%s\n' "$cpu"
    printf 'cores\t%s (threads per core: %s)\n' "$cores" "${tpc:-?}"
    printf 'memory\t%s\n' "$mem"
    printf 'OS\t%s, %s\n' "$(. /etc/os-release 2>/dev/null && echo "$PRETTY_NAME")" "$(uname -sr)"
    printf 'compiler\t%s\n' "$(version_of "${CC:-cc}" --version)"
    printf 'testbed\t%s, %s build, git %s\n' "$(version_of "$TB" --version)" "${build:-unknown}" "$gitd"
    printf 'Vulkan device\t%s\n' "${vk:-none}"
    printf 'Embree\t%s\n' "$embree"
    printf 'POV-Ray\t%s\n' "$pov"
    printf 'hyperfine\t%s\n' "$hf"
}

echo "run-all: $(date -u '+%Y-%m-%d %H:%M UTC')$(is_quick && echo ', --quick: tiny sizes, figures mean nothing')"
machine_facts >"$work/machine.tsv"
awk -F'\t' '{ printf "  %-14s %s\n", $1 ":", $2 }' "$work/machine.tsv"
echo "  load average   $(loadavg) ($(uptime | sed 's/.*up /up /; s/,  *[0-9]* users*//; s/,  *load average.*//'))"
echo "  benchmarks     ${selected[*]}"

warn_not_idle() {
    local msg bar='!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!'
    msg=$(printf '%s\n' "$bar" "!!! WARNING: machine not idle: figures not valid" \
        "!!! (other processes used $1 % of the CPU before '$bench'; at most $idle_max % is idle)" "$bar")
    # Both streams, written separately: `tee /dev/stderr` reopens a shared
    # log file and truncates it.
    printf '%s\n' "$msg"
    printf '%s\n' "$msg" >&2
}

# ------------------------------------------------------------------ run
failed=()
total_start=$SECONDS
for bench in "${selected[@]}"; do
    for b in "${benchmarks[@]}"; do [[ "${b%%|*}" == "$bench" ]] && what=${b#*|}; done
    echo
    echo "=== $bench: $what"
    log=$work/$bench.log
    : >"$log"
    busy=$(busy_percent)
    before=$(loadavg)
    echo "load average before: $before"
    echo "CPU used by other processes before: $busy %"
    idle=1
    if awk -v b="$busy" -v m="$idle_max" 'BEGIN { exit !(b > m) }'; then
        idle=0
        warn_not_idle "$busy"
    fi
    start=$SECONDS
    ntab_before=$(wc -l <"$work/tables.list")
    set +e
    ( set -euo pipefail; "bench_$bench" )
    rc=$?
    set -e
    after=$(loadavg)
    echo "load average after:  $after"
    if (( idle )); then state=yes; else state="**no: figures not valid**"; fi
    printf '%s\t%s\t%s\t%s\t%s\n' "$bench" "$busy %" "$before" "$after" "$state" >>"$work/loads.tsv"
    tail -n +"$((ntab_before + 1))" "$work/tables.list" | while read -r t; do
        echo
        cat "$t"
    done
    (( idle )) || echo "(other processes used $busy % of the CPU at the start: machine not idle, figures not valid)"
    if (( rc == 0 )); then
        echo "status: $bench ok ($((SECONDS - start)) s)"
    else
        echo "status: $bench FAILED ($((SECONDS - start)) s; see the messages above)"
        failed+=("$bench")
    fi
done

if [[ -n "$out" ]]; then
    {
        echo "<!-- tools/bench/run-all.sh$(is_quick && echo ' --quick') output, $(date -u '+%Y-%m-%d %H:%M UTC') -->"
        echo "<!-- run-all.sh table: machine -->"
        echo "| | |"
        echo "| --- | --- |"
        awk -F'\t' '{ printf "| %s | %s |\n", $1, $2 }' "$work/machine.tsv"
        echo
        echo "<!-- run-all.sh table: load -->"
        echo "| benchmark | CPU used by others (2 s before) | load average before | load average after | idle (others <= $idle_max %) |"
        echo "| --- | --- | --- | --- | --- |"
        awk -F'\t' '{ printf "| %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5 }' "$work/loads.tsv"
        while read -r t; do echo; cat "$t"; done <"$work/tables.list"
    } >"$out"
    echo
    echo "run-all: tables written to $out"
fi

echo
echo "run-all: $(( ${#selected[@]} - ${#failed[@]} )) of ${#selected[@]} benchmarks ran in $((SECONDS - total_start)) s"
if (( ${#failed[@]} )); then
    echo "run-all: FAILED: ${failed[*]}" >&2
    exit 1
fi
