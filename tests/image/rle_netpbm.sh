#!/usr/bin/env bash
# Utah RLE interoperability with netpbm, pixel for pixel, both directions:
#   netpbm -> us:  pnmtorle writes, our reader (rle_tool topnm) must give the
#                  source PNM back byte for byte, and the same as rletopnm;
#   us -> netpbm:  our writer (rle_tool frompnm) writes, rletopnm must give the
#                  source back byte for byte (alpha through --alphaout);
#   hand-built files (rle_craft.py: colour maps, background fill, long
#                  opcodes) decode identically with rletopnm and with us.
# Usage: rle_netpbm.sh RLE_TOOL   (TB_SOURCE_DIR, TB_TEST_TMPDIR from CTest)
set -euo pipefail
tool=$1
src=${TB_SOURCE_DIR:?}/tests/image
tmp=$(mktemp -d "${TB_TEST_TMPDIR:-/tmp}/rle_netpbm.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"
fails=0
checks=0

same() { # same FILE1 FILE2 WHAT
    checks=$((checks + 1))
    if ! cmp -s "$1" "$2"; then
        echo "FAIL: $3: $1 and $2 differ"
        cmp "$1" "$2" | head -1 || true
        fails=$((fails + 1))
    fi
}

# ---- source images: grey and colour, odd sizes, long runs, noise
pgmramp -lr 61 7 > ramp.pgm
pgmnoise -randomseed=7 33 17 > noise.pgm
pbmmake -g 13 5 | pamdepth -quiet 255 | pamtopnm > checker.pgm
ppmpat -madras -randomseed=3 45 19 > madras.ppm
pgmnoise -randomseed=1 37 9 > n1.pgm
pgmnoise -randomseed=2 37 9 > n2.pgm
pgmnoise -randomseed=3 37 9 > n3.pgm
rgb3toppm n1.pgm n2.pgm n3.pgm > noise.ppm
# 700 wide: runs and literals longer than 256 (long opcode forms)
ppmmake rgb:20/c0/ff 400 3 > wide_run.ppm
for k in 4 5 6; do pgmnoise -randomseed=$k 300 3 > wn$k.pgm; done
rgb3toppm wn4.pgm wn5.pgm wn6.pgm > wide_noise.ppm
pamcat -leftright wide_run.ppm wide_noise.ppm | pamtopnm > wide.ppm
ppmmake rgb:00/00/00 1 1 > one.ppm
pgmramp -tb 1 300 > tall.pgm

for f in ramp.pgm noise.pgm checker.pgm madras.ppm noise.ppm wide.ppm one.ppm tall.pgm; do
    base=${f%.*}
    ext=${f##*.}
    # netpbm -> us
    pnmtorle "$f" > "$base.np.rle"
    "$tool" topnm "$base.np.rle" "$base.ours.$ext"
    same "$f" "$base.ours.$ext" "pnmtorle $f, read by tb_rle_read"
    rletopnm "$base.np.rle" > "$base.np.$ext"
    same "$base.np.$ext" "$base.ours.$ext" "pnmtorle $f: tb_rle_read vs rletopnm"
    # us -> netpbm
    "$tool" frompnm "$f" "$base.tb.rle"
    rletopnm "$base.tb.rle" > "$base.back.$ext"
    same "$f" "$base.back.$ext" "tb_rle_write $f, read by rletopnm"
done

# The comment pnmtorle writes (HISTORY=...) becomes an attribute.
"$tool" attrs madras.np.rle > attrs.txt
checks=$((checks + 1))
if ! grep -q '^HISTORY=pnmtorle' attrs.txt; then
    echo "FAIL: pnmtorle's HISTORY comment is not an attribute:"; cat attrs.txt
    fails=$((fails + 1))
fi

# ---- alpha, colour: pnmtorle -alpha makes black pixels transparent
pnmtorle -alpha madras.ppm > madras.alpha.rle
"$tool" topnm madras.alpha.rle madras.alpha.ours.ppm madras.alpha.ours.pgm
rletopnm --alphaout=madras.alpha.np.pgm madras.alpha.rle > madras.alpha.np.ppm
same madras.ppm madras.alpha.ours.ppm "pnmtorle -alpha: colour"
same madras.alpha.np.pgm madras.alpha.ours.pgm "pnmtorle -alpha: alpha, tb_rle_read vs rletopnm"
# ... and our alpha out through rletopnm --alphaout
pgmnoise -randomseed=9 37 9 > alpha37.pgm
"$tool" frompnm noise.ppm noise.alpha.tb.rle alpha37.pgm
rletopnm --alphaout=noise.alpha.back.pgm noise.alpha.tb.rle > noise.alpha.back.ppm
same noise.ppm noise.alpha.back.ppm "tb_rle_write RGBA: colour via rletopnm"
same alpha37.pgm noise.alpha.back.pgm "tb_rle_write RGBA: alpha via rletopnm --alphaout"

# ---- alpha, grey: rletopnm's grey alpha output reads the wrong channel, so
# the expected mask (black -> 0, else 255, pnmtorle's rule) comes from Python.
pnmtorle -alpha checker.pgm > checker.alpha.rle
"$tool" topnm checker.alpha.rle checker.alpha.ours.pgm checker.alpha.ours.a.pgm
same checker.pgm checker.alpha.ours.pgm "pnmtorle -alpha grey: grey"
python3 - checker.pgm checker.alpha.want.pgm <<'EOF'
import sys
data = open(sys.argv[1], 'rb').read()
head, tokens, i = [], [], 0
while len(tokens) < 4:          # P5 W H MAXVAL, whitespace separated
    while data[i:i+1].isspace(): i += 1
    j = i
    while not data[j:j+1].isspace(): j += 1
    tokens.append(data[i:j]); i = j
i += 1
w, h = int(tokens[1]), int(tokens[2])
pix = data[i:i + w * h]
open(sys.argv[2], 'wb').write(b'P5\n%d %d\n255\n' % (w, h) + bytes(0 if p == 0 else 255 for p in pix))
EOF
same checker.alpha.want.pgm checker.alpha.ours.a.pgm "pnmtorle -alpha grey: alpha"

# ---- hand-built files: colour maps, background, long opcodes
python3 "$src/rle_craft.py" interop craft > /dev/null
for f in craft/*.rle; do
    base=${f%.rle}
    rletopnm "$f" > "$base.np.pnm"
    "$tool" topnm "$f" "$base.ours.pnm"
    same "$base.np.pnm" "$base.ours.pnm" "hand-built $(basename "$f"): tb_rle_read vs rletopnm"
done
rletopnm --alphaout=craft/rgba.np.a.pgm craft/rgba.rle > /dev/null
"$tool" topnm craft/rgba.rle craft/rgba.ours2.pnm craft/rgba.ours.a.pgm
same craft/rgba.np.a.pgm craft/rgba.ours.a.pgm "hand-built rgba.rle: alpha"

# ---- the same files through `testbed convert` (format chosen by extension)
"${TESTBED:?}" convert madras.np.rle madras.conv.rle --linear
rletopnm madras.conv.rle > madras.conv.ppm
same madras.ppm madras.conv.ppm "testbed convert --linear: pnmtorle file -> rle -> rletopnm"
# default sRGB: decoding and re-encoding 8-bit codes is exact, so PNG holds the same codes
"$TESTBED" convert madras.alpha.rle madras.conv.png
pngtopam -alphapam madras.conv.png | pamchannel -infile=- 0 1 2 | pamtopnm -assume > madras.conv2.ppm
same madras.ppm madras.conv2.ppm "testbed convert: pnmtorle -alpha file -> png, colour"
pngtopam -alphapam madras.conv.png | pamchannel -infile=- 3 | pamtopnm -assume > madras.conv2.pgm
same madras.alpha.np.pgm madras.conv2.pgm "testbed convert: pnmtorle -alpha file -> png, alpha"

echo "$checks checks, $fails failed"
[ "$fails" -eq 0 ]
