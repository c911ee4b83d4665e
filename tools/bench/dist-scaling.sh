#!/usr/bin/env bash
# Scaling of `mpirun -np N testbed render` on this machine (docs/distributed.md,
# docs/performance.md "Distributed"): 1 rank x 1 thread against 2 ranks x 1
# thread for the ray tracer, the path tracer and radiosity on the Cornell
# boxes and on a larger generated scene (and the fixed start-up price of a
# job, as a render of 16 x 16 pixels), the per-rank work, wait and bytes
# from the stats, the figures the scaling model needs (compute and bytes per
# tile and per shot), and what reading the MID file costs against parsing it
# (every rank reads the scene itself; the alternative is rank 0 broadcasting
# the bytes), and radiosity with several shooters in flight against the
# deterministic mode (time, and the difference of the results). Also what
# the machine allows at all (two independent one-thread renders side by
# side against one alone: no 2-rank job can beat that ratio) and what MPI's
# start costs with Open MPI's default components against loopback-only ones.
#
#   tools/bench/dist-scaling.sh [--quick] [--reps N]
#
# Environment: TESTBED (default build/ci/testbed), MPIRUN (default: mpirun
# on loopback shared memory with the ob1 and sm/pt2pt components, allowed as
# root; docs/distributed.md "Running on one machine"). Prints the load average
# before and after every case: figures taken at a load above the core count
# are not a measure of scaling (the ranks wait for cores, not for each other).
# Exit status: 0 done, 1 a run failed, 2 usage error.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
quick=0 reps=3
while [[ $# -gt 0 ]]; do
    case $1 in
        --quick) quick=1 reps=1 ;;
        --reps) [[ $# -ge 2 ]] || { echo "dist-scaling: --reps needs N" >&2; exit 2; }; reps=$2; shift ;;
        -h|--help) sed -n '2,22p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *) echo "dist-scaling: unknown option '$1' (see --help)" >&2; exit 2 ;;
    esac
    shift
done
TB=${TESTBED:-$root/build/ci/testbed}
[[ -x $TB ]] || { echo "dist-scaling: no testbed at $TB (set TESTBED)" >&2; exit 2; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_WAIT_POLICY=passive
MPIRUN_BASE="mpirun --oversubscribe --bind-to none"
LOOPBACK="--mca btl self,vader --mca pml ob1 --mca osc sm,pt2pt"
MPIRUN=${MPIRUN:-$MPIRUN_BASE $LOOPBACK}
work=$(mktemp -d "${TMPDIR:-/tmp}/dist-scaling.XXXXXX")
trap 'rm -rf "$work"' EXIT

load() { cut -d' ' -f1 /proc/loadavg; }
now() { date +%s.%N; }

# scenes: the boxes as shipped (quick: shrunk), and a generated grid
box=$root/scenes/cornell-box.mid spheres=$root/scenes/cornell-box-spheres.mid room=$root/scenes/radiosity-room.mid
count=3000 room_thr=0.01 spp=8
if ((quick)); then
    sed 's/resolution = \[512 512\]/resolution = [96 96]/' "$box" > "$work/box.mid"
    sed 's/resolution = \[512 512\]/resolution = [96 96]/' "$spheres" > "$work/spheres.mid"
    box=$work/box.mid spheres=$work/spheres.mid count=200 room_thr=0.3 spp=2
fi
"$TB" generate grid --count $count --seed 1 -o "$work/grid.mid"

# timed CMD...: runs CMD, prints "WALL CPU" (seconds; CPU = user + system of
# every process it started, mpirun and the ranks included)
timed() {
    python3 - "$@" <<'PY'
import resource, subprocess, sys, time
t0 = time.monotonic()
with open(sys.argv[1], 'w') as log:
    rc = subprocess.call(sys.argv[2:], stdout=log, stderr=subprocess.STDOUT)
wall = time.monotonic() - t0
ru = resource.getrusage(resource.RUSAGE_CHILDREN)
print('%.3f %.3f' % (wall, ru.ru_utime + ru.ru_stime))
sys.exit(rc)
PY
}

# the machine's ceiling: one 1-thread render alone against two of them side
# by side (the same work twice, no MPI): 2 x alone / together is the most
# any 2 x 1 job can gain here (cores that slow each other down, or a host
# that gives the second vCPU less, show here, not in the code)
ceiling() {
    local a=999999 b=999999 w c r
    for ((r = 0; r < reps; r++)); do
        read -r w c < <(timed "$work/o" "$TB" render "$@" --threads 1 --backend cpu -o "$work/c1.pfm") ||
            { failed=1; return; }
        if awk -v x="$w" -v y="$a" 'BEGIN { exit !(x < y) }'; then a=$w; fi
        # shellcheck disable=SC2016
        read -r w c < <(timed "$work/o" bash -c 'o=$1; shift; "$@" -o "$o/c2.pfm" & "$@" -o "$o/c3.pfm"; wait' _ \
            "$work" "$TB" render "$@" --threads 1 --backend cpu) || { failed=1; return; }
        if awk -v x="$w" -v y="$b" 'BEGIN { exit !(x < y) }'; then b=$w; fi
    done
    printf 'ceiling (%s): one 1-thread render alone %.2f s, two side by side %.2f s: at most %.2fx for 2 ranks x 1 thread (load %s)\n' \
        "$1" "$a" "$b" "$(awk -v x="$a" -v y="$b" 'BEGIN { print 2 * x / y }')" "$(load)"
}

# MPI's start with Open MPI's default components, loopback transports only,
# and loopback with the ob1 and sm/pt2pt components (no UCX or libfabric
# probing): wall time of a job of 16 x 16 pixels and each rank's MPI_Init
# (--stats rank<R>_init_seconds), best of `reps`
startup_flags() {
    printf '| mpirun flags | job wall (s) | MPI start, rank 0 / rank 1 (s) | load |\n|---|---|---|---|\n'
    local label flags r w c best i0 i1
    for label in "(Open MPI's defaults)" "--mca btl self,vader" "$LOOPBACK"; do
        flags=$label; [[ $label == "(Open MPI's defaults)" ]] && flags=
        best=999999 i0='' i1=''
        for ((r = 0; r < reps + 2; r++)); do
            # shellcheck disable=SC2086
            read -r w c < <(timed "$work/o" $MPIRUN_BASE $flags -np 2 "$TB" render "$work/tiny.mid" --spp 1 --threads 1 \
                -o "$work/t.pfm" --stats "$work/startup.stats") || { cat "$work/o"; failed=1; return; }
            if awk -v x="$w" -v y="$best" 'BEGIN { exit !(x < y) }'; then
                best=$w
                read -r i0 i1 < <(python3 -c 'import json, sys; j = json.load(open(sys.argv[1]))
print("%.3f %.3f" % (j["rank0_init_seconds"], j["rank1_init_seconds"]))' "$work/startup.stats")
            fi
        done
        # shellcheck disable=SC2016
        printf '| `%s` | %.2f | %s / %s | %s |\n' "$label" "$best" "$i0" "$i1" "$(load)"
    done
}

# case NAME ARGS...: the fastest of `reps` runs of 1 rank and of 2 ranks (1
# thread each): wall seconds and CPU seconds; then one more 2-rank run with
# --stats for the per-rank figures (not timed: --stats turns rank 0's
# counters on, a few per cent, which the timed runs on both sides leave
# off). Both sides render on the CPU (--backend cpu: one process would
# otherwise also probe the Vulkan device, which a job of several ranks
# never does). Under load the wall times measure the scheduler, not the
# code: the CPU seconds still show what distributing costs (2 ranks' CPU
# over 1 rank's).
failed=0
case_() {
    local name=$1; shift
    local l0 w1=999999 c1=0 w2=999999 c2=0 r w c
    l0=$(load)
    for ((r = 0; r < reps; r++)); do
        read -r w c < <(timed "$work/out1" "$TB" render "$@" --threads 1 --backend cpu) ||
            { cat "$work/out1"; failed=1; return; }
        if awk -v a="$w" -v b="$w1" 'BEGIN { exit !(a < b) }'; then w1=$w c1=$c; fi
        # shellcheck disable=SC2086
        read -r w c < <(timed "$work/out2" $MPIRUN -np 2 "$TB" render "$@" --threads 1 --backend cpu) ||
            { cat "$work/out2"; failed=1; return; }
        if awk -v a="$w" -v b="$w2" 'BEGIN { exit !(a < b) }'; then w2=$w c2=$c; fi
    done
    # shellcheck disable=SC2086
    $MPIRUN -np 2 "$TB" render "$@" --threads 1 --backend cpu --stats "$work/$name.json" > "$work/out3" 2>&1 ||
        { cat "$work/out3"; failed=1; return; }
    printf '| %s | %.2f / %.2f | %.2f / %.2f | %.2fx | %.2fx | %s / %s |\n' "$name" "$w1" "$c1" "$w2" "$c2" \
        "$(awk -v a="$w1" -v b="$w2" 'BEGIN { print a / b }')" "$(awk -v a="$c2" -v b="$c1" 'BEGIN { print a / b }')" \
        "$l0" "$(load)"
}
# the fixed price of a job (launch, MPI start, scene load, output): a
# render of 16 x 16 pixels; the speed-ups below include it once
sed 's/resolution = \[[0-9]* [0-9]*\]/resolution = [16 16]/' "$box" > "$work/tiny.mid"
startup_flags
echo
ceiling "$box" --spp $spp
echo
printf '| case | 1 rank x 1 thread: wall / CPU (s) | 2 ranks x 1 thread: wall / CPU (s) | speedup (wall) | CPU cost of 2 ranks | load before/after |\n'
printf '|---|---|---|---|---|---|\n'
case_ start-up "$work/tiny.mid" --spp 1 -o "$work/t.pfm"
case_ raytrace-box "$box" --spp $spp --passes 2 -o "$work/a.pfm"
case_ path-spheres "$spheres" --method path --spp $spp -o "$work/b.pfm"
case_ radiosity-box "$box" --method radiosity --patches "$work/c.csv"
# the same with no yielding poll: each exchange sleeps at once (what the
# default 1 ms of yielding polls saves; docs/distributed.md, TB_DIST_SPIN_US)
TB_DIST_SPIN_US=0 case_ radiosity-box-sleep "$box" --method radiosity --patches "$work/c.csv"
case_ raytrace-grid "$work/grid.mid" --spp $spp -o "$work/d.pfm"
case_ path-grid "$work/grid.mid" --method path --spp $spp -o "$work/e.pfm"
# the generated grid's palette has a reflectance of 1 (no radiosity): the
# bundled room of 5167 elements is the larger radiosity scene
case_ radiosity-room "$room" --method radiosity --threshold $room_thr --patches "$work/f.csv"

# the model's inputs, from the 2-rank stats of each case
echo
printf '| case | rank | units | work (s) | wait (s) | MPI start (s) | CPU (s) | bytes sent | compute per unit (ms) | bytes per unit |\n'
printf '|---|---|---|---|---|---|---|---|---|---|\n'
for j in "$work"/*.json; do
    python3 - "$j" <<'PY'
import json, os, sys
j = json.load(open(sys.argv[1])); name = os.path.basename(sys.argv[1])[:-5]
for r in range(int(j.get('ranks', 1))):
    u = next(v for k, v in j.items() if k.startswith('rank%d_' % r) and k.split('_', 1)[1] in ('tiles', 'receivers'))
    w = j['rank%d_work_seconds' % r]; b = j['rank%d_bytes_sent' % r]
    print('| %s | %d | %d | %.3f | %.3f | %.3f | %.3f | %d | %.4f | %.1f |' % (name, r, u, w,
          j['rank%d_wait_seconds' % r], j.get('rank%d_init_seconds' % r, 0), j.get('rank%d_cpu_seconds' % r, 0), b,
          1e3 * w / u if u else 0, b / u if u else 0))
t = j.get('timers', {})
ff = t.get('Radiosity/form factor time'); up = t.get('Radiosity/update time')
if ff and ff['calls']:
    print('| %s | form factors | %d computed shots | %.3f s (%.3f ms/shot) | update %.3f s in %d shots | | | | | |' % (
          name, ff['calls'], ff['seconds'], 1e3 * ff['seconds'] / ff['calls'], up['seconds'], up['calls']))
PY
done

# radiosity with several shooters in flight against the deterministic mode:
# time, shots, and the difference of the patches from the deterministic
# solve and from a converged one (unshot 1e-4, one process)
echo
printf '| radiosity, Cornell box | wall / CPU (s) | shots | difference from 1 process | from the converged solve |\n'
printf '|---|---|---|---|---|\n'
Q=("$box" --method radiosity)
timed "$work/o" "$TB" render "${Q[@]}" --threshold 0.0001 --patches "$work/ref.csv" > /dev/null || failed=1
for run in "1 process:1:" "2 ranks:2:" "2 ranks, --several-shooters:2:--several-shooters" \
           "3 ranks, --several-shooters:3:--several-shooters"; do
    IFS=: read -r label n flag <<<"$run"
    if [[ $n == 1 ]]; then
        read -r w c < <(timed "$work/o" "$TB" render "${Q[@]}" --threads 1 --patches "$work/r$n$flag.csv") || failed=1
        cp "$work/r$n$flag.csv" "$work/det.csv"
    else
        # shellcheck disable=SC2086
        read -r w c < <(timed "$work/o" $MPIRUN -np "$n" "$TB" render "${Q[@]}" --threads 1 $flag \
            --patches "$work/r$n$flag.csv") || failed=1
    fi
    shots=$(sed -n 's/.*radiosity, [0-9]* elements, \([0-9]*\) shots.*/\1/p' "$work/o")
    printf '| %s | %.2f / %.2f | %s | %s | %s |\n' "$label" "$w" "$c" "$shots" \
        "$(python3 "$root/tools/bench/rad-diff.py" "$work/det.csv" "$work/r$n$flag.csv")" \
        "$(python3 "$root/tools/bench/rad-diff.py" "$work/ref.csv" "$work/r$n$flag.csv")"
done

# reading the MID file against loading (parsing + building) it
echo
for s in "$box" "$work/grid.mid"; do
    a=$(now); cat "$s" > /dev/null; b=$(now); rd=$(awk -v a="$a" -v b="$b" 'BEGIN { print b - a }')
    "$TB" render "$s" --spp 1 --max-depth 0 --threads 1 -o "$work/x.pfm" --stats "$work/load.json" > /dev/null 2>&1 || failed=1
    python3 - "$work/load.json" "$s" "$rd" <<'PY'
import json, os, sys
j = json.load(open(sys.argv[1])); t = j['timers']['Scene/load']['seconds']
print('scene %s: %d bytes, read %.4f s (page cache), load (parse + build) %.4f s' % (
      os.path.basename(sys.argv[2]), os.path.getsize(sys.argv[2]), float(sys.argv[3]), t))
PY
done
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'); load now $(load)"
exit $failed
