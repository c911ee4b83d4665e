#!/usr/bin/env bash
# The JSON report parses and holds what the workload in stats_tool recorded.
set -eu
tool=$1
dir=${TB_TEST_TMPDIR:-/tmp}/stats_json.$$
mkdir -p "$dir"
trap 'rm -rf "$dir"' EXIT
printf 'camera 0 0 5\nsphere 0 0 0 1\n' > "$dir/scene.mid"
"$tool" json "$dir/out.json" "$dir/scene.mid" 'arg with "quotes"' "back\\slash"
python3 -c 'import json,sys; json.load(open(sys.argv[1]))' "$dir/out.json"
python3 - "$dir/out.json" "$dir/scene.mid" <<'PY'
import hashlib, json, re, sys
path, scene = sys.argv[1], sys.argv[2]
with open(path, encoding="utf-8") as f:
    r = json.load(f)
def check(cond, what):
    if not cond:
        sys.exit("FAIL: " + what)
for key in ["schema", "provenance", "counters", "memory", "distributions",
            "ratios", "percentages", "timers"]:
    check(key in r, "missing top-level key " + key)
c = r["counters"]
check(c["Tool/items"] == 1000, "Tool/items = %r" % c.get("Tool/items"))
check(c['Tool/odd "name" \\ with\ttab'] == 7, "escaped counter name")
check(c["Tool/never touched"] == 0, "untouched counter listed as 0")
check(r["distributions"]["Tool/sizes"] ==
      {"count": 10, "sum": 55, "min": 1, "max": 10, "mean": 5.5}, "distribution")
check(r["ratios"]["Tool/hits per ray"] == {"num": 3, "den": 2, "ratio": 1.5}, "ratio")
check(r["percentages"]["Tool/shadow rays blocked"] == {"num": 1, "den": 4, "percent": 25.0}, "percent")
check(r["memory"]["Tool/memory"] == 4096, "memory")
t = r["timers"]["Tool/phase"]
check(t["calls"] == 3 and t["seconds"] >= 0 and t["mean_seconds"] >= 0, "timer %r" % t)
check(r["rays"] == 1000 and r["seconds"] == 0.5 and r["rays_per_second"] == 2000, "run values")
check(r["third"] == 1.0 / 3.0, "doubles round-trip exactly")
check(r["not_a_number"] is None, "NaN written as null")
check(r["note"] == 'quote " backslash \\ newline \n tab \t bell \x07 caf\u00e9', "escaped string %r" % r["note"])
check(r["bad_utf8"] == "x\ufffdy", "invalid UTF-8 replaced")
p = r["provenance"]
with open(scene, "rb") as f:
    check(p["scene_sha256"] == hashlib.sha256(f.read()).hexdigest(), "scene_sha256")
check(p["scene"] == scene, "scene path")
check(p["seed"] == 42, "seed")
check(p["options"] == 'spp=4 "quoted"', "options")
check(p["command_line"].endswith("""'arg with "quotes"' 'back\\slash'"""), "command line %r" % p["command_line"])
check(re.fullmatch(r"\d+\.\d+\.\d+", p["version"]) is not None, "version")
check(re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", p["time_utc"]) is not None, "time")
check(isinstance(p["cores"], int) and p["cores"] >= 1, "cores")
for k in ["git_revision", "hostname", "os", "cpu", "threads"]:
    check(k in p, "provenance." + k)
print("json ok")
PY
# A report to a folder that does not exist fails and leaves nothing behind.
if "$tool" json "$dir/no/such/dir/out.json" "$dir/scene.mid" 2>/dev/null; then
  echo "FAIL: write into a missing folder succeeded"; exit 1
fi
# A scene that cannot be read is reported, not hashed as empty.
if "$tool" json "$dir/out2.json" "$dir/missing.mid" 2>/dev/null; then
  echo "FAIL: missing scene accepted"; exit 1
fi
[[ ! -e "$dir/out2.json" ]] || { echo "FAIL: report written despite the error"; exit 1; }
echo "all ok"
