#!/bin/sh
# Adaptive antialiasing on the Vulkan renderer (docs/gpu.md, "Adaptive
# antialiasing"): `testbed render --backend vulkan --adaptive` against
# `--backend cpu --adaptive` on scenes with edges (the spectral Cornell box
# with the stderr criterion, its RGB twin with Mitchell's contrast, the
# MID 1.1 materials scene) under the validation layer: the per-pixel sample
# counts (--sample-map) equal to the CPU's but for at most a few pixels
# whose criterion sits at the threshold (docs/accuracy.md), image NMSE within
# the tolerance; the counts really adaptive (not the uniform map of a
# non-adaptive render, so a Vulkan path that ignored --adaptive fails);
# rounds larger than one wavefront call; the same image and map for
# --threads 1 and 2.
set -eu
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}" "${TB_TEST_TMPDIR:?}"
. "$TB_SOURCE_DIR/tests/gpu/gpu_test.sh"
scratch_dir shade_adaptive
fail() { echo "FAIL: $*"; [ -f "$t/ad.err" ] && cat "$t/ad.err"; [ -f "$t/ad.out" ] && cat "$t/ad.out"; exit 1; }

# name, size, options: the counts may differ in at most MAXDIFF pixels
check() {
    name=$1 w=$2 h=$3
    shift 3
    sized "$TB_SOURCE_DIR/scenes/$name.mid" "$t/$name.mid" "$w" "$h"
    "$TESTBED" render "$t/$name.mid" -o "$t/$name-cpu.pfm" --sample-map "$t/$name-cpu-map.pfm" --backend cpu "$@" \
        >/dev/null 2>"$t/ad.err" || fail "cpu adaptive render of $name"
    TB_VK_VALIDATION=1 "$TESTBED" render "$t/$name.mid" -o "$t/$name-vk.pfm" --sample-map "$t/$name-vk-map.pfm" \
        --backend vulkan --threads 2 --stats "$t/$name.json" "$@" >"$t/ad.out" 2>"$t/ad.err" ||
        fail "vulkan adaptive render of $name"
    if grep -q "vulkan validation \|VUID" "$t/ad.err"; then fail "validation messages ($name)"; fi
    grep -q '"pixels_refined"' "$t/$name.json" || fail "no pixels_refined in --stats ($name)"
    set -- $(mapcmp "$t/$name-vk-map.pfm" "$t/$name-cpu-map.pfm")
    diff=$1 tvk=$2 tcpu=$3 lo=$4 hi=$5 npix=$6
    e=$(nmse "$t/$name-vk.pfm" "$t/$name-cpu.pfm")
    echo "$name ${w}x$h: vulkan vs cpu: $diff of $npix pixels with other sample counts, samples $tvk vs $tcpu" \
        "(per pixel $lo..$hi), NMSE $e"
    [ "$diff" -le "$MAXDIFF" ] || fail "$name: $diff pixels with other sample counts (> $MAXDIFF)"
    python3 -c "import sys; sys.exit(0 if $e <= $TOL else 1)" || fail "$name: NMSE $e > $TOL"
    # really adaptive: some pixels at the first round only, some refined,
    # unlike the uniform map of a non-adaptive render
    [ "$lo" -lt "$hi" ] || fail "$name: every pixel has $lo samples: not adaptive"
    "$TESTBED" render "$t/$name.mid" -o "$t/$name-uni.pfm" --sample-map "$t/$name-uni-map.pfm" --backend vulkan \
        --spp "$SPP" >/dev/null 2>"$t/ad.err" || fail "vulkan uniform render of $name"
    set -- $(mapcmp "$t/$name-uni-map.pfm" "$t/$name-cpu-map.pfm")
    [ "$1" -gt $((npix / 20)) ] || fail "$name: the adaptive counts should differ from the uniform $SPP spp ($1 pixels)"
}

SPP=2 MAXDIFF=4 TOL=1e-4 check cornell-box 40 40 --spp 2 --adaptive
SPP=2 MAXDIFF=4 TOL=1e-4 check cornell-box-rgb 40 40 --spp 2 --adaptive 0.2 --aa-criterion contrast --max-spp 8
SPP=1 MAXDIFF=4 TOL=1e-4 check materials 40 40 --spp 1 --adaptive 0.02 --max-spp 8 --aa-pattern sobol

# Rounds larger than one wavefront call (65 536 samples): a 20 x 8 image at
# 600 spp per round, whose first tile's first round with its ring is 81 600
# samples, goes through in pieces; the counts, the --stats figures
# (samples, ring samples, refined pixels, largest count) and the image are
# the CPU's.
sized "$TB_SOURCE_DIR/scenes/cornell-box-rgb.mid" "$t/split.mid" 20 8
for b in cpu vulkan; do
    "$TESTBED" render "$t/split.mid" -o "$t/split-$b.pfm" --sample-map "$t/split-$b-map.pfm" --stats "$t/split-$b.json" \
        --spp 600 --adaptive 0.005 --max-spp 1800 --backend $b >"$t/ad.out" 2>"$t/ad.err" || fail "$b split render"
done
set -- $(mapcmp "$t/split-vulkan-map.pfm" "$t/split-cpu-map.pfm")
[ "$1" -eq 0 ] && [ "$4" -eq 600 ] && [ "$5" -eq 1800 ] ||
    fail "split: $1 pixels with other counts, counts $4..$5 (expected 0, 600..1800)"
for k in samples ring_samples pixels_refined max_spp_used; do
    a=$(grep "\"$k\"" "$t/split-cpu.json") b=$(grep "\"$k\"" "$t/split-vulkan.json")
    [ -n "$a" ] && [ "$a" = "$b" ] || fail "split: --stats $k: cpu '$a', vulkan '$b'"
done
e=$(nmse "$t/split-vulkan.pfm" "$t/split-cpu.pfm")
echo "20x8, 600 spp per round in pieces: counts equal, NMSE $e"
python3 -c "import sys; sys.exit(0 if $e <= 1e-4 else 1)" || fail "split: NMSE $e > 1e-4"

# Thread-count independence: the same image and map with 1 and 2 threads.
for n in 1 2; do
    "$TESTBED" render "$t/materials.mid" -o "$t/th$n.pfm" --sample-map "$t/th$n-map.pfm" --backend vulkan \
        --threads $n --spp 1 --adaptive 0.02 --max-spp 8 --aa-pattern sobol >/dev/null 2>"$t/ad.err" ||
        fail "vulkan render with $n threads"
done
cmp -s "$t/th1.pfm" "$t/th2.pfm" || fail "--threads 1 and 2 give different images"
cmp -s "$t/th1-map.pfm" "$t/th2-map.pfm" || fail "--threads 1 and 2 give different sample maps"
echo "ok"
