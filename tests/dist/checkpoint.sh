#!/bin/sh
# Checkpoints of a progressive render (docs/distributed.md): in one process,
# 2 passes saved then resumed to 5 give the 5-pass image bit for bit, and
# resuming with other options is refused; the path tracer's checkpoint
# resumed over 2 ranks gives its uninterrupted image, the hybrid's too; over 2 ranks, killing rank 1
# mid-render stops the job with a message naming the rank and the last
# checkpoint, which is intact, and `--resume` over 3 ranks finishes with
# the uninterrupted image. Radiosity: stopped and resumed solves write the
# uninterrupted solve's patches (one process and 2 ranks), with adaptive
# subdivision too; wrong jobs and kinds are refused.
#   checkpoint.sh  (with TESTBED, TB_SOURCE_DIR, TB_TEST_TMPDIR set)
set -u
. "$(dirname "$0")/mpirun.sh"
test_dir dist_checkpoint
R="$T/box.mid --spp 1 --seed 3"
tb() { "$TESTBED" render "$@" > "$T/out" 2>&1 || { cat "$T/out"; fail "testbed render $*"; }; }

# one process: 5 passes at once, or 2 saved and 3 more resumed
tb $R --passes 5 -o "$T/full.pfm"
tb $R --passes 2 -o "$T/half.pfm" --checkpoint "$T/c.ckpt"
grep -q "checkpoint $T/c.ckpt: 2 passes" "$T/out" || { cat "$T/out"; fail "no checkpoint line"; }
tb $R --passes 5 -o "$T/res.pfm" --resume "$T/c.ckpt" --threads 1
cmp "$T/full.pfm" "$T/res.pfm" || fail "resumed render differs from the uninterrupted one"
"$TESTBED" render $R --spp 2 --passes 5 -o "$T/x.pfm" --resume "$T/c.ckpt" > "$T/out" 2>&1 &&
    fail "resume with another --spp accepted"
grep -q "c.ckpt: written for another job" "$T/out" || { cat "$T/out"; fail "no message for another job"; }
[ ! -e "$T/x.pfm" ] || fail "an image was written for a refused resume"
"$TESTBED" render $R --passes 5 -o "$T/x.pfm" --resume "$T/box.mid" > "$T/out" 2>&1 && fail "a scene taken as a checkpoint"
grep -q "box.mid: not a testbed checkpoint" "$T/out" || { cat "$T/out"; fail "no message for a non-checkpoint"; }

# the path tracer: 2 passes saved in one process, resumed to 4 over 2 ranks
sed 's/resolution = \[512 512\]/resolution = [48 40]/' "$TB_SOURCE_DIR/scenes/cornell-box-spheres.mid" > "$T/sp.mid"
P="$T/sp.mid --method path --spp 2"
tb $P --passes 4 -o "$T/pf.pfm"
tb $P --passes 2 -o "$T/ph.pfm" --checkpoint "$T/p.ckpt"
$MPIRUN -np 2 "$TESTBED" render $P --passes 4 -o "$T/pr.pfm" --resume "$T/p.ckpt" --threads 1 > "$T/out" 2>&1 ||
    { cat "$T/out"; fail "path tracer resume over 2 ranks"; }
cmp "$T/pf.pfm" "$T/pr.pfm" || fail "path tracer: resumed over 2 ranks differs from the uninterrupted render"

# the hybrid renderer: its film resumes, its radiosity pass is solved again
sed 's/resolution = \[512 512\]/resolution = [32 32]/' "$TB_SOURCE_DIR/scenes/cornell-box-rgb.mid" > "$T/hb.mid"
Hy="$T/hb.mid --method hybrid --max-edge 150 --spp 1"
tb $Hy --passes 2 -o "$T/hf.pfm"
tb $Hy --passes 1 -o "$T/hh.pfm" --checkpoint "$T/h.ckpt"
tb $Hy --passes 2 -o "$T/hr.pfm" --resume "$T/h.ckpt"
cmp "$T/hf.pfm" "$T/hr.pfm" || fail "hybrid: resumed render differs from the uninterrupted one"

# two ranks, rank 1 killed once the first checkpoint is there
rm -f "$T/c.ckpt"
TB_DIST_JOB=$$ $MPIRUN -np 2 "$TESTBED" render $R --passes 400 --threads 1 -o "$T/k.pfm" --checkpoint "$T/c.ckpt" \
    > "$T/kout" 2>&1 &
kill_rank1 $! "$T/c.ckpt" "$T/kout" passes
done_passes=$killed_at
[ ! -e "$T/k.pfm" ] || fail "an image was written by the killed job"
# the checkpoint is whole (its checksum), so the job resumes from it: to 12
# passes if it got no further, else to its own count plus 2
want=12
[ "$done_passes" -lt 12 ] || want=$((done_passes + 2))
$MPIRUN -np 3 "$TESTBED" render $R --passes $want --threads 1 -o "$T/k.pfm" --resume "$T/c.ckpt" > "$T/out" 2>&1 ||
    { cat "$T/out"; fail "resume after the kill"; }
tb $R --passes $want -o "$T/k1.pfm"
cmp "$T/k1.pfm" "$T/k.pfm" || fail "killed and resumed job differs from one uninterrupted process"
# radiosity: a solve stopped at unshot 0.05 and resumed to 0.005, in one
# process and over 2 ranks, writes the patches of the uninterrupted solve;
# another seed is another job
Q="$TB_SOURCE_DIR/scenes/cornell-box.mid --method radiosity --max-edge 120"
tb $Q --threshold 0.005 --patches "$T/rf.csv"
tb $Q --threshold 0.05 --patches "$T/rh.csv" --checkpoint "$T/r.ckpt"
grep -q "checkpoint $T/r.ckpt: [0-9]* shots" "$T/out" || { cat "$T/out"; fail "no radiosity checkpoint line"; }
tb $Q --threshold 0.005 --patches "$T/rr.csv" --resume "$T/r.ckpt"
cmp "$T/rf.csv" "$T/rr.csv" || fail "resumed radiosity differs from the uninterrupted solve"
$MPIRUN -np 2 "$TESTBED" render $Q --threshold 0.005 --patches "$T/rr2.csv" --resume "$T/r.ckpt" --threads 1 \
    > "$T/out" 2>&1 || { cat "$T/out"; fail "radiosity resume over 2 ranks"; }
cmp "$T/rf.csv" "$T/rr2.csv" || fail "radiosity resumed over 2 ranks differs from the uninterrupted solve"
"$TESTBED" render $Q --threshold 0.005 --patches "$T/x.csv" --resume "$T/r.ckpt" --seed 4 > "$T/out" 2>&1 &&
    fail "radiosity resume with another seed accepted"
grep -q "r.ckpt: written for another job" "$T/out" || { cat "$T/out"; fail "no message for another seed"; }
"$TESTBED" render $Q --patches "$T/x.csv" --resume "$T/c.ckpt" > "$T/out" 2>&1 && fail "render checkpoint resumed as radiosity"
grep -q "c.ckpt: a render checkpoint, not a radiosity one" "$T/out" || { cat "$T/out"; fail "no message for the kind"; }
# adaptive subdivision: every checkpoint of a solve (snapshots of the file,
# which each shot rewrites) resumes to the uninterrupted patches, in one
# process and over 2 ranks; the refinement's rounds are rebuilt from the
# checkpoint. --max-shots makes every round shoot (it is part of the job)
A="$TB_SOURCE_DIR/scenes/cornell-box.mid --method radiosity --max-edge 120 --adapt 0.1 --threshold 0.002 --max-shots 40"
tb $A --patches "$T/af.csv"
"$TESTBED" render $A --threads 1 --patches "$T/ax.csv" --checkpoint "$T/a.ckpt" --checkpoint-every 0 > "$T/aout" 2>&1 &
job=$!
while kill -0 $job 2>/dev/null; do
    # the rounds done (the payload's second u64) name the snapshot
    r=$(od -An -tu8 -j56 -N8 "$T/a.ckpt" 2>/dev/null | tr -d ' ')
    [ -n "$r" ] && [ ! -e "$T/snap.$r" ] && cp "$T/a.ckpt" "$T/snap.$r" 2>/dev/null
    sleep 0.01
done
wait $job || { cat "$T/aout"; fail "adaptive solve with checkpoints"; }
cmp "$T/af.csv" "$T/ax.csv" || fail "adaptive: writing checkpoints changed the patches"
cp "$T/a.ckpt" "$T/snap.final"
n=0
for f in "$T"/snap.*; do
    tb $A --patches "$T/ar.csv" --resume "$f"
    cmp "$T/af.csv" "$T/ar.csv" || fail "adaptive: resumed from $(basename "$f") differs from the uninterrupted solve"
    n=$((n + 1))
done
$MPIRUN -np 2 "$TESTBED" render $A --threads 1 --patches "$T/ar2.csv" --resume "$T/snap.1" > "$T/out" 2>&1 ||
    $MPIRUN -np 2 "$TESTBED" render $A --threads 1 --patches "$T/ar2.csv" --resume "$T/snap.0" > "$T/out" 2>&1 ||
    { cat "$T/out"; fail "adaptive resume over 2 ranks"; }
cmp "$T/af.csv" "$T/ar2.csv" || fail "adaptive: resumed over 2 ranks differs from the uninterrupted solve"
"$TESTBED" render $A --threshold 0.001 --patches "$T/x.csv" --resume "$T/a.ckpt" > "$T/out" 2>&1 &&
    fail "adaptive resume with another threshold accepted"
grep -q "a.ckpt: written for another job" "$T/out" || { cat "$T/out"; fail "no message for another adaptive threshold"; }
snaps=$(cd "$T" && echo snap.*)

rm -rf "$T"
echo "dist checkpoint: ok (killed after $done_passes passes; adaptive: resumed from $n checkpoints: $snaps)"
