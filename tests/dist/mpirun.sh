# Sourced by the host/dist script tests: $MPIRUN, a quick loopback-only
# mpirun that also runs as root (CI) and oversubscribed (-np 3 on 2 cores),
# and fail(). Open MPI's shared-memory transport (vader) on one machine
# (large messages by its single-copy mechanism where the kernel allows it,
# else copied through shared memory: the results are the same); no
# binding, so oversubscribed ranks share the cores; the ob1 and sm/pt2pt
# components only (no UCX probing: MPI starts in about half the time).
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
MPIRUN="${TB_MPIEXEC:-mpirun} --oversubscribe --bind-to none --mca btl self,vader --mca pml ob1 --mca osc sm,pt2pt"
fail() { echo "FAIL: $*"; exit 1; }
# rank_pid MARK RANK: the process id of that rank of the job started with
# TB_DIST_JOB=MARK in its environment (mpirun passes it on to local ranks).
rank_pid() {
    for d in /proc/[0-9]*; do
        e=$({ tr '\0' '\n' < "$d/environ"; } 2>/dev/null) || continue
        if printf '%s\n' "$e" | grep -qx "TB_DIST_JOB=$1" && printf '%s\n' "$e" | grep -qx "OMPI_COMM_WORLD_RANK=$2"; then
            echo "${d#/proc/}"; return 0
        fi
    done
    return 1
}
# kill_rank1 JOB CKPT LOG UNIT: once CKPT is written (within a minute), kills
# rank 1 of the job JOB (a background mpirun started with TB_DIST_JOB=$$,
# output in LOG) with SIGKILL; the job must stop, LOG name rank 1 and the
# intact checkpoint with its count of UNIT (passes, shots), set in $killed_at.
kill_rank1() {
    i=0
    while [ ! -s "$2" ] && [ $i -lt 600 ]; do sleep 0.1; i=$((i + 1)); done
    [ -s "$2" ] || { kill "$1"; cat "$3"; fail "no checkpoint within a minute"; }
    victim=$(rank_pid $$ 1) || { kill "$1"; wait "$1"; cat "$3"; fail "rank 1 not found (the job ended first?)"; }
    kill -9 "$victim"
    wait "$1" && { cat "$3"; fail "the job went on after rank 1 died"; }
    grep -q "rank 1 .*exited on signal 9" "$3" || { cat "$3"; fail "the dead rank is not named"; }
    grep -q "last checkpoint: $2 ([0-9]* $4), intact: continue with --resume" "$3" ||
        { cat "$3"; fail "the last checkpoint is not named"; }
    killed_at=$(sed -n "s/.*last checkpoint: .*(\([0-9]*\) $4).*/\1/p" "$3" | head -1)
}
# test_dir NAME: a fresh folder $T for the test NAME, holding box.mid, the
# Cornell box shrunk to 64 x 64 pixels.
test_dir() {
    T="${TB_TEST_TMPDIR:-/tmp}/$1.$$"
    rm -rf "$T" && mkdir -p "$T"
    sed 's/resolution = \[512 512\]/resolution = [64 64]/' "$TB_SOURCE_DIR/scenes/cornell-box.mid" > "$T/box.mid"
    grep -q 'resolution = \[64 64\]' "$T/box.mid" || fail "could not shrink the Cornell box"
}
