#!/bin/sh
# `testbed validate --kernel formfactor` on the Cornell box through lavapipe
# with the validation layer: the Vulkan form-factor kernel must agree with the
# CPU batch within docs/accuracy.md's tolerances ("Form-factor kernel") and the
# layer must report nothing; `--kernel all` includes it; usage errors.
set -eu
: "${TESTBED:?}" "${TB_SOURCE_DIR:?}" "${TB_TEST_TMPDIR:?}"
out="$TB_TEST_TMPDIR/ff_validate.out"
scene="$TB_SOURCE_DIR/scenes/cornell-box.mid"
if ! TB_VK_VALIDATION=1 "$TESTBED" validate "$scene" --kernel formfactor --shooters 6 --receivers 3000 >"$out" 2>&1; then
    echo "FAIL: testbed validate --kernel formfactor"
    cat "$out"
    exit 1
fi
cat "$out"
for line in "max scaled error .* ok$" "max relative error " "mean relative error .* ok$" "visibility agreement .* ok$" \
            "validation layer       0 errors, 0 warnings  ok"; do
    grep -q "$line" "$out" || { echo "missing: $line"; exit 1; }
done
# Every receiver of the box (2819 centroids and corners: fewer than 3000), 6 shooters x 16 samples.
grep -q "^kernel formfactor: 1322 elements .*, 2819 receivers (of 2819 .*6 shooters x 16 samples" "$out" ||
    { echo "unexpected mesh or receiver counts"; exit 1; }
grep -q "kernel intersect" "$out" && { echo "--kernel formfactor ran the intersect comparison"; exit 1; }
# --kernel all runs it too (after the intersect kernel).
"$TESTBED" validate "$scene" --kernel all --rays 500 --shooters 1 --receivers 200 >"$out" 2>&1 ||
    { echo "FAIL: --kernel all"; cat "$out"; exit 1; }
grep -q "^kernel intersect" "$out" && grep -q "^kernel formfactor" "$out" ||
    { echo "--kernel all should run both"; cat "$out"; exit 1; }
# Usage errors (exit 2).
set +e
for bad in "--shooters 0" "--samples 5000" "--receivers x"; do
    "$TESTBED" validate "$scene" --kernel formfactor $bad >/dev/null 2>&1
    [ $? -eq 2 ] || { echo "'$bad' should be a usage error"; exit 1; }
done
echo "ok"
