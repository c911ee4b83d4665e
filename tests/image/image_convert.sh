#!/usr/bin/env bash
# `testbed convert` end to end: help, usage errors (exit 2), failures (exit 1,
# no output file), every pair of formats (RLE, PNG, PFM, EXR float and half)
# keeping 8-bit codes exactly, exposure, and attributes carried across.
set -uo pipefail
: "${TESTBED:?}" "${TB_TEST_TMPDIR:?}"
T="$TB_TEST_TMPDIR/image_convert"
rm -rf "$T"
mkdir -p "$T"
cd "$T" || exit 1

failures=0
fail() { echo "FAIL: $*" >&2; failures=$((failures + 1)); }

# expect STATUS PATTERN ARGS...: `testbed convert ARGS` exits with STATUS and
# its stderr (or stdout for status 0) matches PATTERN.
expect() {
    local want=$1 pattern=$2
    shift 2
    "$TESTBED" convert "$@" > out.txt 2> err.txt
    local got=$?
    if [[ $got != "$want" ]]; then
        fail "convert $*: exit $got, expected $want; stderr: $(cat err.txt)"
    elif [[ $want == 0 ]]; then
        grep -Eq -- "$pattern" out.txt || fail "convert $*: stdout lacks '$pattern'"
    else
        grep -Eq -- "$pattern" err.txt || fail "convert $*: stderr lacks '$pattern': $(cat err.txt)"
    fi
}

# An 8-bit reference with every code from 0 to 255 somewhere.
awk 'BEGIN { w = 16; h = 6; print "P3"; print w, h; print 255;
  for (y = 0; y < h; y++) { line = "";
    for (x = 0; x < w; x++) for (c = 0; c < 3; c++) line = line " " ((y * 48 + x * 3 + c) % 256);
    print line } }' > base.ppm
pnmtopng base.ppm > base.png
pnmtoplainpnm base.ppm | tr -s ' \n' '\n\n' > base.nums

# check IMAGE WHAT: IMAGE, converted back to PNG, holds base.ppm's codes.
check() {
    if ! "$TESTBED" convert "$1" check.png 2> err.txt; then
        fail "$2: cannot convert $1 back to PNG: $(cat err.txt)"
        return
    fi
    pngtopnm check.png | pnmtoplainpnm | tr -s ' \n' '\n\n' > check.nums
    cmp -s base.nums check.nums || fail "$2: pixels differ from the original"
}

# --- help and usage errors
expect 0 '^usage: testbed convert IN OUT' --help
expect 0 '^usage: testbed convert' -h
"$TESTBED" help convert | grep -q '^usage: testbed convert' || fail "testbed help convert"
"$TESTBED" help | grep -Eq '^ +convert +convert an image' || fail "convert missing from testbed help"
expect 2 'need an input and an output'
expect 2 'need an input and an output' base.png
expect 2 "unexpected argument 'b.png'" base.png a.png b.png
expect 2 "unknown option '--frobnicate'" base.png a.png --frobnicate
expect 2 'unknown option' base.png a.png -x
expect 2 "bits: expected one of 8, 16, got '12'" base.png a.png --bits 12
expect 2 "bits: expected one of 8, 16, got 'abc'" base.png a.png --bits=abc
expect 2 'bits: missing value 8|16' base.png a.png --bits
expect 2 'exposure: expected a number in \[-100, 100\]' base.png a.png --exposure 1.5x
expect 2 'exposure: expected a number' base.png a.png --exposure=nan
expect 2 'exposure: expected a number' base.png a.png --exposure 1e9
expect 2 'exposure: missing value STOPS' base.png a.png --exposure
expect 2 'bits applies to PNG output only' base.png a.exr --bits 16
expect 2 'half applies to OpenEXR output only' base.png a.png --half
expect 2 'cannot tell the format' base.png a.jpg
expect 2 'cannot tell the format' base.gif a.png
grep -q '^testbed convert: error: ' err.txt || fail "usage errors start with 'testbed convert: error: '"
ls a.* > /dev/null 2>&1 && fail "a usage error left an output file"

# --- failures: exit 1, a message naming the file, and no output file
expect 1 '^testbed convert: error: .*missing\.png' missing.png out1.png
printf 'PF\n4 4\n-1\n' > short.pfm
expect 1 'short\.pfm.*truncated' short.pfm out1.png
printf 'not an image' > junk.exr
expect 1 'junk\.exr' junk.exr out1.png
expect 1 'no/such/dir' base.png no/such/dir/out.png
pnmtopng -alpha=<(ppmtopgm base.ppm) base.ppm > base_rgba.png
expect 1 'PFM stores 1 \(grey\) or 3 \(RGB\) channels' base_rgba.png out1.pfm
ls out1.* > /dev/null 2>&1 && fail "a failed conversion left an output file"
ls ./*.tmp.* > /dev/null 2>&1 && fail "a failed conversion left a temporary file"

# --- every pair of formats keeps the 8-bit codes
formats=(rle png pfm exr)
for src in "${formats[@]}"; do
    "$TESTBED" convert base.png "src.$src" 2> err.txt || fail "png -> $src: $(cat err.txt)"
    check "src.$src" "png -> $src"
    for dst in "${formats[@]}"; do
        "$TESTBED" convert "src.$src" "dst_$src.$dst" 2> err.txt || fail "$src -> $dst: $(cat err.txt)"
        check "dst_$src.$dst" "$src -> $dst"
    done
    "$TESTBED" convert --half "src.$src" "half_$src.exr" 2> err.txt || fail "$src -> half exr: $(cat err.txt)"
    check "half_$src.exr" "$src -> exr (half)"
done
echo "format pairs done"

# --- exposure: linear PFM values code/255 (codes <= 127), +1 stop -> codes doubled
awk 'BEGIN { print "P3"; print 8, 2; print 255;
  for (y = 0; y < 2; y++) { line = ""; for (x = 0; x < 24; x++) line = line " " ((y * 24 + x) * 5 % 128); print line } }' > low.ppm
awk 'BEGIN { print "P3"; print 8, 2; print 255;
  for (y = 0; y < 2; y++) { line = ""; for (x = 0; x < 24; x++) line = line " " (2 * ((y * 24 + x) * 5 % 128)); print line } }' > doubled.ppm
pamtopfm low.ppm > low.pfm
"$TESTBED" convert --linear --exposure 1 low.pfm bright.png || fail "exposure conversion"
cmp -s <(pngtopnm bright.png | pnmtoplainpnm | tr -s ' \n' '\n\n') \
       <(pnmtoplainpnm doubled.ppm | tr -s ' \n' '\n\n') || fail "--exposure 1 did not double the values"
pamtopfm doubled.ppm > doubled.pfm
"$TESTBED" convert --linear --exposure=-1 doubled.pfm dim.png || fail "negative exposure conversion"
cmp -s <(pngtopnm dim.png | pnmtoplainpnm | tr -s ' \n' '\n\n') \
       <(pnmtoplainpnm low.ppm | tr -s ' \n' '\n\n') || fail "--exposure=-1 did not halve the values"
echo "exposure done"

# --- attributes: PNG text -> EXR -> RLE -> PNG; PFM drops them with a note
printf 'Title Cornell box\nSource testbed 1991\n' > text.txt
pnmtopng -text text.txt base.ppm > text.png
"$TESTBED" convert text.png text.exr || fail "text png -> exr"
"$TESTBED" convert text.exr text.rle || fail "text exr -> rle"
"$TESTBED" convert text.rle text_back.png || fail "text rle -> png"
pngtopam -text=back.txt text_back.png > /dev/null
grep -Eq '^Title +Cornell box$' back.txt || fail "Title attribute lost: $(cat back.txt)"
grep -Eq '^Source +testbed 1991$' back.txt || fail "Source attribute lost: $(cat back.txt)"
"$TESTBED" convert text.exr text.pfm 2> err.txt || fail "text exr -> pfm"
grep -q 'note: PFM files hold no attributes; 2 not copied' err.txt || fail "no note about dropped attributes"

# --- a failed write keeps the old output
printf 'old' > keep.pfm
"$TESTBED" convert base_rgba.png keep.pfm 2> /dev/null && fail "RGBA -> PFM accepted"
[[ $(cat keep.pfm) == old ]] || fail "failed conversion changed the existing output"

if ((failures)); then
    echo "$failures failure(s)"
    exit 1
fi
echo "all convert checks passed"
