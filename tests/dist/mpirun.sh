# Sourced by the host/dist script tests: $MPIRUN, a quick loopback-only
# mpirun that also runs as root (CI) and oversubscribed (-np 3 on 2 cores),
# and fail(). Open MPI's shared-memory transport (vader) on one machine
# (large messages by its single-copy mechanism where the kernel allows it,
# else copied through shared memory: the results are the same); no
# binding, so oversubscribed ranks share the cores.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
MPIRUN="${TB_MPIEXEC:-mpirun} --oversubscribe --bind-to none --mca btl self,vader"
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
