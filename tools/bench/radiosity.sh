#!/usr/bin/env bash
# Radiosity speed, a new build against a base build (docs/performance.md,
# "Radiosity"): the Cornell benchmark (spectral Cornell box, --max-edge 35,
# 1 642 elements, ray cast with 4 samples, to 1% unshot) and a generated
# scene of 14 736 elements (`testbed generate grid --count 64 --seed 1`,
# default element size, ray cast with 4 samples, to 0.3% unshot), each at
# 1 and 2 threads. The two builds run alternately, REPS times each, and the
# script prints the median wall, user+system CPU and solver seconds of each
# and the ratio new/base of the medians (below 1: the new build is faster),
# with the load average before and after. Runs under load are provisional:
# compare ratios from one run of this script, not seconds across runs. It
# also checks that both builds wrote byte-identical --patches CSVs.
#
#   tools/bench/radiosity.sh BASE_TESTBED NEW_TESTBED [--reps N] [--quick]
#
# --quick: the Cornell benchmark at 2 threads only, once each.
# Exit status: 0 done, 1 a run failed or the CSVs differ, 2 usage error.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
reps=3 quick=0 base='' new=''
while [[ $# -gt 0 ]]; do
    case $1 in
        --reps) [[ $# -ge 2 ]] || { echo "radiosity.sh: --reps needs N" >&2; exit 2; }; reps=$2; shift ;;
        --quick) quick=1 reps=1 ;;
        -h|--help) sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        -*) echo "radiosity.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
        *) if [[ -z $base ]]; then base=$1; elif [[ -z $new ]]; then new=$1; else
               echo "radiosity.sh: too many arguments (see --help)" >&2; exit 2; fi ;;
    esac
    shift
done
[[ -x $base && -x $new ]] || { echo "radiosity.sh: needs BASE_TESTBED and NEW_TESTBED (see --help)" >&2; exit 2; }
[[ $reps =~ ^[1-9][0-9]*$ ]] || { echo "radiosity.sh: --reps must be a positive integer" >&2; exit 2; }
work=$(mktemp -d "${TMPDIR:-/tmp}/radiosity-bench.XXXXXX")
trap 'rm -rf "$work"' EXIT
"$new" generate grid --count 64 --seed 1 -o "$work/grid64.mid"

load() { cut -d' ' -f1-3 /proc/loadavg; }
median() { sort -g | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }

# one run: prints "wall cpu solver" (seconds)
run() {
    local tb=$1 out=$2; shift 2
    /usr/bin/time -f '%e %U %S' -o "$work/time" "$tb" render "$@" --patches "$out.csv" --stats "$out.json" \
        >/dev/null 2>"$work/err" || { cat "$work/err" >&2; return 1; }
    local solver
    solver=$(sed -n 's/^  "seconds": \([0-9.e+-]*\),*$/\1/p' "$out.json")
    awk -v s="$solver" '{printf "%s %.3f %s\n", $1, $2 + $3, s}' "$work/time"
}

status=0
bench() {
    local name=$1 threads=$2; shift 2
    : >"$work/base.t"; : >"$work/new.t"
    local l0 r
    l0=$(load)
    for ((r = 0; r < reps; r++)); do
        run "$base" "$work/base" "$@" --threads "$threads" >>"$work/base.t"
        run "$new" "$work/new" "$@" --threads "$threads" >>"$work/new.t"
    done
    local same=identical
    cmp -s "$work/base.csv" "$work/new.csv" || { same=DIFFERENT; status=1; }
    local b n
    for f in 1 2 3; do
        b[$f]=$(cut -d' ' -f$f "$work/base.t" | median)
        n[$f]=$(cut -d' ' -f$f "$work/new.t" | median)
    done
    awk -v name="$name" -v t="$threads" -v bw="${b[1]}" -v nw="${n[1]}" -v bc="${b[2]}" -v nc="${n[2]}" \
        -v bs="${b[3]}" -v ns="${n[3]}" -v same="$same" -v l0="$l0" -v l1="$(load)" -v reps="$reps" 'BEGIN {
        printf "| %s | %d | %.2f / %.2f (%.3f) | %.2f / %.2f (%.3f) | %.2f / %.2f (%.3f) | %s | %s; %s |\n",
            name, t, bw, nw, nw / bw, bc, nc, nc / bc, bs, ns, ns / bs, same, l0, l1 }'
}

echo "Radiosity, base $base vs new $new, median of $reps runs each (seconds base / new (ratio new/base))"
echo
echo "| scene | threads | process wall s | CPU s (user+sys) | solver s | patches CSV | load before; after |"
echo "| --- | --- | --- | --- | --- | --- | --- |"
cornell=("$root/scenes/cornell-box.mid" --method radiosity --max-edge 35 --formfactor raycast --samples 4 --threshold 0.01)
grid=("$work/grid64.mid" --method radiosity --formfactor raycast --samples 4 --threshold 0.003)
bench "Cornell box, 1642 elements" 2 "${cornell[@]}"
if [[ $quick == 0 ]]; then
    bench "Cornell box, 1642 elements" 1 "${cornell[@]}"
    bench "generated grid 64, 14736 elements" 2 "${grid[@]}"
    bench "generated grid 64, 14736 elements" 1 "${grid[@]}"
fi
exit $status
