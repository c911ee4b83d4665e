#!/usr/bin/env bash
# `testbed devices` end to end: the listing, --json (parsed by Python and
# checked against vulkaninfo, an independent tool), --check, --validation,
# the no-driver and no-loader messages (exit 0, CPU path), usage errors.
set -u
tb=${TESTBED:?} tmp=${TB_TEST_TMPDIR:-/tmp}/gpu_devices_cli.$$
mkdir -p "$tmp"
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

"$tb" devices > "$tmp/list.txt" 2>&1 || fail "devices exited $?"
cat "$tmp/list.txt"
grep -q '^Vulkan loader [0-9]' "$tmp/list.txt" || fail "no loader line"
grep -q -- '--backend vulkan: ' "$tmp/list.txt" || fail "no --backend vulkan line"
grep -q -- '--backend auto: ' "$tmp/list.txt" || fail "no --backend auto line"
grep -q 'subgroup ' "$tmp/list.txt" || fail "no subgroup size"
grep -q 'timestamps ' "$tmp/list.txt" || fail "no timestamp line"

"$tb" devices --json --check > "$tmp/list.json" || fail "devices --json --check exited $?"
python3 - "$tmp/list.json" <<'PY' || fail "JSON content"
import json, subprocess, sys
j = json.load(open(sys.argv[1]))
devs = j["devices"]
assert j["error"] is None and len(devs) >= 1, j
for d in devs:
    for key in ("name", "type", "api_version", "driver_name", "subgroup_size", "max_workgroup_size",
                "heaps", "timestamps", "usable"):
        assert key in d, key
    assert d["type"] in ("discrete", "integrated", "virtual", "cpu", "other")
    if d["usable"]:
        assert d["self_test"]["ok"], d["self_test"]
# --backend vulkan uses the best device; auto uses it only when it is a GPU
vk = j["vulkan"]["device"]
assert vk is not None and devs[vk]["usable"]
rank = {"discrete": 4, "integrated": 3, "virtual": 2, "cpu": 1, "other": 0}
assert all(rank[devs[vk]["type"]] >= rank[d["type"]] for d in devs if d["usable"])
gpu = devs[vk]["type"] in ("discrete", "integrated", "virtual")
assert (j["auto"]["backend"] == "vulkan") == gpu, j["auto"]
# independent check: vulkaninfo lists the same device names in the same order
# (vulkaninfo comes from vulkan-tools, installed by tools/setup.sh: missing is a failure)
try:
    out = subprocess.run(["vulkaninfo", "--summary"], capture_output=True, text=True, timeout=60).stdout
except FileNotFoundError:
    sys.exit("vulkaninfo not installed (Debian package vulkan-tools): the independent name check cannot run")
names = [l.split("=", 1)[1].strip() for l in out.splitlines() if l.strip().startswith("deviceName")]
assert names == [d["name"] for d in devs], (names, [d["name"] for d in devs])
print("devices --json agrees with vulkaninfo:", names)
PY

# validation on: the listing and the self-test produce no message
"$tb" devices --check --validation > "$tmp/val.txt" 2>&1 || { cat "$tmp/val.txt"; fail "--validation exited $?"; }
grep -q 'validation: 0 errors, 0 warnings' "$tmp/val.txt" || fail "no validation summary"

# no driver: reported, exit 0
for var in VK_ICD_FILENAMES VK_DRIVER_FILES; do
  out=$(env "$var=/nonexistent/tb-no-icd.json" "$tb" devices) || fail "no-driver run ($var) exited $?"
  echo "$out"
  grep -q '^no Vulkan devices: no Vulkan driver (ICD) could be loaded' <<<"$out" || fail "no-driver message ($var)"
  grep -q 'auto uses the CPU path' <<<"$out" || fail "no-driver fallback note ($var)"
done
env VK_ICD_FILENAMES=/nonexistent/tb-no-icd.json VK_DRIVER_FILES=/nonexistent/tb-no-icd.json \
  "$tb" devices --json > "$tmp/none.json" || fail "no-driver --json exited $?"
python3 -c '
import json, sys
j = json.load(open(sys.argv[1]))
assert j["devices"] == [] and j["loader_version"] is None and "driver" in j["error"], j
assert j["auto"]["backend"] == "cpu" and j["vulkan"]["device"] is None, j
' "$tmp/none.json" || fail "no-driver JSON"

# no loader: reported, exit 0
out=$(TB_VULKAN_LOADER=/nonexistent/libvulkan.so.1 "$tb" devices) || fail "no-loader run exited $?"
grep -q 'Vulkan loader /nonexistent/libvulkan.so.1 not found' <<<"$out" || fail "no-loader message: $out"

# usage
"$tb" devices --help | grep -q '^usage: testbed devices' || fail "--help"
"$tb" devices --bogus > /dev/null 2>&1
[[ $? == 2 ]] || fail "unknown option should exit 2"
"$tb" help | grep -q '^  devices ' || fail "devices missing from testbed help"
echo "devices CLI ok"
