/* Workgroup width from the device's limits, and the limits the kernels
 * depend on as one line (for -v) and as --stats fields (docs/gpu.md,
 * "Device limits"). Nothing here assumes lavapipe's values. */
#include <math.h>
#include <stdio.h>

#include "host/gpu/gpu.h"
#include "util/stats/stats.h"

uint32_t tb_gpu_workgroup_limit(const tb_gpu_device_info *info)
{
    uint32_t a = info->max_workgroup_size[0], b = info->max_workgroup_invocations;
    return a < b ? a : b;
}

uint32_t tb_gpu_default_workgroup(const tb_gpu_device_info *info)
{
    uint32_t limit = tb_gpu_workgroup_limit(info), sg = info->subgroup_size ? info->subgroup_size : 1;
    /* TB_GPU_DEFAULT_WORKGROUP rounded up to whole subgroups (a subgroup of
     * 128 gives 128), then the largest whole number of subgroups the device
     * allows (the limit itself if one subgroup is more). */
    uint32_t w = (TB_GPU_DEFAULT_WORKGROUP + sg - 1) / sg * sg;
    if (w > limit)
        w = limit >= sg ? limit / sg * sg : limit;
    return w ? w : 1;
}

int tb_gpu_limits_describe(const tb_gpu_device_info *i, char *buf, size_t n)
{
    char ts[96];
    if (i->timestamps)
        snprintf(ts, sizeof ts, "timestamps %u bits, %.3g ns per tick", i->timestamp_valid_bits,
                 (double)i->timestamp_period);
    else
        snprintf(ts, sizeof ts, "no timestamps (kernel times not measured)");
    char sg[32];
    if (i->subgroup_size)
        snprintf(sg, sizeof sg, "%u", i->subgroup_size);
    else
        snprintf(sg, sizeof sg, "unknown");
    return snprintf(buf, n,
                    "%s: subgroup %s, workgroup %u (limit %u invocations), shared memory %u bytes, "
                    "storage buffer %.0f MiB, %s",
                    i->name, sg, tb_gpu_default_workgroup(i), tb_gpu_workgroup_limit(i), i->max_shared_memory,
                    (double)i->max_storage_buffer_range / 1048576.0, ts);
}

tb_status tb_gpu_limits_to_stats(const tb_gpu_device_info *i)
{
    tb_status st = tb_stats_set_string("gpu_device", i->name);
    if (!st)
        st = tb_stats_set_value("gpu_subgroup_size", i->subgroup_size ? (double)i->subgroup_size : NAN);
    if (!st)
        st = tb_stats_set_value("gpu_workgroup_size", (double)tb_gpu_default_workgroup(i));
    if (!st)
        st = tb_stats_set_value("gpu_max_workgroup_invocations", (double)tb_gpu_workgroup_limit(i));
    if (!st)
        st = tb_stats_set_value("gpu_max_shared_memory", (double)i->max_shared_memory);
    if (!st)
        st = tb_stats_set_value("gpu_timestamp_period_ns", i->timestamps ? (double)i->timestamp_period : NAN);
    return st;
}
