#!/usr/bin/env bash
# `testbed compare` end to end: the JSON is strict JSON (no NaN/Infinity),
# its SSIM matches the independent Python implementation, identical images
# give MSE 0 and PSNR null (+inf), the error image is written with the right
# size, and the exit codes are 0 / 1 / 2 as documented.
# Usage: compare_cli.sh   (TESTBED, TB_SOURCE_DIR, TB_TEST_TMPDIR from CTest)
set -euo pipefail
tb=${TESTBED:?}
src=${TB_SOURCE_DIR:?}/tests/image
tmp=$(mktemp -d "${TB_TEST_TMPDIR:-/tmp}/compare_cli.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"
fails=0

check() { # check WHAT COMMAND... : the command must succeed
    local what=$1
    shift
    if ! "$@"; then
        echo "FAIL: $what"
        fails=$((fails + 1))
    fi
}

status() { # status WANT COMMAND... : the command must exit with WANT
    local want=$1
    shift
    local got=0
    "$@" > /dev/null 2> stderr.txt || got=$?
    if [ "$got" -ne "$want" ]; then
        echo "FAIL: '$*' exited $got, want $want"
        cat stderr.txt
        fails=$((fails + 1))
    fi
}

# Strict JSON: Python's parser accepts NaN/Infinity unless told not to.
strict_json='
import json, sys
def bad(c): raise ValueError("non-JSON constant " + c)
doc = json.load(open(sys.argv[1]), parse_constant=bad)
'

python3 "$src/compare_ssim_reference.py" --write-pfm . > py1.json
python3 "$src/compare_ssim_reference.py" --peak 2 > py2.json

"$tb" compare a.pfm b.pfm --json > c1.json
check "JSON is valid (json.tool)" python3 -m json.tool c1.json > /dev/null
check "JSON is strict" python3 -c "$strict_json" c1.json
"$tb" compare a.pfm b.pfm --json --peak 2 --error-image err.pfm > c2.json
check "JSON with --peak is strict" python3 -c "$strict_json" c2.json

check "SSIM and metrics agree with Python" python3 - py1.json c1.json py2.json c2.json <<'EOF'
import json, math, sys
py1, c1, py2, c2 = (json.load(open(p)) for p in sys.argv[1:5])
ok = True
def near(what, a, b, tol):
    global ok
    if not abs(a - b) <= tol:
        print("mismatch: %s: testbed %r, python %r" % (what, a, b)); ok = False
for py, c in ((py1, c1), (py2, c2)):
    assert [ch["name"] for ch in c["channels"]] == ["R", "G", "B"], c["channels"]
    for k in range(3):
        near("ssim[%d] peak %g" % (k, py["peak"]), c["channels"][k]["ssim"], py["ssim"][k], 1e-6)
    near("mean ssim peak %g" % py["peak"], c["all"]["ssim"], py["mean"], 1e-6)
    assert c["width"] == 24 and c["height"] == 20 and c["valid_pixels"] == 480
# PSNR follows from MSE and the peak
for c in (c1, c2):
    near("psnr", c["all"]["psnr"], 10 * math.log10(c["peak"] ** 2 / c["all"]["mse"]), 1e-9)
near("psnr gain of peak 2", c2["all"]["psnr"] - c1["all"]["psnr"], 10 * math.log10(4), 1e-9)
assert c2["error_image"]["path"] == "err.pfm" and c2["error_image"]["scale"] > 0
sys.exit(0 if ok else 1)
EOF

check "error image is a 24x20 colour PFM" python3 - err.pfm <<'EOF'
import sys
f = open(sys.argv[1], 'rb')
head = f.read(64).split(b'\n')
assert head[0] == b'PF', head[0]
assert head[1].split() == [b'24', b'20'], head[1]
EOF

# identical images: MSE 0, PSNR +inf -> null, SSIM 1
"$tb" compare a.pfm a.pfm --json > same.json
check "identical images" python3 - same.json <<'EOF'
import json, sys
c = json.load(open(sys.argv[1]))
assert c["all"]["mse"] == 0 and c["all"]["psnr"] is None, c["all"]
assert abs(c["all"]["ssim"] - 1) < 1e-12, c["all"]["ssim"]
EOF

# the table names every metric and channel
"$tb" compare a.pfm b.pfm --channels G > table.txt
check "table output" grep -q "PSNR" table.txt
check "table has only G" bash -c '! grep -q "^R " table.txt && grep -q "^G " table.txt'

# exit codes
python3 - small.pfm <<'EOF'
import struct, sys
with open(sys.argv[1], 'wb') as f:
    f.write(b'PF\n5 5\n-1.0\n' + struct.pack('<75f', *([0.5] * 75)))
EOF
status 0 "$tb" compare --help
status 0 "$tb" help compare
status 2 "$tb" compare
status 2 "$tb" compare a.pfm
status 2 "$tb" compare a.pfm b.pfm c.pfm
status 2 "$tb" compare a.pfm b.pfm --bogus
status 2 "$tb" compare a.pfm b.pfm --peak
status 2 "$tb" compare a.pfm b.pfm --peak zero
status 2 "$tb" compare a.pfm b.pfm --peak -1
status 2 "$tb" compare a.pfm b.pfm --error-scale nan
status 1 "$tb" compare a.pfm missing.pfm
status 1 "$tb" compare a.pfm small.pfm
status 1 "$tb" compare a.pfm b.pfm --channels R,Q
status 1 "$tb" compare a.pfm b.pfm --error-image /nonexistent-dir/err.pfm
status 0 "$tb" compare a.pfm b.pfm --error-image err.png
grep -q "size mismatch" <("$tb" compare a.pfm small.pfm 2>&1) ||
    { echo "FAIL: size mismatch message"; fails=$((fails + 1)); }

echo "$fails failed"
[ "$fails" -eq 0 ]
