#!/usr/bin/env python3
"""`testbed calibrate` and `testbed predict` end to end (docs/predict.md).

1. --help of both exits 0; usage errors exit 2.
2. A real mini calibration (--set quick: sixteen small generated scenes, every
   method) writes COSTS.json; it parses, holds every term with a cost >= 0,
   and the --runs CSV has a row per run.
3. predict --json on a generated scene (raytrace, path, radiosity) is valid
   JSON with "seconds", "peak_rss_bytes" (positive, finite) and "modules"
   (every module, summing to seconds without memory); the text output names
   the modules.
4. Without --costs, predict reads $XDG_CACHE_HOME/testbed/costs.json, and
   with none there says to run testbed calibrate (exit 1); calibrate without
   -o writes that file; a broken COSTS.json gets "file:line:col: error".
5. Memory: the predicted peak resident memory of a generated scene the
   calibration did not render (grid kind, 40 objects, seed 9, the ray
   tracer at 1024 x 768) is within +-25% of the render's measured peak
   (os.wait4). Memory does not depend on the machine's load; timing
   accuracy is the benchmark's job (tools/bench/predict-accuracy.sh), not
   asserted here. Mesh-heavy scenes and the path tracer are not asserted
   with the quick set: their peak comes from the load's transient buffers
   or the film, which 16 tiny runs do not pin down (docs/predict.md,
   "Limits"; the default set gets them within 25%).

Environment: TESTBED, TB_TEST_TMPDIR."""
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

TB = os.environ.get("TESTBED", "testbed")
TMP = tempfile.mkdtemp(prefix="predict-test-", dir=os.environ.get("TB_TEST_TMPDIR") or None)
ENV = dict(os.environ, TB_NO_PROGRESS="1", XDG_CACHE_HOME=os.path.join(TMP, "cache"))
MODULES = ["load", "build", "raytrace", "path", "radiosity", "process", "memory"]


def run(*args, expect=0, env=ENV):
    p = subprocess.run([TB, *args], capture_output=True, text=True, env=env)
    if p.returncode != expect:
        sys.exit("FAIL: testbed %s: exit %d (expected %d)\nstdout:\n%s\nstderr:\n%s"
                 % (" ".join(args), p.returncode, expect, p.stdout, p.stderr))
    return p


def check(cond, what):
    if not cond:
        sys.exit("FAIL: " + what)


def main():
    # 1. help and usage
    for cmd in ("calibrate", "predict"):
        p = run(cmd, "--help")
        check("usage: testbed " + cmd in p.stdout, cmd + " --help prints the usage")
    check("no SCENE.mid given" in run("predict", expect=2).stderr, "predict without a scene is a usage error")
    check("--set" in run("calibrate", "--set", "huge", expect=2).stderr, "calibrate --set huge is a usage error")

    # 4a. no costs yet: a clear error naming the default path and calibrate
    scene = os.path.join(TMP, "grid.mid")
    run("generate", "grid", "--count", "10", "--seed", "3", "-o", scene)
    p = run("predict", scene, expect=1)
    default = os.path.join(TMP, "cache", "testbed", "costs.json")
    check(default in p.stderr and "testbed calibrate" in p.stderr,
          "predict without costs names %s and testbed calibrate: %r" % (default, p.stderr))

    # 2. the mini calibration, to the default path
    runs_csv = os.path.join(TMP, "runs.csv")
    run("calibrate", "--set", "quick", "--runs", runs_csv)
    check(os.path.exists(default), "calibrate without -o writes " + default)
    costs = json.load(open(default))
    check(costs["schema"] == "testbed-costs-5" and costs["threads"] >= 1, "COSTS.json schema and threads")
    check(len(costs["costs"]) >= 40, "COSTS.json has every term")
    for k, v in costs["costs"].items():
        check(isinstance(v, (int, float)) and math.isfinite(v) and v >= 0, "cost %s = %r is finite and >= 0" % (k, v))
    check(set(costs["fit"]) == set(MODULES), "COSTS.json reports every module's fit")
    with open(runs_csv) as f:
        lines = f.read().splitlines()
    check(len(lines) == 17 and lines[0].startswith("run,method,kind"), "runs CSV: a header and 16 runs")
    # the renders record whether they probed the Vulkan device (--backend auto): the ray tracer always,
    # radiosity never
    import csv
    for r in csv.DictReader(lines):
        want = {"raytrace": "1", "radiosity": "0"}.get(r["method"])
        check(want is None or r["vulkan_probe"] == want,
              "run %s (%s): vulkan_probe %s, expected %s" % (r["run"], r["method"], r["vulkan_probe"], want))
        check(float(r["image_bytes"]) > 0, "run %s: the PNG's bytes estimated" % r["run"])

    # 3. predict --json for every method, and the text output
    for method, extra in (("raytrace", []), ("path", ["--spp", "2"]), ("radiosity", ["--max-edge", "3"])):
        p = run("predict", scene, "--method", method, *extra, "--json")
        d = json.loads(p.stdout)
        for k in ("seconds", "peak_rss_bytes", "modules"):
            check(k in d, "predict --json has %r" % k)
        check(d["method"] == method, "predict --json names the method")
        check(math.isfinite(d["seconds"]) and d["seconds"] > 0, "%s: seconds %r > 0" % (method, d["seconds"]))
        check(math.isfinite(d["peak_rss_bytes"]) and d["peak_rss_bytes"] > 1e6,
              "%s: peak_rss_bytes %r" % (method, d["peak_rss_bytes"]))
        check(set(d["modules"]) == set(MODULES), "%s: every module" % method)
        total = sum(v for k, v in d["modules"].items() if k != "memory")
        check(abs(total - d["seconds"]) <= 1e-4 * d["seconds"] + 1e-9, "%s: modules sum to seconds" % method)
        check(abs(d["modules"]["memory"] - d["peak_rss_bytes"]) <= 1e-3 * d["peak_rss_bytes"],
              "%s: the memory module is the peak" % method)
        check(d["statistics"]["pixels"] > 0, "%s: statistics gathered" % method)
    # channels: the spectral Cornell box counts 31 per sample and hit, its RGB twin 3
    here = os.path.dirname(os.path.abspath(__file__))
    for name, ch in (("cornell-box.mid", 31), ("cornell-box-rgb.mid", 3)):
        box = os.path.join(here, "..", "..", "scenes", name)
        s = json.loads(run("predict", box, "--method", "path", "--spp", "1", "--pilot", "16", "--json").stdout)["statistics"]
        check(s["camera_samples"] > 0 and s["hits"] > 0, "%s: work counted" % name)
        check(abs(s["sample_channels"] - ch * s["camera_samples"]) <= 1e-6 * s["sample_channels"]
              and abs(s["hit_channels"] - ch * s["hits"]) <= 1e-6 * s["hit_channels"]
              and abs(s["pixel_channels"] - ch * s["pixels"]) <= 1e-6 * s["pixel_channels"],
              "%s: %d channels per sample, hit and pixel: %r" % (name, ch, s))
        check(s["leaf_tests"] > 0, "%s: leaf tests (triangles) counted" % name)
        # Lambert and area lights only: the Vulkan path tracer takes the box, so auto probes the device
        check(s["vulkan_probe"] == 1 and s["noise_octaves"] == 0, "%s: probes Vulkan, no noise: %r" % (name, s))
    def stats(path, *args):
        return json.loads(run("predict", path, "--pilot", "16", *args, "--json").stdout)["statistics"]
    box = os.path.join(here, "..", "..", "scenes", "cornell-box-rgb.mid")
    check(stats(box, "--method", "path", "--spp", "1", "--backend", "cpu")["vulkan_probe"] == 0,
          "--backend cpu: no Vulkan probe")
    check(stats(box, "--method", "path", "--spp", "1", "--adaptive")["vulkan_probe"] == 0,
          "adaptive path tracing renders on the CPU without asking Vulkan")
    check(stats(scene, "--method", "raytrace")["vulkan_probe"] == 1, "the ray tracer probes with auto")
    check(stats(scene, "--method", "raytrace", "--backend", "cpu")["vulkan_probe"] == 0, "... not with cpu")
    check("is not modelled" in run("predict", scene, "--backend", "vulkan", expect=2).stderr,
          "--backend vulkan is refused")
    # materials.mid: noise patterns and bump maps, which the Vulkan path tracer takes: auto probes
    s = stats(os.path.join(here, "..", "..", "scenes", "materials.mid"), "--method", "path", "--spp", "1")
    check(s["vulkan_probe"] == 1 and s["noise_octaves"] > s["hits"], "materials: noise octaves counted: %r" % s)
    # a pattern on a torus: the kernel refuses it (its (u, v) is not on the device), so render never probes
    refused = os.path.join(TMP, "refused.mid")
    with open(refused, "w") as f:
        f.write('mid 1.1\ncamera "c" { eye = [0 -6 3] look_at = [0 0 0] up = [0 0 1] fov = 45 resolution = [24 24] }\n'
                'point_light "l" { position = [0 -3 4] intensity = 10 }\n'
                'torus "t" { geometry = { major = 1 minor = 0.3 } rendering = { diffuse = 0.5 '
                'diffuse_pattern = checker(8, 0.2, 0.8) } }\n')
    check(stats(refused, "--method", "path", "--spp", "1")["vulkan_probe"] == 0,
          "a scene the Vulkan path tracer refuses: no probe")
    # the radiosity image traces ceil(sqrt(spp))^2 rays per pixel; the pilot image counts its leaf tests
    s = stats(scene, "--method", "radiosity", "--max-edge", "3", "--spp", "2")
    check(abs(s["rad_pixel_rays"] - 4 * s["pixels"]) <= 1e-5 * s["rad_pixel_rays"] and s["rad_pixel_leaf_tests"] > 0 and s["vulkan_probe"] == 0,
          "radiosity image rays and leaf tests: %r" % s)
    p = run("predict", scene, "--costs", default)
    for m in ("load", "raytrace", "process", "memory"):
        check(m in p.stdout, "text output names module %s: %r" % (m, p.stdout))

    # 4b. a broken COSTS.json: located error, exit 1
    bad = os.path.join(TMP, "bad.json")
    with open(bad, "w") as f:
        f.write('{\n  "schema": "testbed-costs-5",\n  "threads": 2,\n  "costs": {"load.fixed": oops}\n}\n')
    p = run("predict", scene, "--costs", bad, expect=1)
    check(bad + ":4:27: error: expected a number" in p.stderr, "bad COSTS.json located: %r" % p.stderr)

    # 5. memory of a held-out generated scene within +-25% of the measured peak
    held = os.path.join(TMP, "held.mid")
    run("generate", "grid", "--count", "40", "--seed", "9", "-o", held)
    d = json.loads(run("predict", held, "--method", "raytrace", "--json").stdout)
    proc = subprocess.Popen([TB, "render", held, "--method", "raytrace", "-o", os.path.join(TMP, "m.png")],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=ENV)
    _, status, ru = os.wait4(proc.pid, 0)
    check(os.waitstatus_to_exitcode(status) == 0, "the held-out render runs")
    measured = ru.ru_maxrss * 1024.0
    # the PNG-byte estimate (the pilot's image, 1/4 each way, x 16) against the PNG the render wrote; a view
    # of mostly sky (this open grid) has fewer bytes per pixel than the closed Cornell box
    png = os.path.getsize(os.path.join(TMP, "m.png"))
    est = d["statistics"]["image_bytes"]
    check(0.5 * png <= est <= 4.0 * png, "PNG bytes estimated %.0f, written %d" % (est, png))
    sb = stats(box, "--method", "raytrace")
    check(sb["image_bytes"] / sb["pixels"] > 2.0 * est / d["statistics"]["pixels"],
          "the Cornell box's PNG bytes per pixel %.3f > twice the open grid's %.3f"
          % (sb["image_bytes"] / sb["pixels"], est / d["statistics"]["pixels"]))
    ratio = d["peak_rss_bytes"] / measured
    print("memory: predicted %.1f MiB, measured %.1f MiB, ratio %.3f"
          % (d["peak_rss_bytes"] / 2**20, measured / 2**20, ratio))
    check(0.75 <= ratio <= 1.25, "predicted peak memory within 25%% of the measured (ratio %.3f)" % ratio)
    shutil.rmtree(TMP)
    print("predict_cli: all checks passed")


if __name__ == "__main__":
    main()
