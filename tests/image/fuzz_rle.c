/* libFuzzer target for the Utah RLE reader. Any input must give TB_OK or an
 * error status, never a crash, leak or sanitizer report. Inputs the reader
 * accepts are also written back and re-read: the codes must survive exactly
 * (the writer and reader agree on everything the reader can produce). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/image/image.h"

/* Keep each run small: a 15-byte header may legally claim 8192x8192 pixels
 * (the reader's cap), which is correct but slow to fill thousands of times. */
#define FUZZ_MAX_PIXELS (1u << 20)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0)
        return 0; /* fmemopen needs a non-empty buffer; the unit tests cover empty files */
    if (size >= 10) {
        uint32_t w = (uint32_t)data[6] | (uint32_t)data[7] << 8;
        uint32_t h = (uint32_t)data[8] | (uint32_t)data[9] << 8;
        if ((uint64_t)w * h > FUZZ_MAX_PIXELS)
            return 0;
    }
    FILE *f = fmemopen((void *)data, size, "rb");
    if (!f)
        return 0;
    tb_image_read_options ro = {.encoding = TB_ENCODING_LINEAR};
    tb_image *img = NULL;
    tb_status st = tb_rle_read(f, "fuzz", &ro, &img);
    fclose(f);
    if (st != TB_OK) {
        if (img)
            __builtin_trap(); /* a failed read must not return an image */
        return 0;
    }

    char *buf = NULL;
    size_t len = 0;
    FILE *m = open_memstream(&buf, &len);
    if (!m)
        __builtin_trap();
    tb_image_write_options wo = {.encoding = TB_ENCODING_LINEAR};
    st = tb_rle_write(m, "fuzz-out", img, &wo);
    fclose(m);
    if (st == TB_ERR_UNSUPPORTED) {
        /* sizes over 32767 (which the writer refuses for netpbm's sake) or
         * comments that grow past 64 KiB when their missing NUL is added */
        free(buf);
        tb_image_free(img);
        return 0;
    }
    if (st != TB_OK)
        __builtin_trap(); /* anything else we read, we can write */
    FILE *r = fmemopen(buf, len, "rb");
    tb_image *back = NULL;
    if (!r || tb_rle_read(r, "fuzz-back", &ro, &back) != TB_OK)
        __builtin_trap();
    fclose(r);
    if (back->width != img->width || back->height != img->height ||
        back->channels != img->channels || back->nattrs != img->nattrs)
        __builtin_trap();
    size_t n = (size_t)img->width * (size_t)img->height * (size_t)img->channels;
    if (memcmp(back->pixels, img->pixels, n * sizeof(float)) != 0)
        __builtin_trap();
    for (int i = 0; i < img->nattrs; i++)
        if (strcmp(back->attrs[i].key, img->attrs[i].key) != 0 ||
            strcmp(back->attrs[i].value, img->attrs[i].value) != 0)
            __builtin_trap();
    tb_image_free(back);
    free(buf);
    tb_image_free(img);
    return 0;
}
