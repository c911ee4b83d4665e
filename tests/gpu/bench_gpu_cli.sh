#!/usr/bin/env bash
# `testbed bench gpu` end to end on lavapipe: the device list with the one
# measured marked, its limits, per-kernel timestamp lines whose Mrays/s is
# the ray count over the device time they print; the untimed path when the
# queue has no timestamps (TB_GPU_NO_TIMESTAMPS); a bad --device index; no
# driver. No timing is asserted, only that the figures are consistent.
set -u
tb=${TESTBED:?} tmp=${TB_TEST_TMPDIR:-/tmp}/gpu_bench_gpu_cli.$$
mkdir -p "$tmp"
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
scene=${TB_SOURCE_DIR:?}/scenes/cornell-box.mid

TB_VK_VALIDATION=1 "$tb" bench gpu "$scene" --rays 3000 --repeat 2 --device 0 >"$tmp/out.txt" 2>"$tmp/err.txt" ||
    { cat "$tmp/out.txt" "$tmp/err.txt"; fail "bench gpu exited $?"; }
cat "$tmp/out.txt"
# The layer's messages go to stderr (LeakSanitizer's suppression summary may too).
grep -qiE 'VUID|validation|error' "$tmp/err.txt" && { cat "$tmp/err.txt"; fail "validation messages on stderr"; }
grep -q '^  \* 0  ' "$tmp/out.txt" || fail "device 0 not listed as the one measured"
grep -q '^device: .*subgroup .*workgroup [0-9]* (limit [0-9]* invocations), shared memory [0-9]* bytes' \
    "$tmp/out.txt" || fail "no limits line"
python3 - "$tmp/out.txt" <<'PY' || fail "kernel lines"
import re, sys
lines = open(sys.argv[1]).read().splitlines()
sets = 0
for i, l in enumerate(lines):
    m = re.match(r"^(primary|shadow|diffuse)\s+(\d+)\s+\S+\s+\S+\s+(\S+)", l)
    if not m:
        continue
    rays, kernel_rate = int(m.group(2)), float(m.group(3))
    k = re.match(r"^  kernel intersect\s+(\d+) dispatches per run, device time ([0-9.]+) ms per run .* ([0-9.]+) Mrays/s$",
                 lines[i + 1])
    assert k, lines[i + 1]
    ms, rate = float(k.group(2)), float(k.group(3))
    assert int(k.group(1)) >= 1 and ms > 0
    # The line's rate is rays over its device time, and the table's kernel column agrees.
    assert abs(rate - rays / (ms * 1e3)) <= 0.002 * rate + 0.0015, (rate, rays, ms)
    assert abs(kernel_rate - rate) <= 0.002 * rate + 0.0015, (kernel_rate, rate)
    sets += 1
assert sets == 3, sets
PY

TB_GPU_NO_TIMESTAMPS=1 "$tb" bench gpu "$scene" --rays 1000 --repeat 1 >"$tmp/nots.txt" 2>&1 ||
    { cat "$tmp/nots.txt"; fail "bench gpu without timestamps exited $?"; }
cat "$tmp/nots.txt"
grep -q '^kernel timestamps: not available' "$tmp/nots.txt" || fail "no 'not available' line"
grep -q 'no timestamps recorded' "$tmp/nots.txt" || fail "kernel lines without timestamps"
grep -q '^primary .* nan ' "$tmp/nots.txt" || fail "kernel column not nan"

"$tb" bench gpu "$scene" --rays 100 --device 7 >"$tmp/bad.txt" 2>&1
rc=$?
cat "$tmp/bad.txt"
[ $rc -ne 0 ] || fail "a bad --device exited 0"
grep -q -- '--device 7 does not exist (1 Vulkan device' "$tmp/bad.txt" || fail "bad --device message"

VK_ICD_FILENAMES=/nonexistent/tb.json VK_DRIVER_FILES=/nonexistent/tb.json \
    "$tb" bench gpu "$scene" --rays 100 >"$tmp/noicd.txt" 2>&1
rc=$?
cat "$tmp/noicd.txt"
[ $rc -ne 0 ] || fail "no driver exited 0"
grep -q 'no Vulkan driver' "$tmp/noicd.txt" || fail "no-driver message"
echo "bench gpu: device list, limits, kernel timestamps, no-timestamp path, bad index, no driver"
