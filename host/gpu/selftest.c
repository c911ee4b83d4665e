/* A device self-test: run shaders/selftest.comp on a few thousand words and
 * compare every word with the value computed on the host. */
#include <math.h>
#include <stdlib.h>

#include "host/gpu/gpu.h"

tb_status tb_gpu_device_self_test(tb_gpu_device *dev, uint32_t n, double *seconds)
{
    if (!dev || n == 0)
        return tb_error(TB_ERR_ARG, "tb_gpu_device_self_test: no device or n == 0");
    if (seconds)
        *seconds = NAN;
    const uint32_t mul = 2654435761u, add = 12345u; /* odd multiplier: a wrong word cannot hide */
    uint32_t *v = malloc((size_t)n * sizeof *v);
    if (!v)
        return tb_error(TB_ERR_NOMEM, "self-test: out of memory");
    for (uint32_t i = 0; i < n; i++)
        v[i] = i ^ 0x5bd1e995u;
    tb_status st = TB_OK;
    tb_gpu_buffer *buf = tb_gpu_buffer_create(dev, (size_t)n * sizeof *v);
    tb_gpu_spec_constant spec = {1, mul};
    tb_gpu_kernel *k = buf ? tb_gpu_kernel_get(dev, &(tb_gpu_kernel_desc){.spirv = tb_gpu_builtin("selftest"),
                                                                         .buffers = 1,
                                                                         .push_size = 8,
                                                                         .spec = &spec,
                                                                         .spec_count = 1})
                           : NULL;
    if (!buf || !k) {
        st = tb_error_context(TB_ERR_DEVICE, "self-test");
        goto done;
    }
    uint32_t push[2] = {n, add};
    tb_gpu_dispatch d = {.kernel = k, .buffers = {buf}, .push = push, .items = n};
    if ((st = tb_gpu_buffer_upload(buf, 0, v, (size_t)n * sizeof *v)) || (st = tb_gpu_run(dev, &d, 1)) ||
        (st = tb_gpu_buffer_download(buf, 0, v, (size_t)n * sizeof *v)))
        goto done;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t want = (i ^ 0x5bd1e995u) * mul + add;
        if (v[i] != want) {
            st = tb_error(TB_ERR_DEVICE, "self-test: word %u is 0x%08x, expected 0x%08x: the device "
                          "computes wrong results", i, v[i], want);
            goto done;
        }
    }
    if (seconds)
        *seconds = d.seconds;
done:
    tb_gpu_buffer_destroy(buf);
    free(v);
    return st;
}
