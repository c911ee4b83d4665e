#!/bin/sh
# tools/examples/raytrace.c, the Whitted ray tracer in public calls (surface.h),
# equals `testbed render` (the ray tracer) statistically: the Cornell box (and
# the spheres box: mirror, glass) at 64 x 64, each program twice with two
# seeds; the mean of the image and of each of 4 x 4 regions agree within
# 4.5 standard errors, the standard error of a region estimated per pixel
# from the difference of a program's two runs. (Both scenes have only
# Lambert and Phong materials, which the example shades as the command does.)
#   rt_example.sh EXAMPLE  (with TESTBED, TB_SOURCE_DIR, TB_TEST_TMPDIR set)
set -u
EXAMPLE=$1
T="${TB_TEST_TMPDIR:-/tmp}/rt_example.$$"
rm -rf "$T" && mkdir -p "$T"
fail() { echo "FAIL: $*"; exit 1; }
SPP=${TB_RT_EXAMPLE_SPP:-16}
for scene in cornell-box cornell-box-spheres; do
    sed 's/resolution = \[512 512\]/resolution = [64 64]/' "$TB_SOURCE_DIR/scenes/$scene.mid" > "$T/$scene.mid"
    grep -q "resolution = \[64 64\]" "$T/$scene.mid" || fail "$scene: no 512 x 512 resolution to shrink"
    for seed in 1 2; do
        "$EXAMPLE" "$T/$scene.mid" "$T/ex$seed.pfm" "$SPP" "$seed" > "$T/out" 2>&1 || { cat "$T/out"; fail "example"; }
        "$TESTBED" render "$T/$scene.mid" --backend cpu --spp "$SPP" --seed "$seed" -o "$T/cmd$seed.pfm" \
            > "$T/out" 2>&1 || { cat "$T/out"; fail "command"; }
    done
    python3 - "$T" "$scene" <<'PY' || fail "$scene: the example and the command differ"
import math, struct, sys
d, scene = sys.argv[1], sys.argv[2]
def pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        v = struct.unpack(("<" if scale < 0 else ">") + "%df" % (w * h * 3), f.read())
    return w, h, [v[3 * i] + v[3 * i + 1] + v[3 * i + 2] for i in range(w * h)]  # R + G + B
w, h, a1 = pfm(d + "/ex1.pfm"); _, _, a2 = pfm(d + "/ex2.pfm")
_, _, b1 = pfm(d + "/cmd1.pfm"); _, _, b2 = pfm(d + "/cmd2.pfm")
assert a1 != a2 and b1 != b2, "the seed changes nothing"
def region(x0, y0, x1, y1):
    idx = [y * w + x for y in range(y0, y1) for x in range(x0, x1)]
    n = len(idx)
    ma = sum(a1[i] + a2[i] for i in idx) / (2 * n)
    mb = sum(b1[i] + b2[i] for i in idx) / (2 * n)
    # per-pixel noise variance from two runs: E (x1 - x2)^2 = 2 s^2; mean of 2n samples: s^2 / (2n)
    va = sum((a1[i] - a2[i]) ** 2 for i in idx) / (2 * n) / (2 * n)
    vb = sum((b1[i] - b2[i]) ** 2 for i in idx) / (2 * n) / (2 * n)
    return ma, mb, math.sqrt(va + vb)
worst = 0.0
regions = [(0, 0, w, h)] + [(x, y, x + w // 4, y + h // 4) for y in range(0, h, h // 4) for x in range(0, w, w // 4)]
for r in regions:
    ma, mb, sd = region(*r)
    z = abs(ma - mb) / sd if sd > 0 else (0.0 if ma == mb else float("inf"))
    worst = max(worst, z)
    assert z <= 4.5, ("region", r, ma, mb, sd, z)
ma, mb, sd = region(0, 0, w, h)
print("%s: example %.5f, command %.5f (+- %.5f); worst region %.2f sigma" % (scene, ma, mb, sd, worst))
PY
done
rm -rf "$T"
