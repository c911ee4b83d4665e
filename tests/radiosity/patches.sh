#!/bin/sh
# `testbed render --method radiosity --patch-edge/--patch-area` end to end
# (docs/radiosity.md, "Patches and elements"): the furnace's elements and
# their patches in the CSV (the documented columns, then `patch`), each patch
# holding its share of elements, B = E / (1 - rho) = 2, the patch count in
# --stats, adaptive subdivision keeping the patches, 1 and 2 threads alike,
# and bad options: a clear message, a non-zero exit, no file left behind.
set -u
NAME=radiosity_patches_cli; . "$TB_SOURCE_DIR/tests/radiosity/rad_cli.sh"

rad "$FURNACE" --max-edge 0.25 --patch-edge 0.5 --samples 16 --threshold 1e-3 --threads 1 --patches "$T/a.csv" \
    --stats "$T/a.json" > "$T/out1" 2>&1 || { cat "$T/out1"; fail "furnace run"; }
grep -q "24 patches" "$T/out1" || { cat "$T/out1"; fail "patch count not printed"; }
head -1 "$T/a.csv" | grep -qx 'element,object,area,cx,cy,cz,nx,ny,nz,b_r,b_g,b_b,u_r,u_g,u_b,patch' ||
    fail "CSV header: $(head -1 "$T/a.csv")"
# 96 elements, 24 patches of 4 elements of area 1/16 each, B = 2 within 1%
awk -F, 'NR > 1 { n++; cnt[$16]++; if ($16 !~ /^[0-9]+$/ || $16 >= 24) bad++;
                  for (c = 10; c <= 12; c++) { e = ($c - 2) / 2; if (e < 0) e = -e; if (e > w) w = e } }
         END { for (p in cnt) { np++; if (cnt[p] != 4) bad++ }
               if (n != 96 || np != 24 || bad) { print "rows", n, "patches", np, "bad", bad; exit 1 }
               if (w > 0.01) { print "worst", w; exit 1 } }' "$T/a.csv" || fail "patch column or furnace values"
grep -q '"patches": *24' "$T/a.json" || fail "--stats patches: $(grep patches "$T/a.json")"
rad "$FURNACE" --max-edge 0.25 --patch-edge 0.5 --samples 16 --threshold 1e-3 --threads 2 --patches "$T/b.csv" \
    > "$T/out2" 2>&1 || { cat "$T/out2"; fail "furnace run, 2 threads"; }
cmp -s "$T/a.csv" "$T/b.csv" || fail "1 and 2 threads give different CSV bytes"
# --patch-area 0.25 is the same mesh as --patch-edge 0.5
rad "$FURNACE" --max-edge 0.25 --patch-area 0.25 --samples 16 --threshold 1e-3 --patches "$T/c.csv" \
    > "$T/out3" 2>&1 || { cat "$T/out3"; fail "--patch-area run"; }
cmp -s "$T/a.csv" "$T/c.csv" || fail "--patch-area 0.25 differs from --patch-edge 0.5"

# adaptive subdivision: the refined elements stay in their patches
SHADOW="$TB_SOURCE_DIR/tests/adaptive/shadow.mid"
rad "$SHADOW" --patch-edge 0.5 --samples 16 --adapt 0.3 --adapt-levels 2 --patches "$T/d.csv" > "$T/out4" 2>&1 ||
    { cat "$T/out4"; fail "--adapt with patches"; }
np0=$(sed -n 's/.*: \([0-9]*\) patches .*/\1/p' "$T/out4")
awk -F, -v np0="$np0" 'NR == 1 { if ($NF != "patch") exit 1 }
    NR > 1 { n++; seen[$NF] = 1 } END { for (p in seen) k++; if (k != np0 || n <= k) { print n, k, np0; exit 1 } }' \
    "$T/d.csv" || fail "adaptive subdivision lost patches (expected $np0)"

# --help and errors
rad --help | grep -q -- "--patch-edge" || fail "--help"
for bad in "--patch-edge 0" "--patch-edge -1" "--patch-edge x" "--patch-area 0" "--patch-area nan"; do
    # shellcheck disable=SC2086
    rad "$FURNACE" --max-edge 0.25 $bad --patches "$T/e.csv" > "$T/err" 2>&1
    [ $? -eq 2 ] || fail "'$bad' should be an option error"
    grep -q "patch-" "$T/err" || fail "'$bad': no message"
    [ ! -e "$T/e.csv" ] || fail "'$bad' left a file"
done
rad "$FURNACE" --max-edge 0.25 --patch-edge 0.2 --patches "$T/e.csv" > "$T/err" 2>&1 && fail "patches smaller than elements"
grep -q "must not be smaller than elements" "$T/err" || fail "patch < element: $(cat "$T/err")"
[ ! -e "$T/e.csv" ] || fail "patch < element left a file"
rad "$FURNACE" --max-edge 0 --patch-edge 0.5 --patches "$T/e.csv" > "$T/err" 2>&1 && fail "patches with faces whole"
grep -q "need an element size" "$T/err" || fail "faces whole: $(cat "$T/err")"
rm -rf "$T"
echo ok
