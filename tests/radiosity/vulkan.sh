#!/bin/sh
# `render --method radiosity --backend vulkan` (the form-factor kernel,
# host/gpu/formfactor.h) against the CPU backend on the furnace: the same
# shots, radiosities equal to float rounding. No device is a failure: the
# test machine has lavapipe (tools/setup.sh installs mesa-vulkan-drivers).
set -u
NAME=radiosity_vulkan; . "$TB_SOURCE_DIR/tests/radiosity/rad_cli.sh"
run() { "$TESTBED" render --method radiosity "$FURNACE" --max-edge 0.25 --samples 8 --threshold 1e-2 "$@"; }
if ! run --backend vulkan --patches "$T/v.csv" --stats "$T/v.json" > "$T/v.log" 2>&1; then
    cat "$T/v.log"; echo "FAIL: vulkan run (no Vulkan device? tools/setup.sh installs lavapipe)"; exit 1
fi
run --backend cpu --patches "$T/c.csv" --stats "$T/c.json" > "$T/c.log" 2>&1 || { echo "FAIL: cpu run"; exit 1; }
# What runs where, in the log and --stats: the form factors on the kernel,
# the rest named as CPU steps (nothing falls back unsaid).
grep -q 'steps: form factors vulkan, near-shooter form factors cpu, light shots none, image none' "$T/v.log" ||
    { cat "$T/v.log"; echo "FAIL: vulkan steps line"; exit 1; }
grep -q 'steps: form factors cpu, near-shooter form factors cpu' "$T/c.log" ||
    { cat "$T/c.log"; echo "FAIL: cpu steps line"; exit 1; }
grep -q '"backend_formfactors": "vulkan"' "$T/v.json" && grep -q '"backend_near_field": "cpu"' "$T/v.json" &&
    grep -q '"backend_light_shots": "none"' "$T/v.json" && grep -q '"backend_formfactors": "cpu"' "$T/c.json" ||
    { echo "FAIL: backend_* in --stats"; exit 1; }
[ "$(wc -l < "$T/v.csv")" -eq "$(wc -l < "$T/c.csv")" ] || { echo "FAIL: row counts"; exit 1; }
paste -d, "$T/v.csv" "$T/c.csv" | awk -F, 'NR > 1 {
    for (c = 10; c <= 12; c++) { d = $c - $(c + 15); if (d < 0) d = -d; if (d > 1e-5 * $(c + 15)) bad = 1; if (d > m) m = d }
} END { print "largest |B_vulkan - B_cpu| = " m; exit bad }' || { echo "FAIL: backends differ"; exit 1; }
rm -rf "$T"
echo OK
