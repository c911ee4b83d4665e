#!/usr/bin/env bash
# Our PNG and PFM files against an independent implementation, netpbm:
# netpbm writes a file, `testbed convert` reads it and writes its own, netpbm
# reads that back, and every pixel must equal the original exactly (8- and
# 16-bit PNG, grey, RGB and RGBA; PFM bit for bit; PNG text chunks).
set -euo pipefail
: "${TESTBED:?}" "${TB_TEST_TMPDIR:?}"
T="$TB_TEST_TMPDIR/image_netpbm"
rm -rf "$T"
mkdir -p "$T"
cd "$T"

fail() { echo "FAIL: $*" >&2; exit 1; }
# same FILE1 FILE2 WHAT: the two Netpbm images hold identical pixels.
same() {
    pnmtoplainpnm "$1" > "$1.plain" 2>/dev/null || pamtopnm -plain "$1" > "$1.plain"
    pnmtoplainpnm "$2" > "$2.plain" 2>/dev/null || pamtopnm -plain "$2" > "$2.plain"
    # plain PNM: compare the numbers, not the line breaks
    tr -s ' \n' '\n\n' < "$1.plain" > "$1.nums"
    tr -s ' \n' '\n\n' < "$2.plain" > "$2.nums"
    cmp -s "$1.nums" "$2.nums" || fail "$3: pixels differ ($1 vs $2)"
    echo "ok: $3"
}

# Reference images with every kind of code: a 17 x 9 RGB ramp mixing 0 and
# 255 with everything between, a grey ramp, an alpha mask, a 16-bit image.
awk 'BEGIN { w = 17; h = 9; print "P3"; print w, h; print 255;
  for (y = 0; y < h; y++) { line = "";
    for (x = 0; x < w; x++) for (c = 0; c < 3; c++) {
      v = (x * 37 + y * 101 + c * 71 + x * y * 13) % 256;
      if (x == 0) v = 0; if (x == w - 1) v = 255;
      line = line " " v }
    print line } }' > rgb.ppm
awk 'BEGIN { print "P2"; print 16, 16; print 255;
  for (y = 0; y < 16; y++) { line = ""; for (x = 0; x < 16; x++) line = line " " (y * 16 + x); print line } }' > grey.pgm
awk 'BEGIN { print "P2"; print 17, 9; print 255;
  for (y = 0; y < 9; y++) { line = ""; for (x = 0; x < 17; x++) line = line " " ((x * 29 + y * 53) % 256); print line } }' > mask.pgm
awk 'BEGIN { w = 11; h = 5; print "P3"; print w, h; print 65535;
  for (y = 0; y < h; y++) { line = "";
    for (x = 0; x < w; x++) for (c = 0; c < 3; c++) line = line " " ((x * 6007 + y * 13001 + c * 21011 + x * y * 17) % 65536);
    print line } }' > deep.ppm

# --- PNG 8-bit RGB, sRGB (default) and linear
pnmtopng rgb.ppm > rgb.png
"$TESTBED" convert rgb.png out.png
pngtopnm out.png > out.ppm
same rgb.ppm out.ppm "PNG 8-bit RGB, sRGB"
"$TESTBED" convert --linear rgb.png out_lin.png
pngtopnm out_lin.png > out_lin.ppm
same rgb.ppm out_lin.ppm "PNG 8-bit RGB, linear"

# --- PNG grey
pnmtopng grey.pgm > grey.png
"$TESTBED" convert grey.png grey_out.png
pngtopnm grey_out.png > grey_out.pgm
same grey.pgm grey_out.pgm "PNG 8-bit grey"

# --- PNG RGBA: colour and alpha separately (alpha is stored linearly)
pnmtopng -alpha=mask.pgm rgb.ppm > rgba.png
"$TESTBED" convert rgba.png rgba_out.png
pngtopnm rgba_out.png > rgba_out.ppm
pngtopnm -alpha rgba_out.png > rgba_out_alpha.pgm
same rgb.ppm rgba_out.ppm "PNG RGBA colour"
same mask.pgm rgba_out_alpha.pgm "PNG RGBA alpha"
# ... and through a float format and back
"$TESTBED" convert rgba.png rgba.exr
"$TESTBED" convert rgba.exr rgba_back.png
pngtopnm -alpha rgba_back.png > rgba_back_alpha.pgm
same mask.pgm rgba_back_alpha.pgm "PNG RGBA alpha through EXR"

# --- PNG 16-bit: every code kept through float and --bits 16
pnmtopng deep.ppm > deep.png
"$TESTBED" convert --bits 16 deep.png deep_out.png
pngtopnm deep_out.png > deep_out.ppm
same deep.ppm deep_out.ppm "PNG 16-bit RGB, sRGB"
"$TESTBED" convert --linear deep.png deep.pfm
"$TESTBED" convert --linear --bits 16 deep.pfm deep_lin.png
pngtopnm deep_lin.png > deep_lin.ppm
same deep.ppm deep_lin.ppm "PNG 16-bit through PFM, linear"

# --- PFM: netpbm's file read and rewritten bit for bit (data after the header)
pamtopfm -endian=little rgb.ppm > ref.pfm
"$TESTBED" convert ref.pfm out.pfm
head -c 3 out.pfm | grep -q '^PF' || fail "PFM magic"
n=$((17 * 9 * 3 * 4))
cmp -s <(tail -c "$n" ref.pfm) <(tail -c "$n" out.pfm) || fail "PFM float data differs from netpbm's"
echo "ok: PFM RGB data bit for bit"
pamtopfm -endian=big rgb.ppm > ref_be.pfm
"$TESTBED" convert ref_be.pfm out_be.pfm
cmp -s <(tail -c "$n" ref.pfm) <(tail -c "$n" out_be.pfm) || fail "big-endian PFM not converted to little-endian"
echo "ok: PFM big-endian read"
# No -maxval: Debian 12's pfmtopam (netpbm 11.01) rejects an explicit
# '-maxval 255' now and then ("Maximum allowed -maxval is 65535"); 255 is its
# default, and `same` below checks the header says so.
pfmtopam out.pfm | pamtopnm > out_pfm.ppm
same rgb.ppm out_pfm.ppm "PFM RGB read by netpbm"
# PFM values are code/255: --linear PNG gives the codes back
"$TESTBED" convert --linear ref.pfm from_pfm.png
pngtopnm from_pfm.png > from_pfm.ppm
same rgb.ppm from_pfm.ppm "PFM -> linear PNG"
# grey PFM ("Pf")
pamtopfm grey.pgm > grey.pfm
"$TESTBED" convert grey.pfm grey_out.pfm
head -c 2 grey_out.pfm | grep -q '^Pf' || fail "grey PFM magic"
pfmtopam grey_out.pfm | pamtopnm > grey_pfm.pgm
same grey.pgm grey_pfm.pgm "PFM grey read by netpbm"

# --- PNG text chunks: netpbm's tEXt -> EXR attributes -> our tEXt -> netpbm
printf 'Title Cornell box\nSoftware testbed\n' > text.txt
pnmtopng -text text.txt rgb.ppm > text.png
"$TESTBED" convert text.png text.exr
"$TESTBED" convert text.exr text_out.png
pngtopam -text=text_out.txt text_out.png > /dev/null
grep -Eq '^Title +Cornell box$' text_out.txt || fail "tEXt Title lost: $(cat text_out.txt)"
grep -Eq '^Software +testbed$' text_out.txt || fail "tEXt Software lost: $(cat text_out.txt)"
echo "ok: PNG text chunks through EXR"

echo "all netpbm checks passed"
