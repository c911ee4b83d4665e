#!/bin/sh
# Script test: tools/bench/methods-error.sh --quick --check on both Cornell
# boxes (32 x 32, a 512-spp path-traced reference): the CSV is well formed
# (the header, every method and mode of the quick ladders on both scenes,
# times and errors finite and positive), the hybrid's relMSE at its largest
# budget is below the Whitted tracer's on the spheres box (--check, which
# this test also checks by itself from the CSV), the plots are a PNG and an
# SVG, the reference is cached (a second run renders none) and usage errors
# exit 2. Times are not checked.
set -eu
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}"
dir=$(mktemp -d "${TB_TEST_TMPDIR:-${TMPDIR:-/tmp}}/methods-error.XXXXXX")
trap 'rm -rf "$dir"' EXIT INT TERM
script=$TB_SOURCE_DIR/tools/bench/methods-error.sh
if ! TESTBED="$TESTBED" bash "$script" --quick --check --out "$dir/out" --cache "$dir/cache" >"$dir/log" 2>&1; then
    cat "$dir/log"
    echo "FAIL: methods-error.sh --quick --check failed"
    exit 1
fi
cat "$dir/log"
grep -q '^reference: .*(path, 512 spp)$' "$dir/log" || { echo "FAIL: no reference rendered"; exit 1; }
grep -c '^check cornell-box-spheres: hybrid .*: ok$' "$dir/log" | grep -qx 2 ||
    { echo "FAIL: the check lines (both hybrid modes) are missing"; exit 1; }
python3 - "$dir/out/methods-error.csv" <<'PY'
import csv, math, sys
lines = open(sys.argv[1]).read().splitlines()
assert lines[0] == "scene,method,mode,budget,seconds,cpu_seconds,relMSE,RMSE", "header: " + lines[0]
rows = list(csv.reader(lines[1:]))
assert all(len(r) == 8 for r in rows), "a row without 8 fields"
want = {("raytrace", "whitted"): 2, ("path", "path"): 3, ("radiosity", "radiosity"): 1,
        ("hybrid", "interpolated"): 2, ("hybrid", "gather"): 2}
for scene in ("cornell-box-spheres", "cornell-box"):
    got = {}
    for r in rows:
        if r[0] == scene:
            got[(r[1], r[2])] = got.get((r[1], r[2]), 0) + 1
    assert got == want, f"{scene}: rows per method and mode {got}, expected {want}"
for r in rows:
    s, c, rel, rmse = map(float, r[4:])
    assert all(math.isfinite(v) for v in (s, c, rel, rmse)), f"not finite: {r}"
    assert s > 0 and c >= 0 and rel > 0 and rmse > 0, f"not positive: {r}"
# the claim the check makes, from the CSV: the hybrid's last (largest) budget
# below the Whitted tracer's last on the spheres box, in both modes
sph = [r for r in rows if r[0] == "cornell-box-spheres"]
wh = [float(r[6]) for r in sph if r[2] == "whitted"][-1]
for mode in ("interpolated", "gather"):
    h = [float(r[6]) for r in sph if r[2] == mode][-1]
    assert h < wh, f"hybrid {mode} relMSE {h} not below Whitted's {wh}"
    print(f"csv: hybrid {mode} relMSE {h:.4g} < Whitted {wh:.4g}")
# path: more samples, less error (1 -> 16 spp; RMSE: relMSE is dominated by
# rare bright paths in dark pixels at a few spp, not monotone there)
for scene in ("cornell-box-spheres", "cornell-box"):
    p = [float(r[7]) for r in rows if r[0] == scene and r[2] == "path"]
    assert p[-1] < p[0], f"{scene}: path RMSE does not fall from 1 to 16 spp: {p}"
print("csv: ok")
PY
for s in cornell-box-spheres cornell-box; do
    head -c 8 "$dir/out/methods-error-$s.png" | od -An -c | grep -q 'P   N   G' || { echo "FAIL: $s: no PNG"; exit 1; }
    grep -q '<svg' "$dir/out/methods-error-$s.svg" || { echo "FAIL: $s: no SVG"; exit 1; }
done
# A second run reuses the cached reference.
TESTBED="$TESTBED" bash "$script" --quick --scenes cornell-box --methods raytrace --out "$dir/out2" --cache "$dir/cache" \
    --no-plot >"$dir/log2" 2>&1 || { cat "$dir/log2"; echo "FAIL: second run"; exit 1; }
grep -q '^reference: .*(cached)$' "$dir/log2" || { cat "$dir/log2"; echo "FAIL: the reference was not reused"; exit 1; }
# Usage errors.
set +e
bash "$script" --methods nosuch >/dev/null 2>&1; rc=$?
[ "$rc" -eq 2 ] || { echo "FAIL: --methods nosuch exited $rc, not 2"; exit 1; }
bash "$script" --frobnicate >/dev/null 2>&1; rc=$?
[ "$rc" -eq 2 ] || { echo "FAIL: an unknown option exited $rc, not 2"; exit 1; }
bash "$script" --scenes nosuch >/dev/null 2>&1; rc=$?
[ "$rc" -eq 2 ] || { echo "FAIL: an unknown scene exited $rc, not 2"; exit 1; }
set -e
echo "methods-error: ok"
