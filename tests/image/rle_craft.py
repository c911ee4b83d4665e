#!/usr/bin/env python3
"""Hand-built Utah RLE files, written byte by byte from the format description
(docs/rle.md) and independent of Testbed's C code.

    rle_craft.py interop DIR   valid files for the rletopnm comparison test:
                               colour maps, background fill, long opcodes
    rle_craft.py seeds DIR     a small fuzzing corpus: valid and broken files

The interop set is limited to what netpbm's rletopnm decodes in a defined way:
colour maps of 256 entries (it indexes them with a stride of 256) and either
no background or H_CLEARFIRST (without it rletopnm leaves unwritten pixels
uninitialised).
"""
import os
import struct
import sys

CLEARFIRST, NO_BACKGROUND, ALPHA, COMMENT = 0x1, 0x2, 0x4, 0x8
LONG = 0x40
SKIP_LINES, SET_COLOR, SKIP_PIXELS, BYTE_DATA, RUN_DATA, EOF_OP = 1, 2, 3, 5, 6, 7


def header(w, h, ncolors, flags=NO_BACKGROUND, bg=None, cmap=None, cmaplen=0,
           comments=None, pixelbits=8, xpos=0, ypos=0):
    """The 15-byte header, background (or filler), colour map and comments."""
    ncmap = len(cmap) if cmap else 0
    if comments:
        flags |= COMMENT
    out = bytearray(struct.pack('<HhhHHBBBBB', 0xCC52, xpos, ypos, w, h, flags,
                                ncolors, pixelbits, ncmap, cmaplen))
    if not flags & NO_BACKGROUND:
        b = list(bg) + [0] * (1 + (ncolors // 2) * 2 - len(bg))  # padded to odd length
        out += bytes(b)
    else:
        out += b'\0'  # filler keeps the header even
    for channel in cmap or []:
        assert len(channel) == 1 << cmaplen
        out += struct.pack('<%dH' % len(channel), *channel)
    if comments:
        text = b''.join(c.encode() + b'\0' for c in comments)
        out += struct.pack('<H', len(text)) + text
        if len(text) & 1:
            out += b'\0'
    return bytes(out)


def op(code, operand, long=False):
    if long or operand > 255:
        return bytes([code | LONG, 0]) + struct.pack('<H', operand)
    return bytes([code, operand])


def skip_lines(n, long=False):
    return op(SKIP_LINES, n, long)


def set_color(c):
    return op(SET_COLOR, 255 if c < 0 else c)


def skip_pixels(n, long=False):
    return op(SKIP_PIXELS, n, long)


def byte_data(values, long=False):
    out = op(BYTE_DATA, len(values) - 1, long) + bytes(values)
    return out + (b'\0' if len(values) & 1 else b'')


def run_data(n, value, long=False):
    return op(RUN_DATA, n - 1, long) + bytes([value, 0])


def eof():
    return bytes([EOF_OP, 0])


def full_rows(w, h, ncolors, pixel, alpha=None):
    """Instructions writing every pixel: pixel(x, y, c) with y = 0 at the bottom.
    Rows alternate between ByteData and RunData runs to exercise both."""
    out = bytearray()
    for y in range(h):
        if y:
            out += skip_lines(1)
        chans = ([-1] if alpha else []) + list(range(ncolors))
        for c in chans:
            row = [alpha(x, y) if c < 0 else pixel(x, y, c) for x in range(w)]
            out += set_color(c)
            x = 0
            while x < w:
                n = 1
                while x + n < w and row[x + n] == row[x]:
                    n += 1
                if n >= 3:
                    out += run_data(n, row[x])
                else:
                    out += byte_data(row[x:x + n])
                x += n
    return bytes(out + eof())


def ramp_map(k):
    return [((i * (k + 3) * 37 + 11 * k) % 256) << 8 | (i * 7 % 256) for i in range(256)]


def interop_cases():
    cases = {}
    # Pseudocolour: one 8-bit channel indexing an RGB map (16-bit entries, the
    # high byte is the colour; low bytes are junk on purpose).
    cases['pseudo'] = header(9, 4, 1, cmap=[ramp_map(0), ramp_map(1), ramp_map(2)], cmaplen=8) + \
        full_rows(9, 4, 1, lambda x, y, c: (x * 29 + y * 71) % 256 if x % 4 else 200)
    # Truecolour: three channels, each through its own map.
    cases['truecolor'] = header(6, 3, 3, cmap=[ramp_map(3), ramp_map(4), ramp_map(5)], cmaplen=8) + \
        full_rows(6, 3, 3, lambda x, y, c: (x * 40 + y * 90 + c * 13) % 256)
    # Clear to a background colour, then paint sparse pixels with skips and
    # long-form opcodes; the first two scanlines are skipped entirely.
    body = bytearray(skip_lines(2, long=True))
    body += set_color(0) + skip_pixels(3) + byte_data([250, 251, 252])
    body += set_color(2) + skip_pixels(1, long=True) + run_data(5, 17, long=True)
    body += skip_lines(1) + set_color(1) + byte_data([1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13], long=True)
    body += skip_lines(3) + set_color(1) + skip_pixels(12) + byte_data([99])
    body += eof()
    cases['clearfirst'] = header(13, 7, 3, flags=CLEARFIRST, bg=[40, 80, 120],
                                 comments=['image_gamma=2.2', 'HISTORY=rle_craft.py']) + bytes(body)
    # Grey, clear to background, wide rows with long RunData and ByteData.
    w = 300
    body = bytearray(set_color(0) + run_data(w, 77))
    body += skip_lines(1) + set_color(0) + byte_data([(i * 13) % 256 for i in range(w)])
    body += skip_lines(1) + set_color(0) + skip_pixels(270) + run_data(30, 5)
    body += eof()
    cases['grey_wide'] = header(w, 3, 1, flags=CLEARFIRST, bg=[160]) + bytes(body)
    # RGB with alpha, every pixel written.
    cases['rgba'] = header(7, 5, 3, flags=NO_BACKGROUND | ALPHA) + \
        full_rows(7, 5, 3, lambda x, y, c: (x * 31 + y * 17 + c * 80) % 256,
                  alpha=lambda x, y: 255 if (x + y) % 3 else (x * 40) % 256)
    return cases


def seed_cases():
    cases = dict(interop_cases())
    good = cases['clearfirst']
    cases['grey_overlay_bg'] = header(4, 2, 1, flags=0, bg=[9]) + set_color(0) + byte_data([1]) + eof()
    cases['two_channels'] = header(3, 1, 2) + set_color(1) + run_data(3, 4) + eof()
    cases['cmap_short'] = header(3, 1, 1, cmap=[[0, 0x4000, 0x8000, 0xff00]], cmaplen=2) + \
        set_color(0) + byte_data([0, 1, 3]) + eof()
    cases['bad_magic'] = b'\x53\xcc' + good[2:]
    cases['truncated_header'] = good[:9]
    cases['truncated_data'] = good[:len(good) - 7]
    cases['no_eof'] = good[:-2]
    cases['bad_opcode'] = header(2, 1, 1) + bytes([0x09, 0]) + eof()
    cases['past_row_end'] = header(2, 1, 1) + set_color(0) + byte_data([1, 2, 3]) + eof()
    cases['above_top'] = header(2, 1, 1) + skip_lines(1) + set_color(0) + byte_data([1]) + eof()
    cases['alpha_unflagged'] = header(2, 1, 1) + set_color(-1) + byte_data([1]) + eof()
    cases['cmap_index_oob'] = header(3, 1, 1, cmap=[[0, 1, 2, 3]], cmaplen=2) + \
        set_color(0) + byte_data([0, 4]) + eof()
    cases['huge_header'] = header(65535, 65535, 3) + eof()
    return cases


def main(argv):
    if len(argv) != 3 or argv[1] not in ('interop', 'seeds'):
        sys.stderr.write(__doc__)
        return 2
    cases = interop_cases() if argv[1] == 'interop' else seed_cases()
    os.makedirs(argv[2], exist_ok=True)
    for name, data in sorted(cases.items()):
        with open(os.path.join(argv[2], name + '.rle'), 'wb') as f:
            f.write(data)
        print(name)
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
