#!/bin/sh
# Script test: the POV-Ray suite's scene pairs (tools/bench/pov/) agree.
# Every committed .pov must be what tools/bench/mid2pov.py writes from its
# .mid, and (with povray installed) both renders at 200 x 150 must match
# statistically (tools/bench/pov-suite.sh --check: SSIM and mean value).
# The check must also be able to fail: an edited .pov and an SSIM bound of
# 0.9999 (two renderers' noise never meets it) are caught. Skips (77) when
# povray is not installed (tools/setup.sh --bench), after the .pov check.
set -eu
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}"
tmp=${TB_TEST_TMPDIR:-${TMPDIR:-/tmp}}/pov-suite-test.$$
mkdir -p "$tmp"
trap 'rm -rf "$tmp"' EXIT INT TERM
suite="$TB_SOURCE_DIR/tools/bench/pov-suite.sh"

# An edited .pov is reported (no povray needed).
mkdir -p "$tmp/edited"
cp "$TB_SOURCE_DIR"/tools/bench/pov/classic.* "$tmp/edited/"
echo "// edited" >> "$tmp/edited/classic.pov"
if SUITE="$tmp/edited" bash "$suite" --check --only classic "$tmp/o1" >"$tmp/log1" 2>&1; then
    echo "FAIL: an edited classic.pov passed the check"; cat "$tmp/log1"; exit 1
fi
grep -q "is not what mid2pov.py writes" "$tmp/log1" || { echo "FAIL: no message for the edited .pov"; cat "$tmp/log1"; exit 1; }

# The whole suite.
set +e
bash "$suite" --check "$tmp/o2" >"$tmp/log2" 2>&1
rc=$?
set -e
cat "$tmp/log2"
[ "$rc" -eq 77 ] && exit 77
[ "$rc" -eq 0 ] || { echo "FAIL: pov-suite.sh --check exited $rc"; exit 1; }
[ "$(grep -c ': ok$' "$tmp/log2")" -eq 6 ] || { echo "FAIL: not six scenes compared"; exit 1; }

# A bound no pair of renders meets fails.
if POV_SSIM_MIN=0.9999 bash "$suite" --check --only classic "$tmp/o3" >"$tmp/log3" 2>&1; then
    echo "FAIL: SSIM >= 0.9999 passed"; cat "$tmp/log3"; exit 1
fi
grep -q "FAIL" "$tmp/log3" || { echo "FAIL: no FAIL line for SSIM >= 0.9999"; cat "$tmp/log3"; exit 1; }
echo "pov-suite check: ok"
