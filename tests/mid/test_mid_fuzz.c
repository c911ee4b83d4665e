/* libFuzzer target for the MID reader. Any input must end in a valid item
 * stream or one error with a location, without a crash, leak, hang or
 * sanitizer report. Inputs that read as valid also check the writer: the
 * canonical text of what was read must read back and write identically. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "host/mid/mid_reader.h"
#include "host/mid/mid_writer.h"

#ifndef TB_FUZZ_DATA_DIR
#define TB_FUZZ_DATA_DIR "/nonexistent"
#endif

/* Reads `size` bytes of MID; with `out`, writes every item read to it.
 * Returns the reader's final status. */
static tb_status tb__read(const uint8_t *data, size_t size, FILE *out)
{
    FILE *fp = fmemopen((void *)data, size, "rb");
    if (!fp)
        return TB_ERR_IO;
    tb_mid_reader *r;
    tb_status st = tb_mid_reader_open_stream(&r, fp, "fuzz.mid", TB_FUZZ_DATA_DIR);
    if (st) {
        fclose(fp);
        return st;
    }
    if (out)
        tb_mid_write_header(out);
    tb_mid_item it;
    while (!(st = tb_mid_reader_next(r, &it)) && it.type != TB_MID_ITEM_END) {
        if (out && tb_mid_write_item(out, &it))
            abort(); /* the writer refused an item the reader accepted */
    }
    /* Every error names its place. */
    if (st == TB_ERR_FORMAT && strncmp(tb_last_error(), "fuzz.mid:", 9) != 0)
        abort();
    tb_mid_reader_close(r);
    fclose(fp);
    return st;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0 || size > 1 << 20)
        return 0;
    char *text = NULL;
    size_t len = 0;
    FILE *out = open_memstream(&text, &len);
    if (!out)
        return 0;
    tb_status st = tb__read(data, size, out);
    fclose(out);
    if (st == TB_OK) {
        /* The canonical text is a fixed point of read + write. */
        char *again = NULL;
        size_t again_len = 0;
        FILE *out2 = open_memstream(&again, &again_len);
        if (out2) {
            if (tb__read((const uint8_t *)text, len, out2) != TB_OK)
                abort();
            fclose(out2);
            if (again_len != len || memcmp(again, text, len) != 0)
                abort();
            free(again);
        }
    }
    free(text);
    return 0;
}
