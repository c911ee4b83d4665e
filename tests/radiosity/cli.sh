#!/bin/sh
# `testbed render --method radiosity` end to end (docs/radiosity.md): the
# white furnace through --patches (every element B = E / (1 - rho) = 2 with
# the ambient term left out, to the threshold and the form-factor error),
# the exact CSV columns, the same bytes with 1 and 2 threads, --report with
# --reference, --mesh-out PLY, the default element size, and bad options: a clear message, a non-zero
# exit and no file left behind.
set -u
NAME=radiosity_cli; . "$TB_SOURCE_DIR/tests/radiosity/rad_cli.sh"

# --- the furnace, 1 and 2 threads
rad "$FURNACE" --max-edge 0.25 --samples 16 --threshold 1e-3 --threads 1 --patches "$T/a.csv" \
    --mesh-out "$T/a.ply" --stats "$T/a.json" > "$T/out1" 2>&1 || { cat "$T/out1"; fail "furnace run"; }
rad "$FURNACE" --max-edge 0.25 --samples 16 --threshold 1e-3 --threads 2 --patches "$T/b.csv" > "$T/out2" 2>&1 ||
    { cat "$T/out2"; fail "furnace run, 2 threads"; }
cmp -s "$T/a.csv" "$T/b.csv" || fail "1 and 2 threads give different CSV bytes"
head -1 "$T/a.csv" | grep -qx 'element,object,area,cx,cy,cz,nx,ny,nz,b_r,b_g,b_b,u_r,u_g,u_b' ||
    fail "CSV header: $(head -1 "$T/a.csv")"
# 6 faces of 4 x 4 elements; object k is face k (floor z=0, ceiling z=1, y=0, y=1, x=0, x=1)
awk -F, 'NR > 1 {
    n++
    if ($1 != NR - 2) { print "element column " $1 " at row " NR; bad = 1 }
    axis = ($2 < 2) ? 6 : ($2 < 4) ? 5 : 4; side = $2 % 2
    if ($axis + 0 != side) { print "object " $2 " centroid " $4 " " $5 " " $6; bad = 1 }
    if ($10 < 2 * (1 - 0.03) || $10 > 2 * (1 + 0.03)) { print "B = " $10 " at element " $1; bad = 1 }
}
END { if (n != 96) { print n " rows"; bad = 1 } exit bad }' "$T/a.csv" || fail "furnace CSV"
head -c 3 "$T/a.ply" | grep -q ply || fail "PLY header"
grep -q '"shots"' "$T/a.json" || fail "stats JSON has no shots"

# --- --report against a reference: the NRMSE column ends below where it starts
rad "$FURNACE" --max-edge 0.25 --samples 8 --threshold 1e-2 --patches "$T/c.csv" --report "$T/r.csv" \
    --reference "$T/a.csv" > /dev/null 2>&1 || fail "report run"
head -1 "$T/r.csv" | grep -qx 'seconds,shots,shots_per_n,unshot_fraction,nrmse,nrmse_ambient' || fail "report header"
awk -F, 'NR == 2 { first = $5; f0 = $4 } NR > 2 { last = $5; fl = $4 }
END { if (!(NR >= 3 && last < first && fl < f0 && f0 == 1)) exit 1 }' "$T/r.csv" || { cat "$T/r.csv"; fail "report rows"; }

# --- default element size: the bounding-box diagonal / 24 (Cornell box: 40.03 mm, 1322 elements) unless
# --max-edge or --max-area is given; --max-edge 0 keeps faces whole (16 elements)
CORNELL="$TB_SOURCE_DIR/scenes/cornell-box-rgb.mid"
nelem() { sed -n 's/.*radiosity on .*: \([0-9]*\) elements.*/\1/p' "$1"; }
rad "$CORNELL" --samples 4 --threshold 0.05 --patches "$T/d.csv" > "$T/d.out" 2>&1 || { cat "$T/d.out"; fail "default run"; }
grep -q "max edge 40.0309 (default: bounding-box diagonal / 24)" "$T/d.out" || { cat "$T/d.out"; fail "default size"; }
n=$(nelem "$T/d.out")
[ "$n" -ge 1000 ] && [ "$n" -le 2000 ] || fail "default Cornell mesh: $n elements"
rad "$CORNELL" --max-edge 40.0309 --max-shots 1 --patches "$T/e.csv" > "$T/e.out" 2>&1 || fail "--max-edge 40.0309 run"
[ "$(nelem "$T/e.out")" = "$n" ] || fail "--max-edge 40.0309: $(nelem "$T/e.out") elements, default $n"
rad "$CORNELL" --max-edge 0 --samples 4 --patches "$T/e.csv" > "$T/e.out" 2>&1 || fail "--max-edge 0 run (whole, slightly twisted faces)"
[ "$(nelem "$T/e.out")" = 16 ] && grep -q "faces whole" "$T/e.out" || { cat "$T/e.out"; fail "--max-edge 0"; }
rad "$CORNELL" --max-area 10000 --max-shots 1 --patches "$T/e.csv" > "$T/e.out" 2>&1 || fail "--max-area run"
grep -q "elements (max area 10000)" "$T/e.out" || { cat "$T/e.out"; fail "--max-area alone keeps the default edge"; }
# the default mesh resolves light and shadow on the floor (faces whole: one value); elements
# under the blocks see nothing, so count only lit ones: a spread from 10% to 100% of the brightest
awk -F, 'NR > 1 && $8 > 0.99 && $5 < 1 { b = $10 + $11 + $12; n++; v[n] = b; if (b > mx) mx = b }
END { for (i = 1; i <= n; i++) { if (v[i] > 0.1 * mx && v[i] < 0.5 * mx) dim++; if (v[i] > 0.9 * mx) lit++ }
      if (!(n > 150 && dim >= 10 && lit >= 10)) { print n " floor elements, " dim " dim, " lit " lit"; exit 1 } }' \
    "$T/d.csv" || fail "default Cornell floor is not resolved"

# the default keeps curved surfaces at the polygonizer's 15 degrees: a unit sphere on a 100 x 100 floor
# (edge 100 * sqrt(2) / 24 = 5.9, larger than the sphere) stays round, not an octahedron
cat > "$T/ball.mid" <<'MID'
mid 1
material "m" { diffuse = 0.5 emission = 1 }
polygons "floor" {
    geometry = { vertices = [[0 0 0] [100 0 0] [100 100 0] [0 100 0]] faces = [[0 1 2 3]] }
    rendering = { material = "m" }
}
sphere "ball" { transform = [translate([50 50 1])] rendering = { material = "m" } }
MID
rad "$T/ball.mid" --max-shots 1 --patches "$T/e.csv" > "$T/e.out" 2>&1 || { cat "$T/e.out"; fail "ball run"; }
nball=$(awk -F, 'NR > 1 && $2 == 1' "$T/e.csv" | wc -l)
[ "$nball" -ge 200 ] || fail "default mesh: the sphere has $nball elements"

# --- errors: message, exit status, no files
expect_fail() {
    want="$1"; shift
    rm -f "$T/x.csv" "$T/x.png" "$T/x.ply" "$T/x.json"
    rad "$@" > "$T/err" 2>&1
    st=$?
    [ "$st" -ne 0 ] || fail "no error for: $*"
    grep -q -- "$want" "$T/err" || { cat "$T/err"; fail "message for: $* (wanted '$want')"; }
    ls "$T" | grep -q '^x\.' && fail "a file was left behind by: $*"
    return 0
}
expect_fail "--samples" "$FURNACE" --samples 0 --patches "$T/x.csv"
expect_fail "--formfactor" "$FURNACE" --formfactor radiance --patches "$T/x.csv"
expect_fail "--threshold" "$FURNACE" --threshold 1.5 --patches "$T/x.csv"
expect_fail "--max-edge" "$FURNACE" --max-edge -1 --patches "$T/x.csv"
expect_fail "nothing to write" "$FURNACE"
expect_fail "no camera" "$FURNACE" -o "$T/x.png"
expect_fail "unknown mesh format" "$FURNACE" --mesh-out "$T/x.obj"
expect_fail "go together" "$FURNACE" --report "$T/x.csv" --patches "$T/x.json"
expect_fail "--hemicube-res is for" "$FURNACE" --hemicube-res 64 --patches "$T/x.csv"
expect_fail "nosuch.mid" "$T/nosuch.mid" --patches "$T/x.csv"
expect_fail "elements" "$FURNACE" --max-edge 0.5 --patches "$T/x.csv" --report "$T/x.json" --reference "$T/a.csv"
rad --help | grep -q -- "--formfactor" || fail "--help"
rm -rf "$T"
echo OK
