#!/bin/sh
# `testbed render SCENE --method hybrid` end to end (docs/hybrid.md): the
# Cornell box at 48 x 48 with 80 mm elements in both modes writes an image
# and stats whose provenance says method=hybrid and the mode, brighter than
# the Whitted image of the same command line; 1 and 2 threads give the same
# bytes; --backend vulkan, --gather-rays without gather and a missing -o are
# usage errors (exit 2) with a clear message; --help lists the options.
#   cli.sh  (with TESTBED, TB_SOURCE_DIR, TB_TEST_TMPDIR set)
set -u
T="${TB_TEST_TMPDIR:-/tmp}/hybrid_cli.$$"
rm -rf "$T" && mkdir -p "$T"
fail() { echo "FAIL: $*"; exit 1; }
BOX="$T/box.mid"
sed 's/resolution = \[512 512\]/resolution = [48 48]/' "$TB_SOURCE_DIR/scenes/cornell-box-rgb.mid" > "$BOX"
grep -q 'resolution = \[48 48\]' "$BOX" || fail "could not shrink the Cornell box's resolution"
hyb() { "$TESTBED" render "$BOX" --method hybrid --max-edge 80 --spp 4 "$@"; }

hyb -o "$T/i.pfm" --stats "$T/i.json" --threads 2 > "$T/out" 2>&1 || { cat "$T/out"; fail "interpolated run"; }
grep -q "hybrid (interpolated), radiosity [0-9]* elements" "$T/out" || { cat "$T/out"; fail "summary line"; }
grep -q "direct-only solve" "$T/out" || { cat "$T/out"; fail "no log line of the direct-only solve"; }
hyb -o "$T/g.pfm" --stats "$T/g.json" --hybrid-mode gather --gather-rays 8 --threads 2 > "$T/out" 2>&1 ||
    { cat "$T/out"; fail "gather run"; }
hyb -o "$T/i1.pfm" --threads 1 > "$T/out" 2>&1 || { cat "$T/out"; fail "one-thread run"; }
cmp -s "$T/i.pfm" "$T/i1.pfm" || fail "1 and 2 threads differ"
"$TESTBED" render "$BOX" --spp 4 -o "$T/w.pfm" --backend cpu > "$T/out" 2>&1 || { cat "$T/out"; fail "Whitted run"; }
python3 - "$T" <<'PY' || fail "provenance or image check"
import json, struct, sys
t = sys.argv[1]
def mean(p):
    with open(p, 'rb') as f:
        kind = f.readline().strip(); w, h = map(int, f.readline().split()); sc = float(f.readline())
        n = w * h * (3 if kind == b'PF' else 1)
        d = struct.unpack(('<' if sc < 0 else '>') + '%df' % n, f.read(4 * n))
    return sum(d) / len(d)
for name, mode in (('i', 'interpolated'), ('g', 'gather')):
    j = json.load(open('%s/%s.json' % (t, name)))
    opts = j['provenance']['options']
    assert 'method=hybrid' in opts and ('hybrid_mode=%s' % mode) in opts, opts
    assert j['radiosity_elements'] > 100, {k: v for k, v in j.items() if k.startswith('radiosity_')}
    assert j['radiosity_shots'] > 0, {k: v for k, v in j.items() if k.startswith('radiosity_')}
    assert (j['radiosity_direct_shots'] > 0) == (mode == 'interpolated'), {k: v for k, v in j.items() if k.startswith('radiosity_')}
mi, mg, mw = mean(t + '/i.pfm'), mean(t + '/g.pfm'), mean(t + '/w.pfm')
# the indirect light (about a fifth of the hybrid's) that Whitted lacks; both modes agree to a few per cent
assert mi > 1.15 * mw and mg > 1.15 * mw, (mi, mg, mw)
assert abs(mg / mi - 1) < 0.03, (mi, mg)
PY

# usage errors: exit 2 and a message naming the problem
hyb -o "$T/v.pfm" --backend vulkan > "$T/out" 2>&1; rc=$?
[ $rc -eq 2 ] || fail "--backend vulkan: exit $rc, not 2"
grep -q "runs on the CPU only" "$T/out" || { cat "$T/out"; fail "--backend vulkan: message"; }
hyb -o "$T/v.pfm" --gather-rays 4 > "$T/out" 2>&1; rc=$?
[ $rc -eq 2 ] && grep -q "goes with --hybrid-mode gather" "$T/out" || { cat "$T/out"; fail "--gather-rays alone"; }
hyb > "$T/out" 2>&1; rc=$?
[ $rc -eq 2 ] && grep -q "no output given" "$T/out" || { cat "$T/out"; fail "no -o"; }
hyb -o "$T/v.pfm" --hybrid-mode nearest > "$T/out" 2>&1; rc=$?
[ $rc -eq 2 ] || { cat "$T/out"; fail "unknown --hybrid-mode: exit $rc"; }
"$TESTBED" render --method hybrid --help > "$T/help" 2>&1 || fail "--help"
for o in --hybrid-mode --gather-rays --max-edge --rad-samples --threshold --spp --passes --time-budget --report; do
    grep -q -- "$o" "$T/help" || fail "--help does not list $o"
done
rm -rf "$T"
echo "hybrid cli: both modes, provenance method=hybrid, thread-independent, usage errors"
