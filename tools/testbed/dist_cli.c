/* dist_cli.h: job keys, per-rank summaries, the render set-up. */
#include "dist_cli.h"
#include "util/stats/stats.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const tb_cli_free_opts[] = {"-o", "--threads", "--passes", "--time-budget", "--checkpoint",
                                        "--checkpoint-every", "--resume", "--stats", "--sample-map", "--report",
                                        "--reference", "--exposure", "--backend", "--device", "--patches",
                                        "--mesh-out", "--threshold", "--max-shots", NULL};

/* True if argv[i] is one of `free_opts` ("--name" or "--name=value"); *skip
 * is 1 if its value is the next argument. */
static bool tb__free_opt(const char *a, const char *const *free_opts, int *skip)
{
    for (const char *const *f = free_opts; *f; f++) {
        size_t n = strlen(*f);
        if (strncmp(a, *f, n) == 0 && (a[n] == '\0' || a[n] == '=')) {
            *skip = a[n] == '\0';
            return true;
        }
    }
    return false;
}

uint64_t tb_cli_job_key(const char *scene_path, int argc, char **argv, const char *const *free_opts)
{
    uint64_t h = TB_CKPT_HASH_SEED;
    FILE *fp = fopen(scene_path, "rb");
    if (!fp) {
        tb_error(TB_ERR_IO, "%s: cannot read the scene for the checkpoint's job key", scene_path);
        return 0;
    }
    char buf[65536];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, fp)) > 0)
        h = tb_ckpt_hash(h, buf, n);
    fclose(fp);
    for (int i = 1; i < argc; i++) {
        int skip = 0;
        if (tb__free_opt(argv[i], free_opts, &skip)) {
            i += skip;
            continue;
        }
        h = tb_ckpt_hash(h, argv[i], strlen(argv[i]) + 1);
    }
    return h ? h : 1;
}

bool tb_cli_dist_scene_ok(const char *prog, const char *scene_path)
{
    if (tb_dist_size() > 1 && strcmp(scene_path, "-") == 0) {
        if (tb_dist_rank() == 0)
            fprintf(stderr, "%s: the scene from standard input: under mpirun only rank 0 gets it; give the scene "
                            "as a file every rank can read\n", prog);
        return false;
    }
    return true;
}

bool tb_cli_dist_render_setup(const char *prog, const char *scene_path, int argc, char **argv,
                              tb_render_options *ro, const char *ckpt, double every, const char *resume,
                              tb_tile_exchange **ex, tb_ckpt_render *ck, tb_render_persist *persist)
{
    *ex = NULL;
    if (tb_dist_size() > 1 && !tb_cli_dist_scene_ok(prog, scene_path))
        return false;
    if (tb_dist_size() > 1) {
        *ex = tb_dist_tiles_create(ro->threads);
        if (!*ex) {
            fprintf(stderr, "%s: %s\n", prog, tb_last_error());
            return false;
        }
        ro->exchange = *ex;
    }
    memset(ck, 0, sizeof *ck);
    ck->saved_passes = -1;
    if (ckpt || resume) {
        if (strcmp(scene_path, "-") == 0) {
            fprintf(stderr, "%s: --checkpoint and --resume need a scene file, not standard input\n", prog);
            tb_dist_tiles_free(*ex);
            *ex = NULL;
            return false;
        }
        ck->path = ckpt;
        ck->every = every;
        ck->resume_path = resume;
        ck->key = tb_cli_job_key(scene_path, argc, argv, tb_cli_free_opts);
        if (!ck->key) {
            fprintf(stderr, "%s: %s\n", prog, tb_last_error());
            tb_dist_tiles_free(*ex);
            *ex = NULL;
            return false;
        }
        *persist = tb_ckpt_render_persist(ck);
        ro->persist = persist;
    }
    if (tb_dist_rank() == 0 && tb_dist_size() > 1)
        tb_ckpt_on_term(prog);
    return true;
}

int tb_cli_stats_where_written(const char *stats_path)
{
    int were = tb_stats_enabled();
    tb_stats_set_enabled(stats_path && tb_dist_rank() == 0);
    return were;
}

void tb_cli_dist_summary(const char *prog, const char *unit, bool print)
{
    int n = tb_dist_size();
    if (n < 2)
        return;
    tb_dist_stats *all = tb_dist_rank() == 0 ? calloc((size_t)n, sizeof *all) : NULL;
    if (tb_dist_gather_stats(all) != TB_OK || !all) {
        free(all);
        return;
    }
    for (int r = 0; r < n && print; r++)
        printf("%s: rank %d: %llu %s, work %.3f s, wait %.3f s, %llu bytes sent in %llu messages; MPI start %.3f s, "
               "CPU %.3f s\n", prog, r, (unsigned long long)all[r].units, unit, all[r].work_seconds,
               all[r].wait_seconds, (unsigned long long)all[r].bytes_sent, (unsigned long long)all[r].messages,
               all[r].init_seconds, all[r].cpu_seconds);
    free(all);
}
