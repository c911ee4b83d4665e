#!/bin/sh
# `testbed measure` end to end (docs/measure.md): --help and usage errors;
# readings of a point light over a plane against I cos / r^2 in the CSV
# output, by both methods; the same bytes for 1 and 2 threads; bad sensors
# and MEASURED rows give FILE:LINE: error, exit 1 and leave no output file
# (an existing one untouched); --compare prints residuals and the sensors
# that disagree, exit 0 (3 with --fail-on-disagree); the worked example of
# docs/examples/measure: pi L / E of the Cornell box's walls against the
# measured reflectances.
#   cli.sh  (with TESTBED, TB_SOURCE_DIR, TB_TEST_TMPDIR set)
set -u
T="${TB_TEST_TMPDIR:-/tmp}/measure_cli.$$"
rm -rf "$T" && mkdir -p "$T"
fail() { echo "FAIL: $*"; exit 1; }
M="$TB_SOURCE_DIR/tests/measure"
EX="$TB_SOURCE_DIR/docs/examples/measure"

"$TESTBED" measure --help > "$T/help" 2>&1 || fail "--help exit status"
grep -q -- "--sensors SENSORS.csv" "$T/help" || fail "--help does not show --sensors"
grep -q -- "--fail-on-disagree" "$T/help" || fail "--help does not show --fail-on-disagree"
"$TESTBED" measure "$M/point.mid" > "$T/out" 2>&1; rc=$?
[ $rc -eq 2 ] || fail "no --sensors: exit $rc, want 2"
grep -q "sensors SENSORS.csv is required" "$T/out" || { cat "$T/out"; fail "no --sensors message"; }
"$TESTBED" measure "$M/point.mid" --sensors x.csv --method photon > "$T/out" 2>&1; rc=$?
[ $rc -eq 2 ] || fail "bad --method: exit $rc, want 2"

cat > "$T/s.csv" <<'CSV'
# a comment, then the header
name,kind,x,y,z,dx,dy,dz,half_angle_deg,filter
below,irradiance,0,0,0,0,0,1,,
side,irradiance,1.5,0,0,0,0,1,,
tilted,irradiance,1,1,0.5,0.3,-0.2,1,,
CSV
for m in path radiosity; do
    "$TESTBED" measure "$M/point.mid" --sensors "$T/s.csv" --method $m -o "$T/$m.csv" --threads 2 > "$T/out" 2>&1 ||
        { cat "$T/out"; fail "$m run"; }
done
"$TESTBED" measure "$M/point.mid" --sensors "$T/s.csv" -o "$T/path1.csv" --threads 1 > "$T/out" 2>&1 ||
    { cat "$T/out"; fail "one-thread run"; }
cmp -s "$T/path.csv" "$T/path1.csv" || fail "1 and 2 threads differ"
python3 - "$T" <<'PY' || fail "readings of the point light"
import csv, math, sys
t = sys.argv[1]
I, L = (4.0, 2.0, 1.0), (0.0, 0.0, 2.0)
for m in ('path', 'radiosity'):
    rows = list(csv.DictReader(open('%s/%s.csv' % (t, m))))
    assert [r['name'] for r in rows] == ['below', 'side', 'tilted'], rows
    for r, (p, d) in zip(rows, (((0, 0, 0), (0, 0, 1)), ((1.5, 0, 0), (0, 0, 1)), ((1, 1, 0.5), (0.3, -0.2, 1)))):
        v = [L[i] - p[i] for i in range(3)]
        r2 = sum(x * x for x in v)
        dn = math.sqrt(sum(x * x for x in d))
        cs = sum(v[i] * d[i] for i in range(3)) / math.sqrt(r2) / dn
        for c, ch in enumerate('RGB'):
            want = I[c] * cs / r2
            assert abs(float(r[ch]) - want) <= 1e-6 * want, (m, r['name'], ch, r[ch], want)
        assert r['reading_unit'] == 'W/m^2' and r['photometric_unit'] == 'lx', r
        Y = 0.2126 * float(r['R']) + 0.7152 * float(r['G']) + 0.0722 * float(r['B'])
        assert abs(float(r['photometric']) - 683 * Y) <= 1e-4 * 683 * Y, r
PY

# bad input: FILE:LINE: error, exit 1, no output (an existing file untouched)
echo keep > "$T/keep.csv"
bad() { # bad NAME WANT: sensors file $T/NAME.csv must fail with WANT
    "$TESTBED" measure "$M/point.mid" --sensors "$T/$1.csv" -o "$T/keep.csv" > "$T/out" 2>&1; rc=$?
    [ $rc -eq 1 ] || { cat "$T/out"; fail "$1: exit $rc, want 1"; }
    grep -qF "$2" "$T/out" || { cat "$T/out"; fail "$1: message, want '$2'"; }
    [ "$(cat "$T/keep.csv")" = keep ] || fail "$1: the output file was touched"
}
printf 'name,kind,x,y,z,dx,dy,dz,half_angle_deg,filter\na,lamp,0,0,0,0,0,1,,\n' > "$T/kind.csv"
bad kind "$T/kind.csv:2: error: unknown kind 'lamp'"
printf 'name,kind,x,y,z,dx,dy,dz,half_angle_deg,filter\na,radiance,0,0,0,0,0,1,95,\n' > "$T/angle.csv"
bad angle "$T/angle.csv:2: error: half_angle_deg 95 is not in (0, 90]"
printf 'name,kind,x,y,z,dx,dy,dz,half_angle_deg,filter\na,irradiance,0,0,0,0,0,1,,nofilter.csv\n' > "$T/filter.csv"
bad filter "$T/filter.csv:2: error: filter '$T/nofilter.csv'"
printf 'name,kind,x,y,z,dx,dy,dz\na,irradiance,0,0,0,0,0,1\na,irradiance,1,0,0,0,0,1\n' > "$T/dup.csv"
bad dup "$T/dup.csv:3: error: duplicate sensor name 'a'"
printf 'name,value\nbelow,1\nnobody,2\n' > "$T/m-bad.csv"
"$TESTBED" measure "$M/point.mid" --sensors "$T/s.csv" --compare "$T/m-bad.csv" -o "$T/keep.csv" > "$T/out" 2>&1; rc=$?
[ $rc -eq 1 ] || fail "unknown measured name: exit $rc, want 1"
grep -qF "$T/m-bad.csv:3: error: no sensor named 'nobody'" "$T/out" || { cat "$T/out"; fail "measured message"; }
[ "$(cat "$T/keep.csv")" = keep ] || fail "measured: the output file was touched"
ls "$T" | grep -q '\.tmp' && fail "a temporary file was left behind"

# --compare: one sensor off by 10 % with a 1 % uncertainty disagrees
printf 'name,value,uncertainty\nbelow,0.5882,0.001\nside,0.33,0.003\n' > "$T/m.csv"
"$TESTBED" measure "$M/point.mid" --sensors "$T/s.csv" --compare "$T/m.csv" > "$T/out" 2>&1; rc=$?
[ $rc -eq 0 ] || { cat "$T/out"; fail "--compare with a disagreement: exit $rc, want 0"; }
grep -q "^compared 2 of 3 sensors (reading): RMS relative error" "$T/out" || { cat "$T/out"; fail "summary line"; }
grep -q "^DISAGREE: 1 sensor beyond 2 x the combined uncertainty: side$" "$T/out" || { cat "$T/out"; fail "disagree line"; }
"$TESTBED" measure "$M/point.mid" --sensors "$T/s.csv" --compare "$T/m.csv" --fail-on-disagree > "$T/out" 2>&1; rc=$?
[ $rc -eq 3 ] || fail "--fail-on-disagree: exit $rc, want 3"

# the worked example: the walls' reflectances against the measured ones
"$TESTBED" measure "$TB_SOURCE_DIR/scenes/cornell-box.mid" --sensors "$EX/sensors.csv" --samples 8192 \
    -o "$T/ex.csv" --compare "$EX/radiosity-as-measured.csv" > "$T/out" 2>&1 || { cat "$T/out"; fail "example run"; }
grep -q "^compared 22 of 22 sensors" "$T/out" || { cat "$T/out"; fail "example comparison"; }
python3 "$EX/reflectance.py" "$T/ex.csv" || fail "pi L / E against the measured reflectances"
rm -rf "$T"
echo "measure_cli: ok"
