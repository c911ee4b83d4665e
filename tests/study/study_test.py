#!/usr/bin/env python3
"""`testbed study` end to end (docs/study.md), on the Cornell box at 32 x 32.

1. Usage errors exit 2 with a message naming the problem; a missing scene
   exits 1; neither leaves an output folder behind.
2. Convergence: the path tracer at 8, 16, 32, 64, 128 spp over several
   seeds against a fixed reference (path, 2048 spp, rendered once by the
   study and cached in DIR): the least-squares slope of log relMSE on log
   spp over every cell is -1 +- 0.15 (Monte Carlo variance falls as 1/N),
   and the slope the study itself reports in study.json is the same number.
   Not from 1 spp: relMSE weights the box's dark corners up, where rare
   paths to the light make the error's distribution heavy-tailed, so below
   about 8 spp a typical render's relMSE falls slower than its expectation
   (a slope of about -0.76 over 1 .. 16 spp; docs/study.md).
3. Outputs: cells.csv has a row per cell, study.json the means and 95% CIs
   (checked against the CSV), index.html parses with html.parser with every
   tag balanced and links only files that exist, the plots exist (PNG + SVG).
4. Resume: the same command again renders nothing (study.json and the
   summary line say 0 rendered) and leaves every cell file untouched; one
   more budget renders only its cells; Ctrl-C (SIGINT to the process group
   once a cell is finished) exits 130, keeps finished cells, leaves no
   partial image and no report, and a rerun renders exactly the rest.
   Seconds budgets reach each render as --time-budget.
5. Every method: raytrace, radiosity (coarse elements), hybrid and path at
   two budgets, with a reference given by --reference.

Environment: TESTBED, TB_SOURCE_DIR, TB_TEST_TMPDIR; TB_STUDY_TEST_SEEDS
(default 4) scales the convergence study."""
import csv
import glob
import html.parser
import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import time

TESTBED = os.environ["TESTBED"]
SRC = os.environ["TB_SOURCE_DIR"]
TMP = os.path.join(os.environ.get("TB_TEST_TMPDIR", "/tmp"), "study_test.%d" % os.getpid())
SEEDS = int(os.environ.get("TB_STUDY_TEST_SEEDS", "4"))


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def run(args, expect=0, what=""):
    p = subprocess.run([TESTBED, "study"] + args, capture_output=True, text=True,
                       env=dict(os.environ, OMP_WAIT_POLICY="passive"))
    if p.returncode != expect:
        fail("%s: exit %d, expected %d\nstdout: %s\nstderr: %s" % (what or args, p.returncode, expect,
                                                                   p.stdout, p.stderr))
    return p


def fit_loglog(xs, ys):
    lx = [math.log10(x) for x in xs]
    ly = [math.log10(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    sxy = sum((a - mx) * (b - my) for a, b in zip(lx, ly))
    sxx = sum((a - mx) ** 2 for a in lx)
    return sxy / sxx


class Checker(html.parser.HTMLParser):
    """Balanced tags (void elements excepted) and every href/src."""
    VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta", "source", "track", "wbr"}

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.stack, self.links, self.errors = [], [], []

    def handle_starttag(self, tag, attrs):
        for k, v in attrs:
            if k in ("href", "src"):
                self.links.append(v)
        if tag not in self.VOID:
            self.stack.append((tag, self.getpos()))

    def handle_startendtag(self, tag, attrs):
        for k, v in attrs:
            if k in ("href", "src"):
                self.links.append(v)

    def handle_endtag(self, tag):
        if tag in self.VOID:
            self.errors.append("end tag of void element <%s> at %s" % (tag, self.getpos()))
        elif not self.stack or self.stack[-1][0] != tag:
            self.errors.append("</%s> at %s closes %s" % (tag, self.getpos(), self.stack[-1] if self.stack else None))
        else:
            self.stack.pop()


def check_html(out):
    page = os.path.join(out, "index.html")
    text = open(page, encoding="utf-8").read()
    if not text.startswith("<!DOCTYPE html>"):
        fail("index.html has no doctype")
    c = Checker()
    c.feed(text)
    c.close()
    if c.errors or c.stack:
        fail("index.html is not balanced: %s; left open: %s" % (c.errors[:5], c.stack[:5]))
    if not c.links:
        fail("index.html links nothing")
    for link in c.links:
        if re.match(r"^[a-z]+:", link) or link.startswith("/") or ".." in link:
            fail("index.html links outside the study: %s" % link)
        if not os.path.isfile(os.path.join(out, link)):
            fail("index.html links %s, which does not exist" % link)
    return c.links


def snapshot(out):
    """Every file under out/cells with its modification time and size."""
    snap = {}
    for root, _, files in os.walk(os.path.join(out, "cells")):
        for f in files:
            st = os.stat(os.path.join(root, f))
            snap[os.path.join(root, f)] = (st.st_mtime_ns, st.st_size)
    return snap


def main():
    shutil.rmtree(TMP, ignore_errors=True)
    os.makedirs(TMP)
    box = os.path.join(TMP, "box.mid")
    with open(os.path.join(SRC, "scenes", "cornell-box-rgb.mid")) as f:
        text = f.read()
    small = text.replace("resolution = [512 512]", "resolution = [32 32]")
    if small == text:
        fail("could not shrink the Cornell box's resolution")
    open(box, "w").write(small)

    # 1. usage errors: exit 2, a message, no output folder
    bad = os.path.join(TMP, "bad")
    cases = [
        ([box], "no output folder"),
        ([box, "-o", bad, "--methods", "path,foo"], "unknown method 'foo'"),
        ([box, "-o", bad, "--methods", "path,path"], "given twice"),
        ([box, "-o", bad, "--budgets", "4,2"], "must increase"),
        ([box, "-o", bad, "--budgets", "1,x"], "expected positive numbers"),
        ([box, "-o", bad, "--budgets", "0.5,1"], "not a whole number"),
        ([box, "-o", bad, "--seeds", "0"], "--seeds"),
        ([box, box, "-o", bad, "--reference", box], "1 --reference image(s) for 2 scene(s)"),
        ([box, "-o", bad, "--reference", box, "--reference-spp", "8"], "not with --reference"),
        ([box, "-o", bad, "--args", "path=--spp 3"], "--spp is set by the study"),
        ([box, "-o", bad, "--args", "radiosity=--max-edge 3"], "--max-edge is set by the study"),
        ([box, "-o", bad, "--args", "nope=--x"], "expected METHOD=OPTIONS"),
        (["-o", bad], "no SCENE.mid given"),
    ]
    for args, msg in cases:
        p = run(args, 2, "usage error %s" % args)
        if msg not in p.stderr:
            fail("usage error %s: expected '%s' in: %s" % (args, msg, p.stderr))
    p = run([os.path.join(TMP, "missing.mid"), "-o", bad], 1, "missing scene")
    if "missing.mid" not in p.stderr:
        fail("missing scene: the message does not name it: " + p.stderr)
    p = run([box, "-o", bad, "--reference", os.path.join(TMP, "nope.exr")], 1, "missing reference")
    if "nope.exr" not in p.stderr:
        fail("missing reference: the message does not name it: " + p.stderr)
    tiny = os.path.join(TMP, "tiny.mid")
    open(tiny, "w").write(text.replace("resolution = [512 512]", "resolution = [16 16]"))
    tiny_ref = os.path.join(TMP, "tiny.exr")
    subprocess.run([TESTBED, "render", tiny, "--spp", "1", "--backend", "cpu", "-o", tiny_ref], check=True,
                   capture_output=True)
    p = run([box, "-o", bad, "--reference", tiny_ref], 1, "reference of another size")
    if "is 16x16, the renders of" not in p.stderr or "32x32" not in p.stderr:
        fail("reference of another size: " + p.stderr)
    if os.path.exists(bad):
        fail("a failed study left %s behind" % bad)
    # a render that fails: exit 1, the cell and the end of its log named, no report
    p = run([box, "-o", bad, "--methods", "path", "--budgets", "1", "--seeds", "1", "--reference-spp", "1",
             "--args", "path=--max-depth 9999"], 1, "failing render")
    if "failed (exit status 2)" not in p.stderr or "log.txt" not in p.stderr or "--max-depth" not in p.stderr:
        fail("failing render: " + p.stderr)
    if os.path.exists(os.path.join(bad, "index.html")) or os.path.exists(os.path.join(bad, "study.json")):
        fail("a failed study wrote its report")

    # 2. convergence of the path tracer
    out = os.path.join(TMP, "conv")
    budgets = [8, 16, 32, 64, 128]
    args = [box, "-o", out, "--methods", "path", "--budgets", ",".join(map(str, budgets)),
            "--seeds", str(SEEDS), "--reference-spp", "2048", "--threads", "2"]
    p = run(args, 0, "convergence study")
    total = len(budgets) * SEEDS
    if "%d cells: %d rendered, 0 reused" % (total, total) not in p.stdout:
        fail("first run's summary line: " + p.stdout)
    rows = list(csv.DictReader(open(os.path.join(out, "cells.csv"))))
    if len(rows) != total:
        fail("cells.csv has %d rows, expected %d" % (len(rows), total))
    xs = [float(r["budget"]) for r in rows]
    ys = [float(r["relmse"]) for r in rows]
    if not all(y > 0 and math.isfinite(y) for y in ys):
        fail("relMSE not positive and finite: %s" % ys)
    slope = fit_loglog(xs, ys)
    print("path relMSE slope over %d cells: %.3f" % (len(rows), slope))
    if not -1.15 <= slope <= -0.85:
        fail("path tracer relMSE slope %.3f, expected -1 +- 0.15" % slope)
    j = json.load(open(os.path.join(out, "study.json")))
    conv = j["scenes"][0]["convergence"][0]
    if conv["method"] != "path" or abs(conv["relmse_vs_budget"]["slope"] - slope) > 1e-6:
        fail("study.json's slope %s is not the test's %.6f" % (conv, slope))
    if j["cells_rendered"] != total or j["cells_reused"] != 0:
        fail("study.json counts: %s rendered, %s reused" % (j["cells_rendered"], j["cells_reused"]))
    ref = j["scenes"][0]["reference"]
    if ref["given"] or ref["method"] != "path" or ref["spp"] != 2048 or not os.path.isfile(ref["path"]):
        fail("reference record: %s" % ref)
    # the summary's mean and CI agree with the cells
    tq = [12.7062, 4.3027, 3.1824, 2.7764, 2.5706, 2.4469, 2.3646, 2.3060, 2.2622, 2.2281]
    for srow in j["scenes"][0]["summary"]:
        vals = [float(r["relmse"]) for r in rows if float(r["budget"]) == srow["budget"]]
        mean = sum(vals) / len(vals)
        if abs(srow["relmse"]["mean"] - mean) > 1e-6 * mean:
            fail("summary mean %s vs cells %s" % (srow["relmse"]["mean"], mean))
        if len(vals) > 1 and len(vals) <= 11:
            sd = math.sqrt(sum((v - mean) ** 2 for v in vals) / (len(vals) - 1))
            ci = tq[len(vals) - 2] * sd / math.sqrt(len(vals))
            if abs(srow["relmse"]["ci95"] - ci) > 1e-4 * ci:
                fail("summary CI %s vs cells %s" % (srow["relmse"]["ci95"], ci))
        if not (srow["wall_seconds"]["mean"] > 0 and srow["peak_rss_bytes"]["max"] > 1e6):
            fail("time or memory missing: %s" % srow)
    for cell in j["cells"]:
        stats = json.load(open(os.path.join(out, cell["dir"], "stats.json")))
        if "method=path" not in stats["provenance"]["options"]:
            fail("%s: not a path-traced cell: %s" % (cell["dir"], stats["provenance"]["options"]))
    for plot in ("error-time", "error-budget"):
        for ext in ("png", "svg"):
            if not os.path.isfile(os.path.join(out, "plots", "box-%s.%s" % (plot, ext))):
                fail("missing plot %s.%s" % (plot, ext))
    links = check_html(out)
    if "plots/box-error-time.png" not in links or "images/box/reference.png" not in links:
        fail("index.html does not show the plots and the reference: %s" % links[:10])

    # 4. resume: nothing rendered again, nothing touched
    before = snapshot(out)
    p = run(args, 0, "resumed study")
    if "%d cells: 0 rendered, %d reused" % (total, total) not in p.stdout:
        fail("second run rendered again: " + p.stdout)
    j2 = json.load(open(os.path.join(out, "study.json")))
    if j2["cells_rendered"] != 0 or not all(c["reused"] for c in j2["cells"]):
        fail("study.json of the second run: %s rendered" % j2["cells_rendered"])
    if snapshot(out) != before:
        fail("the second run changed files under cells/")
    # a cell whose image was deleted renders again, alone
    victim = os.path.join(out, j2["cells"][0]["dir"], "image.exr")
    os.remove(victim)
    p = run(args, 0, "a deleted image")
    if "%d cells: 1 rendered, %d reused" % (total, total - 1) not in p.stdout or not os.path.isfile(victim):
        fail("a deleted image should render its cell again: " + p.stdout)
    # a changed option is another key: only those cells render again
    p = run(args[:-2] + ["--threads", "1", "--budgets", "4," + ",".join(map(str, budgets))], 0, "one more budget")
    if "%d cells: %d rendered, %d reused" % (total + SEEDS, SEEDS, total) not in p.stdout:
        fail("one more budget should render %d cells: %s" % (SEEDS, p.stdout))

    # Ctrl-C: the study stops after the running render (exit 130), keeps the
    # finished cells, leaves no image or mark in the interrupted one; a rerun
    # renders exactly the rest
    out3 = os.path.join(TMP, "intr")
    iargs = [box, "-o", out3, "--methods", "path", "--budgets", "64", "--seeds", "8", "--reference", ref["path"],
             "--threads", "1"]
    p = subprocess.Popen([TESTBED, "study"] + iargs, start_new_session=True, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    cells = os.path.join(out3, "cells", "box", "path")
    while p.poll() is None and not glob.glob(os.path.join(cells, "*", "cell.json")):
        time.sleep(0.02)
    os.killpg(p.pid, signal.SIGINT)
    pout, perr = p.communicate()
    if p.returncode == 0:
        print("note: the study finished before Ctrl-C arrived; interrupt not exercised")
    else:
        if p.returncode != 130 or "interrupted;" not in perr or "run the same command again" not in perr:
            fail("Ctrl-C: exit %d, stderr: %s" % (p.returncode, perr))
        done = [d for d in os.listdir(cells) if os.path.isfile(os.path.join(cells, d, "cell.json"))]
        for d in os.listdir(cells):
            if d not in done and os.path.exists(os.path.join(cells, d, "image.exr")):
                fail("the interrupted cell %s kept its partial image" % d)
        if not 1 <= len(done) < 8:
            fail("after Ctrl-C %d cells are finished" % len(done))
        for f in ("index.html", "study.json", "cells.csv", "report.md"):
            if os.path.exists(os.path.join(out3, f)):
                fail("an interrupted study wrote %s" % f)
        p = run(iargs, 0, "resume after Ctrl-C")
        if "8 cells: %d rendered, %d reused" % (8 - len(done), len(done)) not in p.stdout:
            fail("resume after Ctrl-C with %d finished: %s" % (len(done), p.stdout))

    # seconds budgets: each renderer's --time-budget
    out4 = os.path.join(TMP, "sec")
    run([box, "-o", out4, "--methods", "path,raytrace", "--budget-kind", "seconds", "--budgets", "0.05,0.1",
         "--seeds", "1", "--reference", ref["path"], "--threads", "2"], 0, "seconds budgets")
    j4 = json.load(open(os.path.join(out4, "study.json")))
    for cell in j4["cells"]:
        cmd = json.load(open(os.path.join(out4, cell["dir"], "stats.json")))["provenance"]["command_line"]
        if "--time-budget %g" % cell["budget"] not in cmd:
            fail("seconds cell %s: command line %s" % (cell["dir"], cmd))
        if cell["relmse"] is None or cell["ssim"] is None or j4["budget_kind"] != "seconds":
            fail("seconds cell without errors: %s" % cell)
    check_html(out4)

    # 5. every method, with a given reference
    out2 = os.path.join(TMP, "all")
    p = run([box, "-o", out2, "--methods", "raytrace,radiosity,hybrid,path", "--budgets", "1,4", "--seeds", "2",
             "--reference", ref["path"], "--radiosity-edge", "150", "--args", "hybrid=--max-edge 150",
             "--threads", "2"], 0, "every method")
    j3 = json.load(open(os.path.join(out2, "study.json")))
    if j3["methods"] != ["raytrace", "radiosity", "hybrid", "path"] or len(j3["cells"]) != 16:
        fail("every-method study: %s, %d cells" % (j3["methods"], len(j3["cells"])))
    if not j3["scenes"][0]["reference"]["given"]:
        fail("the given reference is not recorded as given")
    for cell in j3["cells"]:
        if not (cell["relmse"] is not None and cell["relmse"] > 0 and cell["ssim"] is not None):
            fail("cell without errors: %s" % cell)
    rad = [c for c in j3["cells"] if c["method"] == "radiosity"]
    edges = set()
    for c in rad:
        opts = json.load(open(os.path.join(out2, c["dir"], "stats.json")))["provenance"]["options"]
        edges.add(re.search(r"max_edge=([0-9.e+-]+)", opts).group(1) if "max_edge=" in opts else opts)
    if len(edges) != 2:
        fail("radiosity budgets 1 and 4 should mesh differently: %s" % edges)
    check_html(out2)
    md = open(os.path.join(out2, "report.md")).read()
    for m in ("raytrace", "radiosity", "hybrid", "path"):
        if "| %s |" % m not in md:
            fail("report.md has no row for %s" % m)
    shutil.rmtree(TMP, ignore_errors=True)
    print("ok")


main()
