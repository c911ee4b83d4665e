#!/bin/sh
# `testbed render --backend`: auto on lavapipe uses the CPU path and says
# why; without a Vulkan driver auto falls back with the reason and vulkan
# fails without writing an image; --device 0 runs Vulkan, a missing device
# fails; --backend metal is a usage error,
# --help lists the options;
# and a tile with more samples than a wavefront batch holds, rendered over
# two batches, gives the CPU's image. (The other image comparisons are in
# shade_cli.sh.)
set -eu
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}" "${TB_TEST_TMPDIR:?}"
. "$TB_SOURCE_DIR/tests/gpu/gpu_test.sh"
scratch_dir shade_backend
fail() { echo "FAIL: $*"; [ -f "$t/backend.err" ] && cat "$t/backend.err"; [ -f "$t/backend.out" ] && cat "$t/backend.out"; exit 1; }

sized "$TB_SOURCE_DIR/scenes/cornell-box-rgb.mid" "$t/backend.mid" 32 32

# More samples than a wavefront batch holds (65 536) in one tile: the tile is
# rendered in runs of rows over several batches; same image as the CPU.
sized "$TB_SOURCE_DIR/scenes/cornell-box-rgb.mid" "$t/split.mid" 20 8
"$TESTBED" render "$t/split.mid" -o "$t/split-cpu.pfm" --spp 600 --backend cpu >/dev/null 2>&1 || fail "cpu split"
"$TESTBED" render "$t/split.mid" -o "$t/split-vk.pfm" --spp 600 --backend vulkan >"$t/backend.out" 2>&1 ||
    fail "vulkan split"
grep -q " 2 waves" "$t/backend.out" || fail "the 20 x 8 image at 600 spp should take 2 batches of one wave"
e=$(nmse "$t/split-vk.pfm" "$t/split-cpu.pfm")
echo "20x8 600 spp (tiles split across batches): NMSE $e"
python3 -c "import sys; sys.exit(0 if $e <= 1e-4 else 1)" || fail "split: NMSE $e > 1e-4"

# Backend choice: auto on a CPU driver uses the CPU path and says why.
"$TESTBED" render "$t/backend.mid" -o "$t/auto.pfm" --backend auto >"$t/backend.out" 2>"$t/backend.err" ||
    fail "auto"
if grep -q "(CPU)" "$t/backend.err" || ! grep -q "backend vulkan" "$t/backend.err"; then
    grep -q "backend cpu: " "$t/backend.err" || fail "auto on lavapipe should say it uses the CPU path"
    if grep -q "hits shaded by the kernel" "$t/backend.out"; then fail "auto on lavapipe ran the kernel"; fi
fi
# --device N means Vulkan on that device (lavapipe too); a missing one fails.
"$TESTBED" render "$t/backend.mid" -o "$t/dev0.pfm" --device 0 >"$t/backend.out" 2>"$t/backend.err" || fail "--device 0"
grep -q "backend vulkan: device 0" "$t/backend.err" || fail "--device 0 should use Vulkan device 0"
grep -q "hits shaded by the kernel" "$t/backend.out" || fail "--device 0 did not run the kernel"
set +e
"$TESTBED" render "$t/backend.mid" -o "$t/dev9.pfm" --device 9 >"$t/backend.out" 2>"$t/backend.err"
rc=$?
set -e
[ $rc -ne 0 ] && [ ! -f "$t/dev9.pfm" ] || fail "--device 9 should fail without an image"
grep -q "device 9 does not exist" "$t/backend.err" || fail "no message for a missing device"
# No Vulkan driver: auto falls back with the reason, vulkan fails with it.
VK_ICD_FILENAMES=/nonexistent/tb-no-icd.json VK_DRIVER_FILES=/nonexistent/tb-no-icd.json \
    "$TESTBED" render "$t/backend.mid" -o "$t/noicd.pfm" >"$t/backend.out" 2>"$t/backend.err" ||
    fail "auto without a driver should fall back to the CPU path"
grep -q "backend cpu: .*driver" "$t/backend.err" || fail "no fallback reason without a driver"
[ -f "$t/noicd.pfm" ] || fail "no image from the fallback"
set +e
VK_ICD_FILENAMES=/nonexistent/tb-no-icd.json VK_DRIVER_FILES=/nonexistent/tb-no-icd.json \
    "$TESTBED" render "$t/backend.mid" -o "$t/noicd2.pfm" --backend vulkan >"$t/backend.out" 2>"$t/backend.err"
rc=$?
set -e
[ $rc -ne 0 ] || fail "--backend vulkan without a driver should fail"
grep -q "backend vulkan" "$t/backend.err" || fail "no --backend vulkan message"
[ ! -f "$t/noicd2.pfm" ] || fail "a failed vulkan render wrote an image"

# Usage and unsupported options.
set +e
"$TESTBED" render "$t/backend.mid" -o "$t/x.pfm" --backend metal >/dev/null 2>&1
[ $? -eq 2 ] || fail "--backend metal should be a usage error"
"$TESTBED" render "$t/backend.mid" -o "$t/x.pfm" --backend vulkan --sample-map "$t/x.png" >/dev/null 2>&1
rc=$?
set -e
[ $rc -eq 2 ] || fail "--sample-map to a PNG should be a usage error"
[ ! -e "$t/x.pfm" ] || fail "a usage error wrote an image"
"$TESTBED" render --help | grep -q -- "--backend B" || fail "--backend not in --help"
"$TESTBED" render --help | grep -q -- "--device N" || fail "--device not in --help"
echo "ok"
