#!/usr/bin/env python3
"""testbed render (the Whitted ray tracer) against analytic answers.

1. Furnace: a closed cube of inward-facing polygons that emit M (RGB) with
   zero reflectance, camera inside: every pixel is M / pi.
2. Mirror: a mirror of specular colour ks fills the view and reflects an
   emitter facing it: every pixel is ks * M / pi (emitters seen through a
   mirror are not lit by light sampling: the material has no diffuse part);
   with uniform specular and emission textures ts, te: ks ts M te / pi.
3. Glass slab at normal incidence (ior 1.5, transmission 1, R = 0.04), an
   emitter behind it, a 0.2-degree field of view: with max depth 2 only the
   straight path reaches the emitter, L = (1 - R)^2 M / pi; with max depth 64
   every internal round trip is traced, L = (1 - R)^2 / (1 - R^2) M / pi;
   a uniform transmission texture tt on both faces, depth 2: (1 - R)^2 tt^2;
   depth 64 with --adc-bailout 0.01 (adaptive depth control) stops the
   round trips, whose weights are (1 - R)^2 R^(2k): (1 - R)^2 again.
4. Direct lighting: a point light of intensity I at height h above a grey
   Lambertian floor, the camera looking straight down through a 0.2-degree
   field of view: L = rho / pi * I / h^2 at the centre.
5. Cornell box (1 spp, 1 light sample): no NaN or Inf, the red wall on the
   left (mean red of the left third above that of the right third), byte-
   identical PFM files for --threads 1 and 2, and for --accel bvh and grid;
   provenance attributes in an EXR.
6. Texture filtering from ray differentials: a grazing floor (rho = 1) under
   a directional light of irradiance pi (shading factor rho E / pi = 1) with
   a 512x512 one-texel black/white checker image: in the far rows, where a
   pixel covers many checks, the default EWA filter gives the mean 0.5 with
   a tiny spread, trilinear the mean 0.5, and --texture-filter bilinear at
   1 spp (no prefiltering) a large spread (aliasing).
7. Emitters of curved primitives (analytic) and CSG objects (tessellated): an emissive cube (exitance M, edge 1) above
   a Lambertian floor, seen at a floor point P off to one side: the bottom
   face and one vertical face see P, E(P) = M (F_bottom + F_side) with each
   form factor from the polygon contour integral (Lambert),
   F = |sum_i beta_i (n . unit(R_i x R_i+1))| / (2 pi), and L = rho E / pi
   (1%). The same cube as a CSG intersection with a large sphere gives the
   same value; a sphere of radius r under a (barely) non-uniform scale, at
   height d above P, gives E = M r^2 / d^2 (1%).
8. MID 1.1 materials: a GGX sphere (alpha 0.5, F0 1) in the furnace box shows
   its albedo at normal incidence, 0.68785 (docs/shading.md), to 0.01;
   scenes/materials.mid at 64 x 36 is finite and the same for 1 and 2
   threads.
"""
import math
import os
import signal
import struct
import subprocess
import sys

TESTBED = os.environ["TESTBED"]
SRC = os.environ["TB_SOURCE_DIR"]
TMP = os.environ.get("TB_TEST_TMPDIR", "/tmp")
os.makedirs(TMP, exist_ok=True)
failures = 0


def check(cond, what):
    global failures
    if cond:
        print("ok:", what)
    else:
        print("FAIL:", what)
        failures += 1


def run(args, expect=0):
    p = subprocess.run([TESTBED, "render"] + args, capture_output=True, text=True,
                       env=dict(os.environ, TB_NO_PROGRESS="1"))
    if p.returncode != expect:
        print(p.stdout, p.stderr)
        raise SystemExit("testbed render %s: exit %d" % (" ".join(args), p.returncode))
    return p


def read_pfm(path):
    with open(path, "rb") as f:
        data = f.read()
    parts = []
    pos = 0
    while len(parts) < 4:  # PF, w, h, scale separated by whitespace
        while data[pos:pos + 1].isspace():
            pos += 1
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        parts.append(data[pos:end].decode())
        pos = end
    pos += 1
    assert parts[0] == "PF", parts
    w, h, scale = int(parts[1]), int(parts[2]), float(parts[3])
    fmt = ("<" if scale < 0 else ">") + "%df" % (w * h * 3)
    vals = struct.unpack_from(fmt, data, pos)
    rows = [vals[(h - 1 - y) * w * 3:(h - y) * w * 3] for y in range(h)]  # bottom-up file, top row first
    return w, h, rows


def write(name, text):
    path = os.path.join(TMP, name)
    with open(path, "w") as f:
        f.write(text)
    return path


def quad(name, verts, material):
    v = " ".join("[%g %g %g]" % p for p in verts)
    return 'polygons "%s" {\n geometry = { vertices = [%s] faces = [[0 1 2 3]] }\n rendering = { %s }\n}\n' % (
        name, v, material)


def max_rel_err(rows, expect):
    worst = 0.0
    for row in rows:
        for i, x in enumerate(row):
            e = expect[i % 3]
            worst = max(worst, abs(x - e) / e)
    return worst


# ------------------------------------------------------------- 1. furnace
M = (2.0, 3.0, 5.0)
mat = "diffuse = 0 emission = [%g %g %g]" % M
s = 1.0
cube = ""
# Each face as listed turns counter-clockwise seen from outside the cube.
faces = {
    "bottom": [(-s, -s, -s), (s, -s, -s), (s, -s, s), (-s, -s, s)],
    "top": [(-s, s, -s), (-s, s, s), (s, s, s), (s, s, -s)],
    "left": [(-s, -s, -s), (-s, -s, s), (-s, s, s), (-s, s, -s)],
    "right": [(s, -s, -s), (s, s, -s), (s, s, s), (s, -s, s)],
    "back": [(-s, -s, -s), (-s, s, -s), (s, s, -s), (s, -s, -s)],
    "front": [(-s, -s, s), (s, -s, s), (s, s, s), (-s, s, s)],
}
for k, v in faces.items():
    cube += quad(k, v[::-1], mat)  # listed outward-facing; reversed to face in
cam = 'camera { eye = [0.1 0.2 0.05] look_at = [0.5 0.1 1] up = [0 1 0] fov = 120 resolution = [24 16] }\n'
furnace = write("rt_furnace.mid", "mid 1\n" + cam + cube)
out = os.path.join(TMP, "rt_furnace.pfm")
run([furnace, "-o", out, "--spp", "4", "--threads", "2"])
w, h, rows = read_pfm(out)
expect = [m / math.pi for m in M]
err = max_rel_err(rows, expect)
check(err < 2e-6, "furnace: every pixel is M/pi (max relative error %.3g)" % err)

# --report: the furnace has no noise, so every pass has relMSE 0 against a
# reference rendering of it; one row per pass with the running spp.
ref = os.path.join(TMP, "rt_furnace_ref.exr")
rep = os.path.join(TMP, "rt_furnace_report.csv")
run([furnace, "-o", ref, "--spp", "2"])
run([furnace, "-o", os.path.join(TMP, "rt_furnace_rep.exr"), "--spp", "1", "--passes", "3",
     "--report", rep, "--reference", ref])
rows_csv = [l.strip().split(",") for l in open(rep) if l.strip()]
check(rows_csv[0] == ["seconds", "spp", "relmse"] and [r[1] for r in rows_csv[1:]] == ["1", "2", "3"]
      and all(float(r[2]) < 1e-12 for r in rows_csv[1:]),
      "--report: a row per pass, relMSE 0 in the furnace: %r" % rows_csv)

# -------------------------------------------------------------- 2. mirror
ks = (0.9, 0.5, 0.25)
Me = (4.0, 4.0, 4.0)
scene = "mid 1\n"
scene += 'camera { eye = [0 0 1] look_at = [0 0 0] up = [0 1 0] fov = 30 resolution = [16 16] }\n'
# Mirror in z = 0 facing +z; emitter in z = 2 facing -z, both 100 wide.
scene += quad("mirror", [(-50, -50, 0), (50, -50, 0), (50, 50, 0), (-50, 50, 0)],
              "diffuse = 0 specular = [%g %g %g]" % ks)
scene += quad("lamp", [(-50, -50, 2), (-50, 50, 2), (50, 50, 2), (50, -50, 2)],
              "diffuse = 0 emission = [%g %g %g]" % Me)
mirror = write("rt_mirror.mid", scene)
out = os.path.join(TMP, "rt_mirror.pfm")
run([mirror, "-o", out, "--spp", "2"])
w, h, rows = read_pfm(out)
expect = [k * m / math.pi for k, m in zip(ks, Me)]
err = max_rel_err(rows, expect)
check(err < 2e-6, "mirror: ks M / pi in every pixel (max relative error %.3g)" % err)

# Specular and emission textures multiply those colours: uniform 2x2 PFM
# textures ts on the mirror and te on the lamp give ks ts M te / pi.
ts, te = (0.5, 0.25, 1.0), (1.0, 0.5, 0.75)
for name, t in (("rt_tex_s.pfm", ts), ("rt_tex_e.pfm", te)):
    with open(os.path.join(TMP, name), "wb") as f:
        f.write(b"PF\n2 2\n-1.0\n" + struct.pack("<12f", *(t * 4)))
scene_t = scene.replace("specular = [%g %g %g]" % ks, 'specular = [%g %g %g] specular_texture = file("rt_tex_s.pfm")' % ks)
scene_t = scene_t.replace("emission = [%g %g %g]" % Me, 'emission = [%g %g %g] emission_texture = file("rt_tex_e.pfm")' % Me)
mirror_t = write("rt_mirror_tex.mid", scene_t)
out = os.path.join(TMP, "rt_mirror_tex.pfm")
run([mirror_t, "-o", out, "--spp", "2"])
w, h, rows = read_pfm(out)
expect = [k * a * m * b / math.pi for k, a, m, b in zip(ks, ts, Me, te)]
err = max_rel_err(rows, expect)
check(err < 2e-6, "specular and emission textures: ks ts M te / pi in every pixel (max relative error %.3g)" % err)

# --------------------------------------------------------------- 3. glass slab
R = ((1.5 - 1) / (1.5 + 1)) ** 2
scene = "mid 1\n"
scene += 'camera { eye = [0 0 10] look_at = [0 0 0] up = [0 1 0] fov = 0.2 resolution = [3 3] }\n'
glass = "diffuse = 0 transmission = 1 ior = 1.5"
scene += quad("front", [(-5, -5, 1), (5, -5, 1), (5, 5, 1), (-5, 5, 1)], glass)   # normal +z (out)
scene += quad("back", [(-5, -5, 0), (-5, 5, 0), (5, 5, 0), (5, -5, 0)], glass)    # normal -z (out)
scene += quad("lamp", [(-50, -50, -3), (50, -50, -3), (50, 50, -3), (-50, 50, -3)],
              "diffuse = 0 emission = [%g %g %g]" % Me)  # faces +z, toward the slab
slab = write("rt_slab.mid", scene)
for depth, expect_t in ((2, (1 - R) ** 2), (64, (1 - R) ** 2 / (1 - R * R))):
    out = os.path.join(TMP, "rt_slab%d.pfm" % depth)
    run([slab, "-o", out, "--max-depth", str(depth)])
    w, h, rows = read_pfm(out)
    centre = rows[1][3:6]
    got = centre[0] / (Me[0] / math.pi)
    check(abs(got - expect_t) < 2e-5,
          "slab, max depth %d: transmittance %.7f, expected %.7f" % (depth, got, expect_t))

# Adaptive depth control: the exit ray of the k-th internal round trip has
# weight (1 - R)^2 R^(2k) (the rays inside more), so --adc-bailout 0.01 keeps
# only k = 0 at depth 64: T = (1 - R)^2 again; --adc-bailout 0 is the default
# bit for bit.
out0 = os.path.join(TMP, "rt_slab64_adc0.pfm")
run([slab, "-o", out0, "--max-depth", "64", "--adc-bailout", "0"])
with open(out0, "rb") as f0, open(os.path.join(TMP, "rt_slab64.pfm"), "rb") as f1:
    check(f0.read() == f1.read(), "slab, --adc-bailout 0: the image of the default, bit for bit")
out = os.path.join(TMP, "rt_slab64_adc.pfm")
run([slab, "-o", out, "--max-depth", "64", "--adc-bailout", "0.01"])
w, h, rows = read_pfm(out)
got = rows[1][3] / (Me[0] / math.pi)
check(abs(got - (1 - R) ** 2) < 2e-5,
      "slab, max depth 64, --adc-bailout 0.01: transmittance %.7f, expected (1 - R)^2 = %.7f" % (got, (1 - R) ** 2))
bad_out = os.path.join(TMP, "rt_slab_adc_bad.pfm")
for bad in ("-0.1", "1", "nan"):
    p = run([slab, "-o", bad_out, "--adc-bailout", bad], expect=2)
    check("--adc-bailout" in p.stderr and not os.path.exists(bad_out),
          "--adc-bailout %s is refused (exit 2, no image)" % bad)

# A uniform transmission texture tt on both faces: the straight path (max
# depth 2) passes both, T = (1 - R)^2 tt^2 per channel.
tt = (0.5, 0.25, 0.8)
with open(os.path.join(TMP, "rt_tex_t.pfm"), "wb") as f:
    f.write(b"PF\n2 2\n-1.0\n" + struct.pack("<12f", *(tt * 4)))
slab_t = write("rt_slab_tex.mid", scene.replace(glass, glass + ' transmission_texture = file("rt_tex_t.pfm")'))
out = os.path.join(TMP, "rt_slab_tex.pfm")
run([slab_t, "-o", out, "--max-depth", "2"])
w, h, rows = read_pfm(out)
got = [rows[1][3 + c] / (Me[c] / math.pi) for c in range(3)]
exp = [(1 - R) ** 2 * t * t for t in tt]
check(all(abs(g - e) < 2e-5 for g, e in zip(got, exp)),
      "transmission texture on the slab: T = %r, expected (1 - R)^2 tt^2 = %r" % (got, exp))

# ------------------------------------------------------------ 4. point light
I, hgt, rho = 50.0, 2.0, 0.5
scene = "mid 1\n"
scene += 'camera { eye = [0 5 0] look_at = [0 0 0] up = [0 0 -1] fov = 0.2 resolution = [3 3] }\n'
scene += 'point_light { position = [0 %g 0] intensity = [%g %g %g] }\n' % (hgt, I, I, I)
scene += quad("floor", [(-10, 0, -10), (-10, 0, 10), (10, 0, 10), (10, 0, -10)], "diffuse = %g" % rho)
pl = write("rt_point.mid", scene)
out = os.path.join(TMP, "rt_point.pfm")
run([pl, "-o", out])
w, h, rows = read_pfm(out)
got = rows[1][4]
exp = rho / math.pi * I / hgt ** 2
check(abs(got - exp) / exp < 1e-4, "point light: L = rho/pi I/h^2: %.7g, expected %.7g" % (got, exp))

# A diffuse texture multiplies the diffuse colour: a uniform 2x2 PFM texture
# on the same floor gives rho * tex / pi * I / h^2 per channel.
tex = (0.5, 0.25, 1.0)
with open(os.path.join(TMP, "rt_tex.pfm"), "wb") as f:
    f.write(b"PF\n2 2\n-1.0\n" + struct.pack("<12f", *(tex * 4)))
scene = scene.replace('diffuse = %g' % rho, 'diffuse = %g diffuse_texture = file("rt_tex.pfm")' % rho)
pt = write("rt_point_tex.mid", scene)
out = os.path.join(TMP, "rt_point_tex.pfm")
run([pt, "-o", out])
w, h, rows = read_pfm(out)
got = rows[1][3:6]
exp = [rho * t / math.pi * I / hgt ** 2 for t in tex]
check(all(abs(g - e) / e < 1e-4 for g, e in zip(got, exp)),
      "diffuse texture multiplies the colour: %r, expected %r" % (got, exp))


# ------------------------------------------------ 6. texture filtering (grazing checker)
n = 512
vals = []
for y in range(n):
    for x in range(n):
        c = float((x + y) & 1)
        vals += [c, c, c]
with open(os.path.join(TMP, "rt_checker.pfm"), "wb") as f:
    f.write(b"PF\n%d %d\n-1.0\n" % (n, n) + struct.pack("<%df" % len(vals), *vals))
scene = "mid 1\n"
scene += 'camera { eye = [0 1 0] look_at = [0 0 20] up = [0 1 0] fov = 30 resolution = [64 48] }\n'
scene += 'directional_light { direction = [0 -1 0] irradiance = [%.9g %.9g %.9g] }\n' % ((math.pi,) * 3)
scene += quad("floor", [(-100, 0, 0), (-100, 0, 100), (100, 0, 100), (100, 0, 0)],
              'diffuse = 1 diffuse_texture = file("rt_checker.pfm")')
gz = write("rt_grazing.mid", scene)
# Rows 24..33 of 48 look 3.5 to 9 degrees below the horizon: the floor fills
# them and one pixel spans many checks along the view direction.
far = range(24, 34)
stats = {}
for filt in ("ewa", "trilinear", "bilinear"):
    out = os.path.join(TMP, "rt_grazing_%s.pfm" % filt)
    run([gz, "-o", out, "--spp", "1", "--texture-filter", filt])
    w, h, rows = read_pfm(out)
    px = [rows[y][3 * x] for y in far for x in range(w)]
    mean = sum(px) / len(px)
    sd = math.sqrt(sum((p - mean) ** 2 for p in px) / len(px))
    stats[filt] = (mean, sd, min(px))
    print("grazing checker, %s: mean %.4f, standard deviation %.4f" % (filt, mean, sd))
m, sd, lo = stats["ewa"]
check(lo > 0 and abs(m - 0.5) < 0.01 and sd < 0.02,
      "EWA from ray differentials: far rows average the checker to 0.5 (mean %.4f, sd %.4f)" % (m, sd))
m, sd, lo = stats["trilinear"]
check(abs(m - 0.5) < 0.01, "trilinear: far rows average to 0.5 (mean %.4f, sd %.4f)" % (m, sd))
m, sd, lo = stats["bilinear"]
check(sd > 0.1, "bilinear at 1 spp aliases: far-row standard deviation %.4f > 0.1" % sd)


# ------------------- 7. emitters of curved primitives (analytic) and CSG objects (tessellated)
Mc, rho = 2.0, 0.5
P = (1.5, 0.0, 0.3)


def polygon_ff(poly, n):
    """Form factor from a differential area at P (normal n) to a polygon."""
    def sub(a, b):
        return [a[i] - b[i] for i in range(3)]

    def cross(a, b):
        return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]

    def dot(a, b):
        return sum(a[i] * b[i] for i in range(3))
    tot = 0.0
    for i in range(len(poly)):
        r0, r1 = sub(poly[i], P), sub(poly[(i + 1) % len(poly)], P)
        c = cross(r0, r1)
        cn = math.sqrt(dot(c, c))
        tot += math.atan2(cn, dot(r0, r1)) * dot(c, n) / cn
    return abs(tot) / (2 * math.pi)


def emitter_scene(name, obj):
    sc = "mid 1\n"
    sc += 'camera { eye = [3 1 %g] look_at = [%g %g %g] up = [0 1 0] fov = 0.2 resolution = [3 3] }\n' % (
        P[2], P[0], P[1], P[2])
    sc += obj
    sc += quad("floor", [(-10, 0, -10), (-10, 0, 10), (10, 0, 10), (10, 0, -10)], "diffuse = %g" % rho)
    path = write(name + ".mid", sc)
    out = os.path.join(TMP, name + ".pfm")
    run([path, "-o", out, "--spp", "16", "--light-samples", "1024"])
    w, h, rows = read_pfm(out)
    return sum(rows[y][3 * x] for y in range(h) for x in range(w)) / (w * h)


emit = "rendering = { diffuse = 0 emission = [%g %g %g] }" % (Mc, Mc, Mc)
hs = 0.5  # the cube [-1,1]^3 scaled by 0.5 and lifted to y in [1, 2]
bottom = [(-hs, 1, -hs), (hs, 1, -hs), (hs, 1, hs), (-hs, 1, hs)]
side = [(hs, 1, -hs), (hs, 2, -hs), (hs, 2, hs), (hs, 1, hs)]
exp = rho / math.pi * Mc * (polygon_ff(bottom, (0, 1, 0)) + polygon_ff(side, (0, 1, 0)))
got = emitter_scene("rt_emit_cube", 'cube "lamp" { transform = [scale(%g) translate([0 1.5 0])] %s }\n' % (hs, emit))
check(abs(got - exp) / exp < 0.01, "emissive cube lights the floor: L = %.6g, expected %.6g (contour integral)" % (got, exp))
got = emitter_scene("rt_emit_csg", 'intersection "lamp" { transform = [scale(%g) translate([0 1.5 0])] %s\n'
                    ' cube {} sphere { transform = [scale(5)] } }\n' % (hs, emit))
check(abs(got - exp) / exp < 0.01, "emissive CSG (cube within a sphere): L = %.6g, expected %.6g" % (got, exp))
r, d = 0.5, 2.0
exp = rho / math.pi * Mc * r * r / (d * d)
got = emitter_scene("rt_emit_ellipsoid", 'sphere "lamp" { transform = [scale([%.9g %g %g]) translate([%g %g %g])] %s }\n' % (
    r * (1 + 1e-6), r, r, P[0], d, P[2], emit))
check(abs(got - exp) / exp < 0.01, "emissive sphere under a non-uniform scale: L = %.6g, expected rho/pi M r^2/d^2 = %.6g"
      % (got, exp))

# ---------------------------------------------------------------- 5. Cornell box
cornell = os.path.join(SRC, "scenes", "cornell-box.mid")
common = [cornell, "--spp", "1", "--light-samples", "1", "--seed", "7"]
a = os.path.join(TMP, "rt_cb_t1.pfm")
b = os.path.join(TMP, "rt_cb_t2.pfm")
c = os.path.join(TMP, "rt_cb_grid.pfm")
run(common + ["-o", a, "--threads", "1"])
run(common + ["-o", b, "--threads", "2"])
run(common + ["-o", c, "--threads", "2", "--accel", "grid"])
da, db, dc = (open(p, "rb").read() for p in (a, b, c))
check(da == db, "Cornell box: --threads 1 and 2 give byte-identical images")
check(da == dc, "Cornell box: BVH and grid give byte-identical images")
w, h, rows = read_pfm(a)
finite = all(math.isfinite(x) for row in rows for x in row)
check(finite, "Cornell box: no NaN or Inf")
third = w // 3
left = sum(row[3 * x] for row in rows for x in range(third)) / (h * third)
right = sum(row[3 * x] for row in rows for x in range(w - third, w)) / (h * third)
check(left > 1.5 * right, "Cornell box: red wall on the left (mean red %.4g left, %.4g right)" % (left, right))
exr = os.path.join(TMP, "rt_cb.exr")
run(common + ["-o", exr, "--max-depth", "1"])
data = open(exr, "rb").read()
check(b"testbed" in data and b"raytrace" in data, "Cornell box EXR carries the provenance attributes")

# Ctrl-C: the partial image is written and the exit status is 130.
part = os.path.join(TMP, "rt_cb_sigint.pfm")
if os.path.exists(part):
    os.remove(part)
proc = subprocess.Popen([TESTBED, "render", cornell, "-o", part, "--spp", "4096", "--threads", "2"],
                        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                        env=dict(os.environ, TB_NO_PROGRESS="1"))
line = proc.stderr.readline()  # printed once the SIGINT handler is in place
proc.send_signal(signal.SIGINT)
out_s, err_s = proc.communicate(timeout=600)
check(proc.returncode == 130 and os.path.exists(part) and "INTERRUPTED" in out_s,
      "Ctrl-C writes the partial image and exits 130 (exit %d, %r)" % (proc.returncode, line.strip()))

# --time-budget: stops early, writes the image, exits 0 (a budget is not an interrupt).
tb = os.path.join(TMP, "rt_cb_budget.pfm")
p = run([cornell, "-o", tb, "--spp", "4096", "--time-budget", "0.2"])
check(os.path.exists(tb) and "INTERRUPTED" in p.stdout, "--time-budget stops early and writes the image")

# ------------------------------------------------ 8. MID 1.1 materials from the command line
# A GGX sphere (alpha 0.5, F0 = 1) filling the middle of the view inside the
# furnace box (radiance 1 everywhere, section 1): the pixel looking at the
# sphere's centre shows its albedo at normal incidence, 0.68785
# (docs/shading.md's table; the C test render_rt_materials checks all angles).
furnace_l = ""
for k, v in faces.items():
    furnace_l += quad(k, v[::-1], "diffuse = 0 emission = 3.14159265358979")
ggx = write("rt_ggx_furnace.mid", "mid 1.1\n"
            'camera { eye = [0 0 0.9] look_at = [0 0 0] up = [0 1 0] fov = 2 resolution = [5 5] }\n'
            "sphere { transform = [scale(0.2)] rendering = { diffuse = 0 specular = 1 model = ggx roughness = 0.5 } }\n"
            + furnace_l)
out = os.path.join(TMP, "rt_ggx_furnace.pfm")
run([ggx, "-o", out, "--spp", "16", "--glossy-samples", "64", "--threads", "2"])
w, h, rows = read_pfm(out)
centre = sum(rows[2][3 * 2:3 * 2 + 3]) / 3.0
check(abs(centre - 0.68785) < 0.01, "GGX furnace from the command line: %.5f, albedo 0.68785" % centre)

# Every 1.1 attribute in one scene: renders without NaN, the same image for
# 1 and 2 threads (glossy rays draw from each sample's own stream).
mats = os.path.join(SRC, "scenes", "materials.mid")
a = os.path.join(TMP, "rt_materials_1.pfm")
b = os.path.join(TMP, "rt_materials_2.pfm")
small = write("rt_materials_small.mid", open(mats).read().replace("resolution = [800 450]", "resolution = [64 36]"))
run([small, "-o", a, "--threads", "1"])
run([small, "-o", b, "--threads", "2"])
w, h, rows = read_pfm(a)
finite = all(math.isfinite(x) and x >= 0.0 for row in rows for x in row)
check(finite and open(a, "rb").read() == open(b, "rb").read(),
      "scenes/materials.mid (64 x 36): finite, byte-identical for 1 and 2 threads")

# Bad command lines fail with the usage status and write nothing.
bad = os.path.join(TMP, "rt_bad.png")
run([cornell, "-o", bad, "--method", "pathtrace"], expect=2)
check(not os.path.exists(bad), "unknown --method is refused and writes nothing")

sys.exit(1 if failures else 0)
