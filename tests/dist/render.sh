#!/bin/sh
# `mpirun -np N testbed render` (docs/distributed.md): the ray tracer's
# image over 2 ranks (1 and 2 threads each) and over 3 oversubscribed
# ranks, several progressive passes, plain and adaptive, a spectral and an
# RGB scene, ranks of different thread counts, and the path tracer's and
# the hybrid renderer's images, are
# byte for byte the one-process image; the stats JSON has per-rank
# figures; a scene with an error stops every rank with its file:line:col
# message and no image; a scene on standard input is refused.
#   render.sh  (with TESTBED, TB_SOURCE_DIR, TB_TEST_TMPDIR set)
set -u
. "$(dirname "$0")/mpirun.sh"
T="${TB_TEST_TMPDIR:-/tmp}/dist_render.$$"
rm -rf "$T" && mkdir -p "$T"
for s in cornell-box cornell-box-rgb; do
    sed 's/resolution = \[512 512\]/resolution = [80 72]/' "$TB_SOURCE_DIR/scenes/$s.mid" > "$T/$s.mid"
    grep -q 'resolution = \[80 72\]' "$T/$s.mid" || fail "could not shrink $s"
done
run1() { "$TESTBED" render "$@" > "$T/out" 2>&1 || { cat "$T/out"; fail "one process: $*"; }; }
runN() { n=$1; shift; $MPIRUN -np "$n" "$TESTBED" render "$@" > "$T/out" 2>&1 || { cat "$T/out"; fail "$n ranks: $*"; }; }

# spectral box: 3 passes of 2 spp; RGB box: adaptive, 2 passes, tent filter
# (its apron crosses tiles, so merge order matters)
A="$T/cornell-box.mid --spp 2 --passes 3 --seed 7"
B="$T/cornell-box-rgb.mid --spp 2 --adaptive --max-spp 8 --passes 2 --filter tent"
run1 $A -o "$T/a1.pfm" --threads 2
run1 $B -o "$T/b1.pfm" --threads 1 --sample-map "$T/m1.pfm"
for n in 2 3; do
    ths="1 2"
    [ $n = 3 ] && ths=1 # 3 ranks of 2 threads on 2 cores: slow, and nothing new
    for th in $ths; do
        runN $n $A -o "$T/a$n.$th.pfm" --threads $th
        cmp "$T/a1.pfm" "$T/a$n.$th.pfm" || fail "spectral box: $n ranks x $th threads differ from one process"
        runN $n $B -o "$T/b$n.$th.pfm" --threads $th --sample-map "$T/m$n.$th.pfm" --stats "$T/s$n.json"
        cmp "$T/b1.pfm" "$T/b$n.$th.pfm" || fail "adaptive RGB box: $n ranks x $th threads differ from one process"
        cmp "$T/m1.pfm" "$T/m$n.$th.pfm" || fail "sample map: $n ranks x $th threads differ from one process"
    done
    grep -q "rank $((n - 1)): [0-9]* tiles, work" "$T/out" || { cat "$T/out"; fail "no per-rank line for $n ranks"; }
    python3 - "$T/s$n.json" "$n" <<'PY' || fail "per-rank stats of $n ranks"
import json, sys
j = json.load(open(sys.argv[1])); n = int(sys.argv[2])
assert j['ranks'] == n, j.get('ranks')
assert 'ranks=%d' % n in j['provenance']['options'], j['provenance']['options']
# 80 x 72 pixels in 16-pixel tiles: 5 x 5 tiles, 2 passes
assert sum(j['rank%d_tiles' % r] for r in range(n)) == 50, [j['rank%d_tiles' % r] for r in range(n)]
for r in range(1, n):
    assert j['rank%d_bytes_sent' % r] > 0 and j['rank%d_work_seconds' % r] >= 0, r
# every rank reports its MPI start (wall time) and its own CPU time (positive,
# and not a clock read as a date)
for r in range(n):
    assert j['rank%d_init_seconds' % r] > 0, r
    assert 0 < j['rank%d_cpu_seconds' % r] < 1e4, r
PY
done

# the hybrid renderer: each rank solves the radiosity pass, the tiles travel
H="$T/cornell-box-rgb.mid --method hybrid --max-edge 100 --spp 2"
run1 $H -o "$T/h1.pfm" --threads 2
runN 2 $H -o "$T/h2.pfm" --threads 1
cmp "$T/h1.pfm" "$T/h2.pfm" || fail "hybrid: 2 ranks differ from one process"

# ranks of different thread counts (mpirun's MPMD form): rank 0's first
# grant (4 threads: up to 16 tiles of 64) overflows the queue of a worker of
# one thread, which grows
sed 's/resolution = \[512 512\]/resolution = [128 128]/' "$TB_SOURCE_DIR/scenes/cornell-box.mid" > "$T/big.mid"
run1 "$T/big.mid" --spp 1 -o "$T/g1.pfm"
$MPIRUN -np 1 "$TESTBED" render "$T/big.mid" --spp 1 -o "$T/g2.pfm" --threads 4 : \
    -np 1 "$TESTBED" render "$T/big.mid" --spp 1 -o "$T/g2.pfm" --threads 1 > "$T/out" 2>&1 ||
    { cat "$T/out"; fail "ranks of 4 and 1 threads"; }
cmp "$T/g1.pfm" "$T/g2.pfm" || fail "ranks of 4 and 1 threads differ from one process"

# the path tracer (docs/pathtrace.md) on the spheres box: mirror and glass paths
sed 's/resolution = \[512 512\]/resolution = [64 48]/' "$TB_SOURCE_DIR/scenes/cornell-box-spheres.mid" > "$T/spheres.mid"
P="$T/spheres.mid --method path --spp 4 --passes 2"
run1 $P -o "$T/pt1.pfm" --threads 2
runN 3 $P -o "$T/pt3.pfm" --threads 1
cmp "$T/pt1.pfm" "$T/pt3.pfm" || fail "path tracer: 3 ranks differ from one process"

# a scene with an error: every rank stops, the message is the file's
printf 'mid 1\ncamera {\n  eye = [0 0 oops]\n}\n' > "$T/bad.mid"
$MPIRUN -np 2 "$TESTBED" render "$T/bad.mid" -o "$T/bad.pfm" > "$T/out" 2>&1 && { cat "$T/out"; fail "bad scene accepted"; }
grep -q "bad.mid:3:[0-9]*: error:" "$T/out" || { cat "$T/out"; fail "no file:line:col error for the bad scene"; }
[ "$(grep -c 'bad.mid:3:' "$T/out")" = 1 ] || { cat "$T/out"; fail "the error should be said once, by rank 0"; }
[ ! -e "$T/bad.pfm" ] || fail "an image was written for the bad scene"
# the scene on standard input reaches rank 0 only: refused, said once
$MPIRUN -np 2 "$TESTBED" render - -o "$T/in.pfm" < "$T/cornell-box-rgb.mid" > "$T/out" 2>&1 &&
    { cat "$T/out"; fail "standard input accepted by 2 ranks"; }
[ "$(grep -c 'under mpirun only rank 0 gets it' "$T/out")" = 1 ] || { cat "$T/out"; fail "no single message for stdin"; }
[ ! -e "$T/in.pfm" ] || fail "an image was written from standard input"

rm -rf "$T"
echo "dist render: ok"
