# Sourced by the host/dist script tests: $MPIRUN, a quick loopback-only
# mpirun that also runs as root (CI) and oversubscribed (-np 3 on 2 cores),
# and fail(). Open MPI's shared-memory transport (vader) on one machine;
# no single-copy (CMA needs ptrace rights a container may lack); no
# binding, so oversubscribed ranks share the cores.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none
MPIRUN="${TB_MPIEXEC:-mpirun} --oversubscribe --bind-to none --mca btl self,vader"
fail() { echo "FAIL: $*"; exit 1; }
# rank_pid MPIRUN_PID RANK: the process id of that rank of the job.
rank_pid() {
    for p in $(pgrep -P "$1"); do
        if tr '\0' '\n' < "/proc/$p/environ" 2>/dev/null | grep -qx "OMPI_COMM_WORLD_RANK=$2"; then
            echo "$p"; return 0
        fi
    done
    return 1
}
