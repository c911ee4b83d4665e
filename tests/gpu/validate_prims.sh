#!/bin/sh
# `testbed validate` (the intersect kernel against the CPU path, tolerances of
# docs/accuracy.md, validation layer on) on every primitive kind the kernel
# places (pyramids, prisms of small, large and non-convex profiles, tori
# thick and thin, square and round arches) at unit scale, far from the
# origin and tiny, huge, and flattened; CSG trees with coincident faces;
# `testbed generate csg` and `grid` (every kind, random transforms): every
# object on the GPU, none routed.
set -eu
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}" "${TB_TEST_TMPDIR:?}"
. "$TB_SOURCE_DIR/tests/gpu/gpu_test.sh"
scratch_dir validate_prims
# prims TRANSFORM: the nine objects, each placed by translate(...) then TRANSFORM.
prims() {
    cat <<MID
mid 1
pyramid "pyr" { transform = [translate([-3 0 0]) $1] geometry = { top = 0 } }
pyramid "frustum" { transform = [translate([-3 3 0]) $1] geometry = { top = 0.4 caps = true } }
prism "hex" { transform = [translate([0 3 0]) $1] geometry = { sides = 6 caps = true } }
prism "many" { transform = [translate([3 3 0]) $1] geometry = { sides = 300 caps = true } }
prism "ell" { transform = [translate([3 -3 0]) $1] geometry = { profile = [[0 0] [1 0] [1 0.3] [0.3 0.3] [0.3 1] [0 1]] caps = true } }
prism "open" { transform = [translate([0 6 0]) $1] geometry = { profile = [[1 0] [0.2 0.2] [0 1] [-0.2 0.2] [-1 0] [-0.2 -0.2] [0 -1] [0.2 -0.2]] caps = false } }
torus "ring" { transform = [translate([0 0 0]) $1] geometry = { major = 1 minor = 0.25 } }
torus "thin" { transform = [translate([0 -3 0]) $1] geometry = { major = 1 minor = 0.01 } }
square_arch "sa" { transform = [translate([-3 -3 0]) $1] geometry = { width = 1 height = 1.5 } }
round_arch "ra" { transform = [translate([3 0 0]) $1] geometry = { width = 1 height = 1.5 } }
MID
}
n=0
for tr in "scale(1)" "scale(0.01) translate([1000 0 0])" "scale(0.001) translate([10000 0 0])" \
    "scale(1000) translate([0 0 -5000])" "scale([1 1 0.1]) rotate([1 1 0] 30)"; do
    prims "$tr" >"$t/prims.mid"
    validate_scene "$t/out" "$t/prims.mid" --rays 10000 --seed 5
    grep -q "routing: 10 objects on the GPU, 0 routed" "$t/out" || { echo "routed: $tr"; cat "$t/out"; exit 1; }
    n=$((n + 1))
done
# CSG trees: differences, intersections and unions of every family, nested,
# with coincident faces (A - A, A u A, a shared face) and a tangent cylinder.
cat >"$t/csg.mid" <<'MID'
mid 1
difference "cup" { transform = [translate([-3 -3 0])] cube { } sphere { transform = [scale(1.2)] } }
intersection "die" { transform = [translate([3 -3 0])] cube { } sphere { transform = [scale(1.3)] } }
union "snowman" { transform = [translate([0 3 0])] sphere { } sphere { transform = [translate([0 0 1])] } }
intersection "deep" { cube { } union { cylinder { transform = [scale([1 1 2])] } torus { geometry = { major = 1 minor = 0.5 } } } }
difference "same" { transform = [translate([3 3 0])] cube { } cube { } }
union "twins" { transform = [translate([-3 3 0])] cube { } cube { } }
difference "shared" { transform = [translate([3 0 0])] cube { } cube { transform = [translate([0 0 1])] } }
difference "arches" { transform = [translate([-3 0 0])] round_arch { geometry = { width = 1 height = 1.5 } } prism { geometry = { profile = [[0 0] [1 0] [1 0.3] [0.3 0.3] [0.3 1] [0 1]] caps = true } } }
union "far" { transform = [scale(0.01) translate([1000 0 0])] cone { } pyramid { geometry = { top = 0.3 caps = true } } square_arch { geometry = { width = 1 height = 1 } } }
MID
validate_scene "$t/out" "$t/csg.mid" --rays 10000 --seed 5
grep -q "routing: 9 objects on the GPU, 0 routed" "$t/out" || { echo "csg routed"; cat "$t/out"; exit 1; }
"$TESTBED" generate csg --count 100 --seed 3 -o "$t/gcsg.mid"
validate_scene "$t/out" "$t/gcsg.mid" --rays 10000 --seed 3
grep -q "routing: 100 objects on the GPU, 0 routed" "$t/out" || { echo "generated csg routed"; cat "$t/out"; exit 1; }
# Every kind with random parameters and transforms: nothing routed.
"$TESTBED" generate grid --count 100 --seed 7 -o "$t/grid.mid"
validate_scene "$t/out" "$t/grid.mid" --rays 10000 --seed 7
grep -q "routing: 100 objects on the GPU, 0 routed" "$t/out" || { echo "grid routed"; cat "$t/out"; exit 1; }
echo "validated $n primitive scenes, CSG trees and generated grid and csg scenes"
