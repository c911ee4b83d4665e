/* libFuzzer target for the PFM reader. Any input must give TB_OK or an error
 * status, never a crash, leak or sanitizer report, and never a half image.
 * Inputs the reader accepts are written back and re-read: every float must
 * come back bit for bit. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/image/image.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0)
        return 0; /* fmemopen needs a non-empty buffer; the unit tests cover empty files */
    FILE *f = fmemopen((void *)data, size, "rb");
    if (!f)
        return 0;
    tb_image *img = NULL;
    tb_status st = tb_pfm_read(f, "fuzz", &img);
    fclose(f);
    if (st != TB_OK) {
        if (img || !tb_last_error()[0])
            __builtin_trap(); /* a failed read returns no image and says why */
        return 0;
    }
    char *buf = NULL;
    size_t len = 0;
    FILE *m = open_memstream(&buf, &len);
    if (!m || tb_pfm_write(m, "fuzz-out", img, NULL) != TB_OK)
        __builtin_trap(); /* 1 or 3 channels: always writable */
    fclose(m);
    FILE *r = fmemopen(buf, len, "rb");
    tb_image *back = NULL;
    if (!r || tb_pfm_read(r, "fuzz-back", &back) != TB_OK)
        __builtin_trap();
    fclose(r);
    size_t n = (size_t)img->width * (size_t)img->height * (size_t)img->channels;
    if (back->width != img->width || back->height != img->height || back->channels != img->channels ||
        memcmp(back->pixels, img->pixels, n * sizeof(float)) != 0)
        __builtin_trap();
    tb_image_free(back);
    free(buf);
    tb_image_free(img);
    return 0;
}
