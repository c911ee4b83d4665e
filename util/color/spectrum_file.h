/* Spectrum files: the data blocks that MID's `spectrum(file("x.spd"))` names. */
#ifndef TB_UTIL_COLOR_SPECTRUM_FILE_H
#define TB_UTIL_COLOR_SPECTRUM_FILE_H

#include <stdio.h>

#include "util/color/spectrum.h"

/* Reads a spectrum file (docs/color.md, "Spectrum files"): UTF-8 text, `#`
 * comments, an optional header line of column names, then one sample per line,
 * `wavelength_nm value`, separated by white space or one comma. Malformed input
 * gives TB_ERR_FORMAT with `name:line:col: error: ...`; unreadable files TB_ERR_IO. */
tb_status tb_spectrum_read_file(const char *path, tb_spectrum *out);

/* tb_spectrum_read_file() from an open stream; `name` is used in messages. */
tb_status tb_spectrum_read_stream(FILE *f, const char *name, tb_spectrum *out);

#endif
