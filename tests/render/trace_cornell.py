#!/usr/bin/env python3
"""End-to-end test of `testbed trace` on the Cornell box (docs/trace.md).

Rays are written here, in Python: the camera's primary rays for a 32 x 32
image (from the published camera: eye, view along +z, 35 mm lens on a 25 mm
film), rays straight down onto the floor and straight up at the ceiling and
the light, random rays from inside the box, rays out of the open front, and
invalid rays. The hits are checked against an independent computation:
the box's quads are read from the MID text and intersected here in double
(Moller-Trumbore); rays down onto the floor must hit object 0 at exactly the
height of their origin with normal (0, 1, 0). Then: BVH, grid and list, 1 and
2 threads give byte-identical HITS files; the stats JSON has "rays",
"seconds" and "rays_per_second" = rays / seconds; malformed RAYS files, bad
scenes fail with exit status 1 and leave no HITS file; --backend vulkan gives
the CPU's objects and faces with t within float tolerance.
"""
import json
import math
import os
import random
import re
import struct
import subprocess
import sys

TESTBED = os.environ["TESTBED"]
SRC = os.environ["TB_SOURCE_DIR"]
WORK = os.path.join(os.environ.get("TB_TEST_TMPDIR", "."), "trace_cornell")
SCENE = os.path.join(SRC, "scenes", "cornell-box.mid")
MISS = 0xFFFFFFFF
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print("FAIL:", what)


def f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


# ---------------------------------------------------------------- the scene, read independently

def bracketed(text, start):
    """The text of the [...] list that opens at text[start]."""
    depth = 0
    for i in range(start, len(text)):
        if text[i] == "[":
            depth += 1
        elif text[i] == "]":
            depth -= 1
            if depth == 0:
                return text[start:i + 1]
    raise ValueError("unbalanced list")


def numbers_lists(s):
    return [[float(v) for v in inner.split()] for inner in re.findall(r"\[([^\[\]]*)\]", s)]


def read_polygons(path):
    text = re.sub(r"#[^\n]*", "", open(path).read())
    kinds = re.findall(r"^(\w+)\s+(?:\"[^\"]*\"\s*)?\{", text, re.M)
    objects = [k for k in kinds if k not in ("camera", "material")]
    assert all(k == "polygons" for k in objects), objects
    polys = []
    for m in re.finditer(r"polygons\s+\"([^\"]*)\"\s*\{", text):
        body = text[m.end():]
        v = bracketed(body, body.index("vertices") + body[body.index("vertices"):].index("["))
        f = bracketed(body, body.index("faces") + body[body.index("faces"):].index("["))
        verts = numbers_lists(v)
        faces = [[int(i) for i in face] for face in numbers_lists(f)]
        polys.append((m.group(1), verts, faces))
    return polys


POLYS = read_polygons(SCENE)
assert [p[0] for p in POLYS][:6] == ["floor", "ceiling", "back wall", "right wall", "left wall", "light"]
# Every face as a fan of triangles, in float32 as the scene stores vertices.
TRIS = []  # (object, face, a, b, c)
for obj, (_, verts, faces) in enumerate(POLYS):
    for fi, face in enumerate(faces):
        p = [tuple(f32(c) for c in verts[i]) for i in face]
        for k in range(1, len(p) - 1):
            TRIS.append((obj, fi, p[0], p[k], p[k + 1]))


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def unit(a):
    n = math.sqrt(dot(a, a))
    return (a[0] / n, a[1] / n, a[2] / n)


def reference(o, d, tmin, tmax):
    """Closest hit in double: (t, object, unit normal, margin), where margin is
    how far inside its triangle the point is (barycentric) and how far the
    next object's hit is behind it (relative), so ambiguous rays can be left out."""
    hits = []
    for obj, fi, a, b, c in TRIS:
        e1, e2 = sub(b, a), sub(c, a)
        p = cross(d, e2)
        det = dot(e1, p)
        if det == 0.0:
            continue
        s = sub(o, a)
        u = dot(s, p) / det
        q = cross(s, e1)
        v = dot(d, q) / det
        t = dot(e2, q) / det
        if u < -1e-9 or v < -1e-9 or u + v > 1 + 1e-9 or not (tmin <= t <= tmax):
            continue
        hits.append((t, obj, unit(cross(e1, e2)), min(u, v, 1 - u - v)))
    if not hits:
        return None
    hits.sort(key=lambda h: h[0])
    t, obj, n, margin = hits[0]
    gap = min([(h[0] - t) / max(t, 1e-9) for h in hits[1:] if h[1] != obj] + [1.0])
    return t, obj, n, min(margin, gap)


# ---------------------------------------------------------------- rays

def camera_rays(n):
    """Primary rays through the pixel centres of an n x n image: eye
    (278, 273, -800) looking along +z, image up +y, image right -x (the view
    direction crossed with up), half-field tangent 12.5 / 35 on both axes."""
    tan = 12.5 / 35.0
    rays = []
    for j in range(n):
        for i in range(n):
            sx = (2 * (i + 0.5) / n - 1) * tan
            sy = (1 - 2 * (j + 0.5) / n) * tan
            d = unit((-sx, sy, 1.0))
            rays.append(((278.0, 273.0, -800.0), d, 0.0, math.inf))
    return rays


def inside_block(x, z, margin=5.0):
    """True if (x, z) is under one of the blocks (their top faces projected
    onto the floor) or within `margin` mm of one."""
    for name, verts, faces in POLYS[6:8]:
        top = [(verts[i][0], verts[i][2]) for i in faces[0]]
        area = sum(top[k][0] * top[(k + 1) % 4][1] - top[(k + 1) % 4][0] * top[k][1] for k in range(4))
        sign = 1.0 if area > 0 else -1.0
        if all(sign * ((b[0] - a[0]) * (z - a[1]) - (b[1] - a[1]) * (x - a[0])) >
               -margin * math.hypot(b[0] - a[0], b[1] - a[1])
               for a, b in ((top[k], top[(k + 1) % 4]) for k in range(4))):
            return True
    return False


rng = random.Random(12345)
rays = camera_rays(32)
ncam = len(rays)
floor_rays = []
while len(floor_rays) < 200:
    x, z = rng.uniform(5, 545), rng.uniform(5, 554)
    if not inside_block(x, z):
        y = float(rng.randint(340, 540))  # above both blocks, below the light
        floor_rays.append(((x, y, z), (0.0, -1.0, 0.0), 0.0, math.inf))
up_rays = []
while len(up_rays) < 200:
    x, z = rng.uniform(5, 550), rng.uniform(5, 554)
    if not inside_block(x, z):
        up_rays.append(((x, 1.0, z), (0.0, 1.0, 0.0), 0.0, math.inf))
random_rays = []
for k in range(2000):
    o = (rng.uniform(1, 555), rng.uniform(1, 548), rng.uniform(1, 558))
    d = (rng.gauss(0, 1), rng.gauss(0, 1), rng.gauss(0, 1))
    random_rays.append((o, d, 0.0, math.inf))
front_rays = [((278.0, 273.0, 100.0), (0.01 * k, 0.02, -1.0), 0.0, math.inf) for k in range(-5, 5)]
short_rays = [((150.0, 400.0, 400.0), (0.0, 0.0, 1.0), 0.0, 5.0)]  # ends in mid-air
invalid_rays = [
    ((math.nan, 0.0, 0.0), (0.0, 0.0, 1.0), 0.0, math.inf),
    ((278.0, 273.0, 280.0), (0.0, 0.0, 0.0), 0.0, math.inf),
    ((math.inf, 273.0, 280.0), (0.0, 0.0, 1.0), 0.0, math.inf),
    ((278.0, 273.0, 280.0), (0.0, 0.0, 1.0), 10.0, 5.0),
    ((278.0, 273.0, 280.0), (0.0, 0.0, 1.0), 0.0, math.nan),
]
all_rays = rays + floor_rays + up_rays + random_rays + front_rays + short_rays + invalid_rays
N = len(all_rays)

os.makedirs(WORK, exist_ok=True)
RAYS = os.path.join(WORK, "rays.bin")


def write_rays(path, rs):
    with open(path, "wb") as f:
        for (o, d, tmin, tmax) in rs:
            f.write(struct.pack("<8f", o[0], o[1], o[2], tmin, d[0], d[1], d[2], tmax))


write_rays(RAYS, all_rays)
# The rays as the file holds them (float32), for the reference.
file_rays = []
with open(RAYS, "rb") as f:
    data = f.read()
for k in range(N):
    v = struct.unpack_from("<8f", data, 32 * k)
    file_rays.append(((v[0], v[1], v[2]), (v[4], v[5], v[6]), v[3], v[7]))


def run(*args, expect=0):
    p = subprocess.run([TESTBED, "trace"] + list(args), capture_output=True, text=True)
    if p.returncode != expect:
        print(p.stdout, p.stderr)
    check(p.returncode == expect, "exit status %d (want %d) for %s" % (p.returncode, expect, " ".join(args)))
    return p


def read_hits(path):
    with open(path, "rb") as f:
        b = f.read()
    return b, [struct.unpack_from("<fIIfffff", b, 32 * k) for k in range(len(b) // 32)]


# ---------------------------------------------------------------- correctness (BVH, 1 thread)

HITS = os.path.join(WORK, "hits-bvh-1.bin")
STATS = os.path.join(WORK, "stats.json")
run(SCENE, "--rays", RAYS, "--hits", HITS, "--accel", "bvh", "--threads", "1", "--stats", STATS)
ref_bytes, hits = read_hits(HITS)
check(len(ref_bytes) == 32 * N, "HITS has %d bytes, want %d" % (len(ref_bytes), 32 * N))

compared = 0
for k, ((o, d, tmin, tmax), h) in enumerate(zip(file_rays, hits)):
    t, obj, face, u, v, nx, ny, nz = h
    label = "ray %d" % k
    if k >= N - len(invalid_rays) or k in range(N - len(invalid_rays) - len(short_rays) - len(front_rays),
                                                  N - len(invalid_rays)):
        # front, short and invalid rays miss: the miss record
        check(math.isinf(t) and t > 0 and obj == MISS and face == MISS and u == 0 and v == 0 and
              (nx, ny, nz) == (0, 0, 0), "%s: want the miss record, got %s" % (label, h))
        continue
    if ncam <= k < ncam + len(floor_rays):
        # straight down onto the floor: object 0, exact distance, normal +y
        check(obj == 0 and face == 0 and t == o[1] and (nx, ny, nz) == (0.0, 1.0, 0.0),
              "%s (floor from y = %g): got %s" % (label, o[1], h))
        continue
    if ncam + len(floor_rays) <= k < ncam + len(floor_rays) + len(up_rays):
        # straight up: the light (y = 548.7) inside its rectangle, else the ceiling (548.8)
        under_light = 213 < o[0] < 343 and 227 < o[2] < 332
        want_obj, y = (5, f32(548.7)) if under_light else (1, f32(548.8))
        check(obj == want_obj and t == f32(y - o[1]) and (nx, ny, nz) == (0.0, -1.0, 0.0),
              "%s (up at x %g z %g): got %s, want object %d t %r" % (label, o[0], o[2], h, want_obj, f32(y - o[1])))
        continue
    ref = reference(o, d, tmin, tmax)
    check(0.0 <= u <= 1.0 and 0.0 <= v <= 1.0 or obj == MISS, "%s: u, v out of range: %s" % (label, h))
    if ref is None:
        check(obj == MISS, "%s: the reference misses, testbed hit %s" % (label, h))
        continue
    rt, robj, rn, margin = ref
    if margin < 1e-6:
        continue  # through an edge or nearly two surfaces at once: either answer is right
    compared += 1
    # The left wall (object 4) is not planar (its fourth vertex is 3.2 mm off
    # the plane of the others): its triangles depend on the diagonal chosen,
    # which moves a hit by up to 3.2 mm across the wall, more along the ray.
    dn = abs(dot(unit(d), rn))
    ttol = 3.3 / max(dn, 1e-3) / math.sqrt(dot(d, d)) if robj == 4 else 2e-6 * rt
    ntol = 1e-2 if robj == 4 else 1e-5
    check(obj == robj, "%s: object %d, reference %d" % (label, obj, robj))
    check(abs(t - rt) <= ttol, "%s: t %r, reference %r (object %d)" % (label, t, rt, robj))
    check(abs(nx - rn[0]) <= ntol and abs(ny - rn[1]) <= ntol and abs(nz - rn[2]) <= ntol,
          "%s: normal %r, reference %r" % (label, (nx, ny, nz), rn))
    check(abs(nx * nx + ny * ny + nz * nz - 1.0) < 1e-6, "%s: normal not unit" % label)
check(compared > 2500, "only %d rays compared with the reference" % compared)
# The camera sees the back wall in the centre of the image.
centre = hits[16 * 32 + 16]
check(centre[1] in (2, 7), "the centre pixel sees object %d" % centre[1])

# ---------------------------------------------------------------- the stats JSON

with open(STATS) as f:
    st = json.load(f)
for key in ("rays", "seconds", "rays_per_second"):
    check(key in st, "stats JSON lacks %s" % key)
check(st.get("rays") == N, "stats rays %r, want %d" % (st.get("rays"), N))
check(st.get("seconds", 0) > 0, "stats seconds %r" % st.get("seconds"))
if st.get("seconds"):
    check(abs(st["rays_per_second"] - st["rays"] / st["seconds"]) <= 1e-9 * st["rays_per_second"],
          "rays_per_second %r != rays / seconds %r" % (st["rays_per_second"], st["rays"] / st["seconds"]))
check(st.get("invalid_rays") == len(invalid_rays), "invalid_rays %r" % st.get("invalid_rays"))
check(st.get("hits") == sum(1 for h in hits if h[1] != MISS), "hits %r" % st.get("hits"))
check(st.get("provenance", {}).get("command_line", "").startswith("testbed trace "), "provenance command line")
check(st.get("counters", {}).get("Trace/invalid rays") == len(invalid_rays), "Trace/invalid rays counter")
check(st.get("counters", {}).get("Scene/polygons objects") == 8, "Scene/polygons objects counter")

# ---------------------------------------------------------------- determinism

for accel in ("bvh", "grid", "list"):
    for threads in ("1", "2"):
        out = os.path.join(WORK, "hits-%s-%s.bin" % (accel, threads))
        run(SCENE, "--rays", RAYS, "--hits", out, "--accel", accel, "--threads", threads)
        check(open(out, "rb").read() == ref_bytes, "%s with %s threads differs from bvh with 1" % (accel, threads))
out = os.path.join(WORK, "hits-auto.bin")
run(SCENE, "--rays", RAYS, "--hits", out, "--backend", "cpu")
check(open(out, "rb").read() == ref_bytes, "--backend cpu differs")

# ---------------------------------------------------------------- failures leave no HITS file

def no_new_files(before, what):
    after = set(os.listdir(WORK))
    check(after == before, "%s left files: %s" % (what, sorted(after - before)))


BAD = os.path.join(WORK, "bad.bin")
with open(BAD, "wb") as f:
    f.write(ref_bytes[:33])  # not a multiple of 32
before = set(os.listdir(WORK))
p = run(SCENE, "--rays", BAD, "--hits", os.path.join(WORK, "bad-hits.bin"), expect=1)
check("multiple of" in p.stderr, "malformed RAYS message: %r" % p.stderr)
no_new_files(before, "a malformed RAYS file")
# An existing HITS file is left as it was.
OLD = os.path.join(WORK, "old-hits.bin")
with open(OLD, "wb") as f:
    f.write(b"old")
before = set(os.listdir(WORK))
run(SCENE, "--rays", BAD, "--hits", OLD, expect=1)
check(open(OLD, "rb").read() == b"old", "a failed run changed an existing HITS file")
# --backend vulkan (host/gpu/intersect.h, lavapipe): a bad RAYS file still fails
# whole; good rays give the CPU's object and face on every ray and t within the
# float tolerance of docs/accuracy.md (the Cornell box is triangles only).
run(SCENE, "--rays", BAD, "--hits", os.path.join(WORK, "vk.bin"), "--backend", "vulkan", expect=1)
no_new_files(before, "--backend vulkan with a malformed RAYS file")
VK = os.path.join(WORK, "vk.bin")
run(SCENE, "--rays", RAYS, "--hits", VK, "--backend", "vulkan")
vk_bytes, vk_hits = read_hits(VK)
check(len(vk_bytes) == len(ref_bytes), "--backend vulkan HITS size")
for k, (a, b) in enumerate(zip(hits, vk_hits)):
    same = a[1:3] == b[1:3] and (a[0] == b[0] or abs(a[0] - b[0]) <= 1e-4 * abs(a[0]))
    check(same, "ray %d: cpu %r, vulkan %r" % (k, a[:3], b[:3]))
before = set(os.listdir(WORK))
BROKEN = os.path.join(WORK, "broken.mid")
with open(BROKEN, "w") as f:
    f.write("mid 1\nsphere {\n  transform = [scale(0)]\n}\n")
p = run(BROKEN, "--rays", RAYS, "--hits", os.path.join(WORK, "b.bin"), expect=1)
check(p.stderr.startswith(BROKEN + ":3:"), "scene error not located: %r" % p.stderr)
no_new_files(before | {"broken.mid"}, "a broken scene")
run(SCENE, "--rays", os.path.join(WORK, "missing.bin"), "--hits", os.path.join(WORK, "m.bin"), expect=1)
run(SCENE, "--rays", RAYS, expect=2)
run(SCENE, "--rays", RAYS, "--hits", os.path.join(WORK, "x.bin"), "--accel", "octree", expect=2)
run(SCENE, "--rays", RAYS, "--hits", os.path.join(WORK, "x.bin"), "--threads", "0", expect=2)
no_new_files(before | {"broken.mid"}, "usage errors")
# An empty RAYS file gives an empty HITS file.
EMPTY = os.path.join(WORK, "empty.bin")
open(EMPTY, "wb").close()
run(SCENE, "--rays", EMPTY, "--hits", os.path.join(WORK, "empty-hits.bin"))
check(os.path.getsize(os.path.join(WORK, "empty-hits.bin")) == 0, "empty RAYS, non-empty HITS")
p = run("--help")
check("--rays" in p.stdout and "0xFFFFFFFF" in p.stdout, "--help text")

if failures:
    print("%d failures" % len(failures))
    sys.exit(1)
print("ok: %d rays, %d compared with the reference" % (N, compared))
