/* libFuzzer target for our libpng wrapper: its setjmp error handling must turn
 * every damaged file into an error status with no crash, leak or half image.
 * Accepted inputs are written back as 16-bit linear PNG and re-read: every
 * value (8-bit codes included, c/255 = 257c/65535) must come back exactly. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/image/image.h"

/* Keep runs quick: decoding is fine, but filling huge images thousands of
 * times is slow (the reader's own limits are tested in the unit tests). */
#define FUZZ_MAX_PIXELS (1u << 20)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0)
        return 0; /* fmemopen needs a non-empty buffer; the unit tests cover empty files */
    if (size >= 24) { /* IHDR width and height sit at bytes 16-23 */
        uint32_t w = (uint32_t)data[16] << 24 | (uint32_t)data[17] << 16 | (uint32_t)data[18] << 8 | data[19];
        uint32_t h = (uint32_t)data[20] << 24 | (uint32_t)data[21] << 16 | (uint32_t)data[22] << 8 | data[23];
        if ((uint64_t)w * h > FUZZ_MAX_PIXELS)
            return 0;
    }
    FILE *f = fmemopen((void *)data, size, "rb");
    if (!f)
        return 0;
    tb_image_read_options ro = {.encoding = TB_ENCODING_LINEAR};
    tb_image *img = NULL;
    tb_status st = tb_png_read(f, "fuzz", &ro, &img);
    fclose(f);
    if (st != TB_OK) {
        if (img || !tb_last_error()[0])
            __builtin_trap();
        return 0;
    }
    char *buf = NULL;
    size_t len = 0;
    FILE *m = open_memstream(&buf, &len);
    if (!m)
        __builtin_trap();
    tb_image_write_options wo = {.encoding = TB_ENCODING_LINEAR, .png_bits = 16};
    st = tb_png_write(m, "fuzz-out", img, &wo);
    fclose(m);
    if (st == TB_ERR_ARG) { /* a text key from the file that is not a valid PNG keyword in ASCII */
        free(buf);
        tb_image_free(img);
        return 0;
    }
    if (st != TB_OK)
        __builtin_trap();
    FILE *r = fmemopen(buf, len, "rb");
    tb_image *back = NULL;
    if (!r || tb_png_read(r, "fuzz-back", &ro, &back) != TB_OK)
        __builtin_trap();
    fclose(r);
    size_t n = (size_t)img->width * (size_t)img->height * (size_t)img->channels;
    if (back->width != img->width || back->height != img->height || back->channels != img->channels ||
        back->nattrs != img->nattrs || memcmp(back->pixels, img->pixels, n * sizeof(float)) != 0)
        __builtin_trap();
    for (int i = 0; i < img->nattrs; i++) {
        const char *v = tb_image_get_attr(back, img->attrs[i].key);
        if (!v || strcmp(v, img->attrs[i].value) != 0)
            __builtin_trap();
    }
    tb_image_free(back);
    free(buf);
    tb_image_free(img);
    return 0;
}
