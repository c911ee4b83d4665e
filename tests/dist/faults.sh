#!/bin/sh
# Faults of a distributed job that no rank may survive alone
# (docs/distributed.md, "Faults"), with real mpirun ranks: every case must
# end (a guard kills a job that hangs) with a non-zero status, a message that
# names the rank, and no output file.
# - rank 0 fails while taking in the others' tiles (TB_FAULT=tile-merge,
#   2 and 3 ranks): the pass drains and every rank stops with its message;
# - one rank runs out of memory caching form factors, with several shooters
#   in flight and in the deterministic mode (TB_FAULT=rad-cache): its cache
#   would no longer match the others', so it stops the job;
# - rank 1 killed mid-radiosity: the job stops naming rank 1 and the last
#   checkpoint, which is intact, and --resume over 3 ranks finishes with
#   the patches of one uninterrupted process.
# TB_FAULT is honoured by builds with the test suite (util/base/fault.h).
#   faults.sh  (with TESTBED, TB_SOURCE_DIR, TB_TEST_TMPDIR set)
set -u
. "$(dirname "$0")/mpirun.sh"
test_dir dist_faults

# guarded NAME CMD...: runs CMD, stopped after 120 s (a hang: status 124);
# output in $T/NAME.out; returns (and sets rc to) CMD's status
guarded() {
    name=$1; shift
    timeout 120 "$@" > "$T/$name.out" 2>&1
    rc=$?
    return $rc
}

# rank 0 fails merging the 5th tile it receives
for np in 2 3; do
    guarded merge$np $MPIRUN -np $np -x TB_FAULT=tile-merge@0:5 "$TESTBED" render "$T/box.mid" --spp 1 --passes 3 \
        --threads 1 -o "$T/m.pfm" && { cat "$T/merge$np.out"; fail "$np ranks: a failed merge on rank 0 went unnoticed"; }
    [ $rc != 124 ] && [ $rc -lt 128 ] || { cat "$T/merge$np.out"; fail "$np ranks: the job hung after rank 0's merge failed (status $rc)"; }
    grep -q "rank 0: merging a tile from rank [1-9]: out of memory unpacking a tile" "$T/merge$np.out" ||
        { cat "$T/merge$np.out"; fail "$np ranks: no message for rank 0's failed merge"; }
    [ ! -e "$T/m.pfm" ] || fail "$np ranks: an image was written after rank 0 failed"
done

# rank 1 (several shooters) or rank 0 (deterministic) cannot cache a
# shooter's form factors after 20 have been cached
Q="$TB_SOURCE_DIR/scenes/cornell-box.mid --method radiosity --max-edge 120 --threshold 0.01 --threads 1"
for run in "1:--several-shooters" "0:"; do
    r=${run%%:*} flag=${run#*:}
    guarded cache$r $MPIRUN -np 2 -x TB_FAULT=rad-cache@$r:20 "$TESTBED" render $Q $flag --patches "$T/c.csv" &&
        { cat "$T/cache$r.out"; fail "rank $r's failed cache allocation went unnoticed ($flag)"; }
    [ $rc != 124 ] && [ $rc -lt 128 ] || { cat "$T/cache$r.out"; fail "the job hung after rank $r's cache allocation failed ($flag)"; }
    grep -q "rank $r of 2: radiosity: out of memory caching the form factors of shooter [0-9]*.*stopping every rank" \
        "$T/cache$r.out" || { cat "$T/cache$r.out"; fail "no message naming rank $r ($flag)"; }
    [ ! -e "$T/c.csv" ] || fail "patches written after rank $r failed ($flag)"
done

# rank 1 killed mid-radiosity, once a checkpoint is there; resumed on 3 ranks
R="$TB_SOURCE_DIR/scenes/cornell-box.mid --method radiosity --max-edge 60 --threshold 0.0005"
TB_DIST_JOB=$$ $MPIRUN -np 2 "$TESTBED" render $R --threads 1 --patches "$T/k.csv" --checkpoint "$T/r.ckpt" \
    --checkpoint-every 0.2 > "$T/kout" 2>&1 &
kill_rank1 $! "$T/r.ckpt" "$T/kout" shots
shots=$killed_at
[ ! -e "$T/k.csv" ] || fail "patches written by the killed job"
guarded resume $MPIRUN -np 3 "$TESTBED" render $R --threads 1 --patches "$T/k.csv" --resume "$T/r.ckpt" ||
    { cat "$T/resume.out"; fail "radiosity resume over 3 ranks after the kill"; }
"$TESTBED" render $R --patches "$T/k1.csv" > "$T/out" 2>&1 || { cat "$T/out"; fail "one-process radiosity"; }
cmp "$T/k1.csv" "$T/k.csv" || fail "killed and resumed radiosity differs from one uninterrupted process"

rm -rf "$T"
echo "dist faults: ok (radiosity killed after $shots shots)"
