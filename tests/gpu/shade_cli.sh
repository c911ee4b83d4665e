#!/bin/sh
# `testbed render --backend vulkan` (the wavefront renderer with the shade
# kernel, docs/gpu.md "Shade kernel and wavefront renderer") against
# `--backend cpu` on the Cornell box (spectral), its RGB twin and the MID 1.1
# materials scene (GGX lobes and glossy rays, checker and noise patterns,
# noise bumps) at 48 x 48, 4 spp, under the validation layer: image NMSE
# within docs/accuracy.md's tolerance (1e-4), the kernel shading every hit
# (none routed to the CPU path); a textured scene shaded by the kernel with
# each texture filter, and one whose texture has a black texel, routed to the
# CPU path (reported, same image); the same image for any thread count. (A tile split over batches, backend choice, fallbacks and
# usage errors: shade_backend.sh.)
set -eu
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}" "${TB_TEST_TMPDIR:?}"
. "$TB_SOURCE_DIR/tests/gpu/gpu_test.sh"
scratch_dir shade_cli
fail() { echo "FAIL: $*"; [ -f "$t/shade.err" ] && cat "$t/shade.err"; [ -f "$t/shade.out" ] && cat "$t/shade.out"; exit 1; }

for name in cornell-box cornell-box-rgb materials; do
    sized "$TB_SOURCE_DIR/scenes/$name.mid" "$t/$name.mid" 48 48
    "$TESTBED" render "$t/$name.mid" -o "$t/$name-cpu.pfm" --spp 4 --backend cpu >/dev/null 2>"$t/shade.err" ||
        fail "cpu render of $name"
    TB_VK_VALIDATION=1 "$TESTBED" render "$t/$name.mid" -o "$t/$name-vk.pfm" --spp 4 --backend vulkan \
        --stats "$t/$name.json" >"$t/shade.out" 2>"$t/shade.err" || fail "vulkan render of $name"
    if grep -q "vulkan validation \|VUID" "$t/shade.err"; then fail "validation messages ($name)"; fi
    grep -q "backend vulkan: " "$t/shade.err" || fail "no backend line ($name)"
    grep -q "vulkan: [1-9][0-9]* hits shaded by the kernel, 0 routed to the CPU path" "$t/shade.out" ||
        fail "the kernel should shade every hit of $name"
    grep -q '"gpu_shaded_hits"' "$t/$name.json" || fail "no gpu_shaded_hits in --stats ($name)"
    grep -q '"gpu_workgroup_size": [1-9]' "$t/$name.json" || fail "no device limits in --stats ($name)"
    e=$(nmse "$t/$name-vk.pfm" "$t/$name-cpu.pfm")
    echo "$name 48x48 4 spp: vulkan vs cpu NMSE $e"
    python3 -c "import sys; sys.exit(0 if $e <= 1e-4 else 1)" || fail "$name: NMSE $e > 1e-4"
    # Not trivially equal: another seed gives a different image (noise well above the tolerance).
    "$TESTBED" render "$t/$name.mid" -o "$t/$name-seed.pfm" --spp 4 --seed 9 --backend cpu >/dev/null 2>&1
    e2=$(nmse "$t/$name-seed.pfm" "$t/$name-cpu.pfm")
    python3 -c "import sys; sys.exit(0 if $e2 > 10 * $e and $e2 > 1e-4 else 1)" ||
        fail "$name: another seed should differ far more (NMSE $e2 vs $e)"
done

# Image textures: a textured floor (a 64 x 64 texture, so the footprints of
# the 48 x 32 pixels span from under a texel to several: every MIP level
# and the EWA ellipse) shaded by the kernel with each filter, the image the
# CPU's within the tolerance; then a texture with a black texel, routed to the
# CPU path with the reason (the image is the CPU's).
python3 - "$t/shade_tex.pfm" "$t/shade_black.pfm" <<'PY'
import struct, sys
def pfm(path, w, h, px):
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (w, h))
        f.write(struct.pack("<%df" % len(px), *px))
px = [0.1 + 0.8 * ((i * 37) % 101) / 101.0 for i in range(3 * 64 * 64)]
pfm(sys.argv[1], 64, 64, px)
pfm(sys.argv[2], 2, 2, [.9, .2, .2, 0, 0, 0, .2, .2, .9, .8, .8, .8])
PY
cat >"$t/shade_tex.mid" <<'EOF'
mid 1
camera "c" { eye = [0 -6 3] look_at = [0 0 0] up = [0 0 1] fov = 50 resolution = [48 32] }
polygons "floor" { geometry = { vertices = [[-4 -4 0] [4 -4 0] [4 4 0] [-4 4 0]] faces = [[0 1 2 3]] }
  rendering = { diffuse = 1 diffuse_texture = file("shade_tex.pfm") } }
sphere "ball" { transform = [scale(0.5) translate([0 0 0.5])] rendering = { diffuse = [0.8 0.4 0.2] } }
polygons "lamp" { geometry = { vertices = [[-0.5 -0.5 3] [-0.5 0.5 3] [0.5 0.5 3] [0.5 -0.5 3]] faces = [[0 1 2 3]] }
  rendering = { diffuse = 0 emission = [10 8 6] } }
point_light { position = [1 1 2] intensity = [5 4 3] }
EOF
for filter in ewa trilinear bilinear; do
    "$TESTBED" render "$t/shade_tex.mid" -o "$t/tex-cpu.pfm" --spp 1 --texture-filter $filter --backend cpu \
        >/dev/null 2>&1 || fail "cpu textured ($filter)"
    TB_VK_VALIDATION=1 "$TESTBED" render "$t/shade_tex.mid" -o "$t/tex-vk.pfm" --spp 1 --texture-filter $filter \
        --backend vulkan >"$t/shade.out" 2>"$t/shade.err" || fail "vulkan textured ($filter)"
    if grep -q "vulkan validation \|VUID" "$t/shade.err"; then fail "validation messages (textured, $filter)"; fi
    grep -q "vulkan: [1-9][0-9]* hits shaded by the kernel, 0 routed to the CPU path" "$t/shade.out" ||
        fail "textured hits should be shaded by the kernel ($filter)"
    e=$(nmse "$t/tex-vk.pfm" "$t/tex-cpu.pfm")
    echo "textured 48x32, $filter: NMSE $e"
    python3 -c "import sys; sys.exit(0 if $e <= 1e-4 else 1)" || fail "textured ($filter): NMSE $e > 1e-4"
done
sed 's/shade_tex.pfm/shade_black.pfm/' "$t/shade_tex.mid" >"$t/shade_black.mid"
"$TESTBED" render "$t/shade_black.mid" -o "$t/black-cpu.pfm" --spp 2 --backend cpu >/dev/null 2>&1 || fail "cpu black"
TB_VK_VALIDATION=1 "$TESTBED" render "$t/shade_black.mid" -o "$t/black-vk.pfm" --spp 2 --backend vulkan \
    >"$t/shade.out" 2>"$t/shade.err" || fail "vulkan black texel"
grep -q "[1-9][0-9]* routed to the CPU path (material [0-9]*: colour (pattern or image texture) black" "$t/shade.out" ||
    fail "hits on a texture with a black texel should be reported as routed"
e=$(nmse "$t/black-vk.pfm" "$t/black-cpu.pfm")
echo "texture with a black texel (routed) 48x32: NMSE $e"
python3 -c "import sys; sys.exit(0 if $e <= 1e-4 else 1)" || fail "black texel: NMSE $e > 1e-4"

# The host's loops run on OpenMP threads over distinct paths: the image does
# not depend on the thread count (the textured scene: kernel and routed hits;
# the materials scene: surface records of patterned hits built in parallel).
for f in shade_tex materials; do
    "$TESTBED" render "$t/$f.mid" -o "$t/thr1.pfm" --spp 1 --backend vulkan --threads 1 >/dev/null 2>&1 || fail "threads 1"
    "$TESTBED" render "$t/$f.mid" -o "$t/thr2.pfm" --spp 1 --backend vulkan --threads 2 >/dev/null 2>&1 || fail "threads 2"
    cmp -s "$t/thr1.pfm" "$t/thr2.pfm" || fail "$f: --threads 1 and 2 give different images"
done
echo "ok"
