#!/usr/bin/env bash
# MID streaming benchmark (docs/performance.md, "MID reader"): for each size,
# streams a procedural scene from `testbed generate` into a file of at least
# SIZE_GB gigabytes (10^9 bytes) in a temporary folder, reads it back with
# `testbed check`, and prints throughput and peak resident memory of both
# programs; the file is deleted afterwards. Not part of the test suite.
#
#   tools/bench/mid-throughput.sh [SIZE_GB ...]        (default: 2)
#   tools/bench/mid-throughput.sh 0.2 1 2              (shows that memory stays flat)
#
# Environment:
#   TESTBED  the testbed binary (default: configure and build build/bench with
#            the project's default build type, RelWithDebInfo)
#   KIND     generator kind: mesh (default; number-heavy polygon meshes),
#            grid or csg (many small objects)
#   SEED     generator seed (default 1)
#   REPEAT   read each file this many times and report the fastest read and
#            the largest peak RSS (default 1; more steadies a shared machine)
#   TMPDIR   where the files go (default /tmp); needs twice the size free
#
# Goals (issue 3): reading >= 100 MB/s, peak RSS flat and <= 64 MiB.
# Peak RSS comes from GNU time (/usr/bin/time, Debian package `time`): the
# maximum resident set size of the process. The file was just written, so it
# is normally in the page cache: the rate is the parser's, not the disk's.
# Both programs are single-threaded; besides wall-clock rates the table gives
# the read rate per CPU second (user + system), which other work on a shared
# machine disturbs less.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
kind=${KIND:-mesh}
seed=${SEED:-1}
repeat=${REPEAT:-1}
sizes=("$@")
[[ ${#sizes[@]} -gt 0 ]] || sizes=(2)

if [[ ! -x /usr/bin/time ]]; then
    echo "mid-throughput: /usr/bin/time not found (apt-get install time)" >&2
    exit 2
fi
if [[ -z "${TESTBED:-}" ]]; then
    cmake -S "$root" -B "$root/build/bench" -DTB_TESTS=OFF >/dev/null
    cmake --build "$root/build/bench" --target testbed -j2 >/dev/null
    TESTBED="$root/build/bench/testbed"
fi

work=$(mktemp -d "${TMPDIR:-/tmp}/mid-throughput.XXXXXX")
trap 'rm -rf "$work"' EXIT

# Bytes per object, from a sample of 400 objects (the preamble is < 2 KB).
"$TESTBED" generate "$kind" --count 400 --seed "$seed" -o "$work/sample.mid"
bpo=$(( $(stat -c %s "$work/sample.mid") / 400 ))
rm -f "$work/sample.mid"

# timed OUT CMD...: runs CMD under GNU time; OUT gets "wall_s max_rss_kb user_s sys_s".
timed() {
    local out=$1
    shift
    /usr/bin/time -o "$out" -f "%e %M %U %S" "$@"
}

echo "testbed: $TESTBED ($("$TESTBED" version))"
echo "kind: $kind, seed $seed, about $bpo bytes per object; folder $work"
echo "command: testbed generate $kind --count N --seed $seed -o FILE; testbed check FILE (best of $repeat)"
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
echo
fmt="%-6s %8s %14s %10s %8s %10s %9s %8s %10s %14s %9s\n"
printf "$fmt" kind size_GB bytes objects gen_s gen_MB/s gen_MiB read_s read_MB/s read_MB/cpu_s read_MiB
for size in "${sizes[@]}"; do
    target=$(awk -v s="$size" 'BEGIN { printf "%.0f", s * 1e9 }')
    need=$(( target / 1024 * 2 ))
    free=$(df -Pk "$work" | awk 'NR == 2 { print $4 }')
    if (( free < need )); then
        echo "mid-throughput: $size GB needs $((need / 1048576)) GiB free in $work, only $((free / 1048576)) GiB" >&2
        exit 1
    fi
    count=$(( target / bpo * 102 / 100 + 1 ))
    file="$work/scene.mid"
    for attempt in 1 2 3; do
        timed "$work/gen.time" "$TESTBED" generate "$kind" --count "$count" --seed "$seed" -o "$file"
        bytes=$(stat -c %s "$file")
        (( bytes >= target )) && break
        count=$(( count * 105 / 100 + 1 ))
    done
    (( bytes >= target )) || { echo "mid-throughput: could not reach $size GB" >&2; exit 1; }
    rs="" rk=0 rc=""
    for ((r = 0; r < repeat; r++)); do
        timed "$work/read.time" "$TESTBED" check "$file" >"$work/summary"
        grep -q "^objects: $count top-level" "$work/summary" || { echo "mid-throughput: check summary:"; cat "$work/summary"; exit 1; } >&2
        read -r s k u y <"$work/read.time"
        c=$(awk -v u="$u" -v y="$y" 'BEGIN { printf "%.2f", u + y }')
        if [[ -z "$rs" ]] || awk -v a="$s" -v b="$rs" 'BEGIN { exit !(a < b) }'; then rs=$s; fi
        if [[ -z "$rc" ]] || awk -v a="$c" -v b="$rc" 'BEGIN { exit !(a < b) }'; then rc=$c; fi
        (( k > rk )) && rk=$k
    done
    read -r gs gk _ _ <"$work/gen.time"
    awk -v k="$kind" -v sz="$size" -v b="$bytes" -v n="$count" -v gs="$gs" -v gk="$gk" -v rs="$rs" -v rk="$rk" \
        -v rc="$rc" -v f="$fmt" \
        'BEGIN { printf f, k, sz, b, n, gs, sprintf("%.1f", b / 1e6 / gs), sprintf("%.1f", gk / 1024),
                 rs, sprintf("%.1f", b / 1e6 / rs), sprintf("%.1f", b / 1e6 / rc), sprintf("%.1f", rk / 1024) }'
    rm -f "$file"
done
