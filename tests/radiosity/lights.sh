#!/bin/sh
# Lights in `testbed render --method radiosity` (docs/radiosity.md, "Lights"),
# end to end, against an independent renderer: tests/radiosity/lights.mid is a
# diffuse floor under a point, a spot (wide falloff) and a directional light;
# a plane does not see itself, so the radiosity solution is the direct light
# alone and its image must match the ray tracer's (`testbed render --method
# raytrace`, radiance rho E / pi) up to the Gouraud interpolation of the mesh
# (measured: RMS 0.23% and largest 2.6% of the peak radiance 0.373, at the
# spot's falloff band). Also: the lights' power in --stats (4 pi I, the spot's
# cone, pi R^2 E through the mesh's bounding sphere) and its bookkeeping, the
# same CSV bytes for 1 and 2 threads, and --help.
set -u
NAME=radiosity_lights; . "$TB_SOURCE_DIR/tests/radiosity/rad_cli.sh"
SCENE="$TB_SOURCE_DIR/tests/radiosity/lights.mid"

"$TESTBED" render "$SCENE" -o "$T/rt.pfm" --spp 16 > "$T/o1" 2>&1 || { cat "$T/o1"; fail "ray tracer"; }
"$TESTBED" render "$SCENE" --method radiosity --max-edge 0.15 --spp 16 --threshold 1e-4 --threads 1 -o "$T/rad.pfm" \
    --patches "$T/a.csv" --stats "$T/s.json" > "$T/o2" 2>&1 || { cat "$T/o2"; fail "radiosity"; }
grep -q "3 point, spot or directional lights shot directly" "$T/o2" || { cat "$T/o2"; fail "no note on the lights"; }
"$TESTBED" compare "$T/rad.pfm" "$T/rt.pfm" --json > "$T/cmp.json" || fail "compare"
grep '"all"' "$T/cmp.json" | sed 's/.*"rmse": \([^,]*\),.*"max_abs": \([^,]*\),.*/\1 \2/' > "$T/err"
read rmse maxabs < "$T/err"
echo "radiosity vs ray tracer: RMSE $rmse, largest $maxabs (peak radiance 0.373)"
awk -v r="$rmse" -v m="$maxabs" 'BEGIN { exit !(r < 0.002 && m < 0.015) }' ||
    fail "radiosity and ray-traced images differ: RMSE $rmse (< 0.002), largest $maxabs (< 0.015)"

# power: point 4 pi (2 + 1.5 + 1); spot 2 pi ((1 - cos 10) + (cos 10 - cos 40) / 2) (3 + 3 + 4);
# directional pi R^2 (0.3 + 0.3 + 0.2), R = half the diagonal of the 6 x 6 floor
val() { sed -n "s/.*\"$1\": \([^,]*\),*/\1/p" "$T/s.json"; }
awk -v e="$(val power_emitted)" -v a="$(val power_absorbed)" -v u="$(val power_unshot)" -v x="$(val power_escaped)" '
BEGIN {
    pi = atan2(0, -1); d = pi / 180
    want = 4 * pi * 4.5 + 2 * pi * ((1 - cos(10 * d)) + (cos(10 * d) - cos(40 * d)) / 2) * 10 + pi * 18 * 0.8
    if (e - want > 1e-5 * want || want - e > 1e-5 * want) { print "emitted " e ", want " want; exit 1 }
    s = e - a - u - x
    if (s > 1e-9 * e || -s > 1e-9 * e) { print "emitted - absorbed - unshot - escaped = " s; exit 1 }
}' || fail "power bookkeeping"

"$TESTBED" render "$SCENE" --method radiosity --max-edge 0.15 --threshold 1e-4 --threads 2 --patches "$T/b.csv" \
    > "$T/o3" 2>&1 || { cat "$T/o3"; fail "radiosity, 2 threads"; }
cmp -s "$T/a.csv" "$T/b.csv" || fail "1 and 2 threads give different CSV bytes"
"$TESTBED" render --method radiosity --help | grep -q "point, spot and directional lights" || fail "--help"
rm -rf "$T"
echo "radiosity lights: ok"
