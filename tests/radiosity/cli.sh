#!/bin/sh
# `testbed render --method radiosity` end to end (docs/radiosity.md): the
# white furnace through --patches (every element B = E / (1 - rho) = 2 with
# the ambient term left out, to the threshold and the form-factor error),
# the exact CSV columns, the same bytes with 1 and 2 threads, --report with
# --reference, --mesh-out PLY, and bad options: a clear message, a non-zero
# exit and no file left behind.
set -u
T="${TB_TEST_TMPDIR:-/tmp}/radiosity_cli.$$"
rm -rf "$T" && mkdir -p "$T"
FURNACE="$TB_SOURCE_DIR/tests/radiosity/furnace.mid"
fail() { echo "FAIL: $*"; exit 1; }
rad() { "$TESTBED" render --method radiosity "$@"; }

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
