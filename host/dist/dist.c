/* The job: MPI start and end, rank and size, agreement on failures,
 * broadcasts and the per-rank accounts (dist.h). */
#include "host/dist/dist.h"
#include "host/dist/dist_internal.h"
#include "util/stats/stats.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <sys/resource.h>

#ifdef TB_HAVE_MPI
#include <mpi.h>
#endif

static int tb__dist_rank_v = 0, tb__dist_size_v = 1;
#ifdef TB_HAVE_MPI
static int tb__dist_mpi = 0; /* MPI_Init_thread was called here */
#endif
static tb_dist_stats tb__dist_totals;

bool tb_dist_built_with_mpi(void)
{
#ifdef TB_HAVE_MPI
    return true;
#else
    return false;
#endif
}

double tb__dist_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* The job size a launcher announced in the environment (Open MPI's mpirun,
 * or a PMI launcher such as srun), or 0 if none started this process. */
static int tb__dist_launched_size(void)
{
    static const char *const vars[] = {"OMPI_COMM_WORLD_SIZE", "PMIX_SIZE", "PMI_SIZE"};
    for (size_t i = 0; i < sizeof vars / sizeof vars[0]; i++) {
        const char *v = getenv(vars[i]);
        if (v && *v)
            return atoi(v);
    }
    return getenv("PMIX_RANK") ? 1 : 0;
}

tb_status tb_dist_init(int *argc, char ***argv)
{
    int launched = tb__dist_launched_size();
#ifdef TB_HAVE_MPI
    if (launched > 0 && !tb__dist_mpi) {
        int provided = 0;
        double t0 = tb__dist_now();
        /* every MPI call of host/dist is made under a lock, by one thread at
         * a time: serialized is all it needs */
        if (MPI_Init_thread(argc, argv, MPI_THREAD_SERIALIZED, &provided) != MPI_SUCCESS)
            return tb_error(TB_ERR_IO, "MPI_Init_thread failed");
        tb__dist_totals.init_seconds = tb__dist_now() - t0;
        if (provided < MPI_THREAD_SERIALIZED) {
            MPI_Finalize();
            return tb_error(TB_ERR_UNSUPPORTED, "this MPI library gives thread level %d, host/dist needs "
                            "MPI_THREAD_SERIALIZED (%d)", provided, MPI_THREAD_SERIALIZED);
        }
        tb__dist_mpi = 1;
        MPI_Comm_rank(MPI_COMM_WORLD, &tb__dist_rank_v);
        MPI_Comm_size(MPI_COMM_WORLD, &tb__dist_size_v);
    }
    return TB_OK;
#else
    (void)argc, (void)argv;
    if (launched > 1)
        return tb_error(TB_ERR_UNSUPPORTED,
                        "started as one of %d ranks, but this testbed was built without MPI (-DTB_MPI=OFF or no "
                        "Open MPI found): it would compute the whole job %d times; rebuild with libopenmpi-dev "
                        "(tools/setup.sh) or run one process",
                        launched, launched);
    return TB_OK;
#endif
}

void tb_dist_finalize(void)
{
#ifdef TB_HAVE_MPI
    if (tb__dist_mpi) {
        MPI_Finalize();
        tb__dist_mpi = 0;
    }
#endif
}

int tb_dist_rank(void) { return tb__dist_rank_v; }

int tb_dist_size(void) { return tb__dist_size_v; }

_Noreturn void tb_dist_abort(int code)
{
    fflush(stdout);
    fflush(stderr);
#ifdef TB_HAVE_MPI
    if (tb__dist_mpi)
        MPI_Abort(MPI_COMM_WORLD, code);
#endif
    exit(code);
}

tb_status tb_dist_agree_status(tb_status st, int *rank)
{
    if (rank)
        *rank = st ? tb__dist_rank_v : -1;
#ifdef TB_HAVE_MPI
    if (!tb__dist_mpi)
        return st;
    double t0 = tb__dist_now();
    int mine = st ? tb__dist_rank_v : tb__dist_size_v, first = 0;
    MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    if (first == tb__dist_size_v) {
        tb__dist_account(0, tb__dist_now() - t0, 0, 1, 0);
        return TB_OK;
    }
    /* the failing rank's status and message, as they are */
    struct {
        int st;
        char msg[1024];
    } m;
    memset(&m, 0, sizeof m);
    if (first == tb__dist_rank_v) {
        m.st = (int)st;
        snprintf(m.msg, sizeof m.msg, "%s", tb_last_error());
    }
    MPI_Bcast(&m, (int)sizeof m, MPI_BYTE, first, MPI_COMM_WORLD);
    tb__dist_account(0, tb__dist_now() - t0, first == tb__dist_rank_v ? sizeof m : 0, 2, 0);
    if (rank)
        *rank = first;
    return tb_error((tb_status)m.st, "%s", m.msg);
#else
    return st;
#endif
}

int tb_dist_bcast_int(int v)
{
#ifdef TB_HAVE_MPI
    if (tb__dist_mpi) {
        double t0 = tb__dist_now();
        MPI_Bcast(&v, 1, MPI_INT, 0, MPI_COMM_WORLD);
        tb__dist_account(0, tb__dist_now() - t0, tb__dist_rank_v == 0 ? sizeof v : 0, 1, 0);
    }
#endif
    return v;
}

tb_status tb_dist_bcast_bytes(void *buf, size_t len)
{
#ifdef TB_HAVE_MPI
    if (tb__dist_mpi) {
        double t0 = tb__dist_now();
        unsigned char *p = buf;
        /* MPI counts are ints: large buffers go in pieces */
        for (size_t off = 0; off < len;) {
            size_t n = len - off < (size_t)1 << 30 ? len - off : (size_t)1 << 30;
            if (MPI_Bcast(p + off, (int)n, MPI_BYTE, 0, MPI_COMM_WORLD) != MPI_SUCCESS)
                return tb_error(TB_ERR_IO, "MPI_Bcast of %zu bytes failed", len);
            off += n;
        }
        tb__dist_account(0, tb__dist_now() - t0, tb__dist_rank_v == 0 ? len : 0, 1, 0);
    }
#else
    (void)buf, (void)len;
#endif
    return TB_OK;
}

void tb__dist_account(double work, double wait, uint64_t bytes, uint64_t messages, uint64_t units)
{
    tb__dist_totals.work_seconds += work;
    tb__dist_totals.wait_seconds += wait;
    tb__dist_totals.bytes_sent += bytes;
    tb__dist_totals.messages += messages;
    tb__dist_totals.units += units;
}

/* CPU seconds (user + system) of this process so far. */
static double tb__dist_cpu(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0)
        return 0.0;
    return (double)ru.ru_utime.tv_sec + (double)ru.ru_stime.tv_sec +
           1e-6 * (double)(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

tb_dist_stats tb_dist_my_stats(void)
{
    tb_dist_stats s = tb__dist_totals;
    s.cpu_seconds = tb__dist_cpu();
    return s;
}

tb_status tb_dist_gather_stats(tb_dist_stats *all)
{
#ifdef TB_HAVE_MPI
    if (tb__dist_mpi) {
        enum { K = 7 };
        double mine[K] = {tb__dist_totals.work_seconds, tb__dist_totals.wait_seconds,
                          (double)tb__dist_totals.bytes_sent, (double)tb__dist_totals.messages,
                          (double)tb__dist_totals.units, tb__dist_totals.init_seconds, tb__dist_cpu()};
        double *buf = NULL;
        if (tb__dist_rank_v == 0 && !(buf = malloc(sizeof mine * (size_t)tb__dist_size_v)))
            return tb_error(TB_ERR_NOMEM, "out of memory for the ranks' stats");
        MPI_Gather(mine, K, MPI_DOUBLE, buf, K, MPI_DOUBLE, 0, MPI_COMM_WORLD);
        if (buf) {
            for (int r = 0; r < tb__dist_size_v; r++) {
                const double *b = buf + K * r;
                all[r] = (tb_dist_stats){.work_seconds = b[0], .wait_seconds = b[1], .bytes_sent = (uint64_t)b[2],
                                         .messages = (uint64_t)b[3], .units = (uint64_t)b[4],
                                         .init_seconds = b[5], .cpu_seconds = b[6]};
            }
            free(buf);
        }
        return TB_OK;
    }
#endif
    if (all)
        all[0] = tb_dist_my_stats();
    return TB_OK;
}

tb_status tb_dist_report_stats(const char *unit)
{
    int n = tb__dist_size_v;
    tb_dist_stats *all = tb__dist_rank_v == 0 ? calloc((size_t)n, sizeof *all) : NULL;
    if (tb__dist_rank_v == 0 && !all)
        return tb_error(TB_ERR_NOMEM, "out of memory for the ranks' stats");
    tb_status st = tb_dist_gather_stats(all);
    if (!st && all)
        st = tb_stats_set_value("ranks", (double)n);
    for (int r = 0; all && r < n && !st; r++) {
        char key[96];
        struct {
            const char *name;
            double v;
        } kv[] = {{"work_seconds", all[r].work_seconds}, {"wait_seconds", all[r].wait_seconds},
                  {"bytes_sent", (double)all[r].bytes_sent}, {"messages", (double)all[r].messages},
                  {unit, (double)all[r].units}, {"init_seconds", all[r].init_seconds},
                  {"cpu_seconds", all[r].cpu_seconds}};
        for (size_t k = 0; k < sizeof kv / sizeof kv[0] && !st; k++) {
            snprintf(key, sizeof key, "rank%d_%s", r, kv[k].name);
            st = tb_stats_set_value(key, kv[k].v);
        }
    }
    free(all);
    return st;
}
