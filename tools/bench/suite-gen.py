#!/usr/bin/env python3
"""Writes one generated scene of the benchmark suite (docs/performance.md,
"Benchmark suite") as MID text on standard output: meshes as polygons
objects, a camera framing them and a quad area light. Deterministic: a
scene depends only on its kind, its size and --seed (Python's Mersenne
Twister, whose random() sequence for an integer seed is fixed).

    tools/bench/suite-gen.py KIND [--tris N] [--seed S] > scene.mid
    tools/bench/suite-gen.py --rest [--no-camera] XLO YLO ZLO XHI YHI ZHI   # camera + lamp framing a box

Kinds (N is the approximate triangle count; the ground quad adds 2):
  bumpy    a displaced sphere (lat/long grid, 12 random plane waves, the first 5 %)
  terrain  a fractal height field (random sines, 8 octaves) over [-2, 2]^2
  boxes    N / 12 boxes of log-uniform sizes, random positions and turns
  slivers  N long thin triangles (length 0.3-1.5, width 0.001-0.01)
  objects  N / 80 small separate objects (subdivided icosahedra, 80 triangles each)
  mixed    a bumpy sphere among boxes on a ground plane (N / 3 in boxes)

--rest prints what follows the meshes of an imported model: the camera,
materials and lamp for a model whose world box is the one given
(--no-camera: no camera, for a model that brings its own).
"""
import math
import random
import sys

DEFAULT_TRIS = {"bumpy": 1000000, "terrain": 3000000, "boxes": 360000, "slivers": 500000,
                "objects": 320000, "mixed": 360000}


def usage(msg):
    sys.stderr.write(f"suite-gen.py: error: {msg}\n{__doc__}")
    sys.exit(2)


class Mesh:
    """One polygons object under construction."""

    def __init__(self):
        self.v = []
        self.f = []

    def vert(self, x, y, z):
        self.v.append((x, y, z))
        return len(self.v) - 1

    def tri(self, a, b, c):
        self.f.append((a, b, c))


def write_mesh(out, name, material, m):
    w = out.write
    w(f'polygons "{name}" {{\n    geometry = {{\n        vertices = [\n')
    w("".join(f"            [{x:.6f} {y:.6f} {z:.6f}]\n" for x, y, z in m.v))
    w("        ]\n        faces = [\n")
    w("".join(f"            [{a} {b} {c}]\n" for a, b, c in m.f))
    w(f'        ]\n    }}\n    rendering = {{ material = "{material}" }}\n}}\n')


def write_frame(out, lo, hi, camera=True):
    """Camera looking at box lo..hi from the -y side and above (unless camera is
    False: the model has its own), lamp above it, materials."""
    c = [(lo[k] + hi[k]) / 2 for k in range(3)]
    r = max(1e-6, math.sqrt(sum((hi[k] - lo[k]) ** 2 for k in range(3))) / 2)
    d = 0.7 * r / math.sin(math.radians(22.5))  # the bounding sphere a little wider than the 45 degree view
    eye = (c[0], c[1] - 0.8 * d, c[2] + 0.6 * d)
    if camera:
        out.write(f'camera "bench" {{\n    eye = [{eye[0]:.6g} {eye[1]:.6g} {eye[2]:.6g}]\n'
                  f"    look_at = [{c[0]:.6g} {c[1]:.6g} {c[2]:.6g}]\n    up = [0 0 1]\n"
                  "    fov = 45\n    resolution = [512 512]\n}\n")
    out.write('material "ground" {\n    diffuse = 0.7\n}\n')
    out.write('material "stuff" {\n    diffuse = [0.8 0.5 0.3]\n}\n')
    out.write('material "lamp" {\n    diffuse = 0.8\n    emission = [20 20 20]\n}\n')
    s, z = 0.25 * r, hi[2] + 0.5 * r
    # The lamp faces down: counter-clockwise seen from below.
    out.write('polygons "lamp" {\n    geometry = {\n'
              f"        vertices = [[{c[0] - s:.6g} {c[1] - s:.6g} {z:.6g}] [{c[0] - s:.6g} {c[1] + s:.6g} {z:.6g}] "
              f"[{c[0] + s:.6g} {c[1] + s:.6g} {z:.6g}] [{c[0] + s:.6g} {c[1] - s:.6g} {z:.6g}]]\n"
              "        faces = [[0 1 2 3]]\n    }\n"
              '    rendering = { material = "lamp" }\n}\n')


def ground(m, half=2.5, z=0.0):
    a, b = m.vert(-half, -half, z), m.vert(half, -half, z)
    c, d = m.vert(half, half, z), m.vert(-half, half, z)
    m.tri(a, b, c)
    m.tri(a, c, d)


def sines(rng, count, fmin, fmax, amp):
    """Random plane waves (direction, frequency, phase, amplitude) for a displacement."""
    waves = []
    for k in range(count):
        th, ph = rng.uniform(0, math.pi), rng.uniform(0, 2 * math.pi)
        f = fmin * (fmax / fmin) ** (k / max(1, count - 1))
        d = (math.sin(th) * math.cos(ph) * f, math.sin(th) * math.sin(ph) * f, math.cos(th) * f)
        waves.append((d, rng.uniform(0, 2 * math.pi), amp * (fmin / f) ** 0.7))
    return waves


def wave_sum(waves, x, y, z):
    return sum(a * math.sin(d[0] * x + d[1] * y + d[2] * z + p) for d, p, a in waves)


def bumpy_sphere(m, rng, n, centre, radius):
    rings = max(3, int(math.sqrt(n / 4)))
    segs = 2 * rings
    waves = sines(rng, 12, 2.0, 40.0, 0.05)
    idx = {}
    cx, cy, cz = centre
    top = m.vert(cx, cy, cz + radius * (1 + wave_sum(waves, 0, 0, 1)))
    bot = m.vert(cx, cy, cz - radius * (1 + wave_sum(waves, 0, 0, -1)))
    for i in range(1, rings):
        t = math.pi * i / rings
        for j in range(segs):
            p = 2 * math.pi * j / segs
            ux, uy, uz = math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)
            r = radius * (1 + wave_sum(waves, ux, uy, uz))
            idx[i, j] = m.vert(cx + r * ux, cy + r * uy, cz + r * uz)
    for j in range(segs):
        j1 = (j + 1) % segs
        m.tri(top, idx[1, j], idx[1, j1])
        m.tri(bot, idx[rings - 1, j1], idx[rings - 1, j])
        for i in range(1, rings - 1):
            a, b, c, d = idx[i, j], idx[i + 1, j], idx[i + 1, j1], idx[i, j1]
            m.tri(a, b, c)
            m.tri(a, c, d)


def box(m, rng, cx, cy, size):
    sx, sy, sz = (size * rng.uniform(0.5, 1.5) for _ in range(3))
    a = rng.uniform(0, 2 * math.pi)
    ca, sa = math.cos(a), math.sin(a)
    v = []
    for k in range(8):
        x, y, z = (sx if k & 1 else -sx) / 2, (sy if k & 2 else -sy) / 2, (sz if k & 4 else 0.0) + 1e-3
        v.append(m.vert(cx + ca * x - sa * y, cy + sa * x + ca * y, z))
    for q in ((0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)):
        m.tri(v[q[0]], v[q[1]], v[q[2]])
        m.tri(v[q[0]], v[q[2]], v[q[3]])


def boxes(m, rng, count, half):
    for _ in range(count):
        box(m, rng, rng.uniform(-half, half), rng.uniform(-half, half), 0.02 * 15 ** rng.random())


def icosphere(centre, radius):
    """A once-subdivided icosahedron (80 triangles): vertices and faces."""
    g = (1 + math.sqrt(5)) / 2
    v = [(-1, g, 0), (1, g, 0), (-1, -g, 0), (1, -g, 0), (0, -1, g), (0, 1, g), (0, -1, -g), (0, 1, -g),
         (g, 0, -1), (g, 0, 1), (-g, 0, -1), (-g, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]
    mids = {}

    def mid(a, b):
        key = (min(a, b), max(a, b))
        if key not in mids:
            mids[key] = len(v)
            v.append(tuple((v[a][k] + v[b][k]) / 2 for k in range(3)))
        return mids[key]

    f2 = []
    for a, b, c in f:
        ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
        f2 += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
    out = []
    for p in v:
        n = math.sqrt(sum(x * x for x in p))
        out.append(tuple(centre[k] + radius * p[k] / n for k in range(3)))
    return out, f2


def main():
    args = sys.argv[1:]
    if "--help" in args or "-h" in args:
        sys.stdout.write(__doc__)
        return
    out = sys.stdout
    if args and args[0] == "--rest":
        camera = "--no-camera" not in args
        nums = [a for a in args[1:] if a != "--no-camera"]
        if len(nums) != 6:
            usage("--rest needs six numbers: XLO YLO ZLO XHI YHI ZHI")
        try:
            b = [float(x) for x in nums]
        except ValueError:
            usage("--rest needs six numbers: XLO YLO ZLO XHI YHI ZHI")
        write_frame(out, b[:3], b[3:], camera)
        return
    kind, n, seed = None, None, 1
    i = 0
    while i < len(args):
        a = args[i]
        if a in ("--tris", "--seed") and i + 1 < len(args):
            try:
                val = int(args[i + 1])
            except ValueError:
                usage(f"{a} wants a whole number, got '{args[i + 1]}'")
            if val < 1:
                usage(f"{a} must be at least 1")
            if a == "--tris":
                n = val
            else:
                seed = val
            i += 2
        elif a.startswith("-"):
            usage(f"unknown option '{a}'")
        elif kind is None:
            kind = a
            i += 1
        else:
            usage(f"unexpected argument '{a}'")
    if kind not in DEFAULT_TRIS:
        usage(f"unknown kind '{kind}' (one of {', '.join(DEFAULT_TRIS)})" if kind else "no KIND given")
    n = n or DEFAULT_TRIS[kind]
    rng = random.Random(seed * 1000003 + sorted(DEFAULT_TRIS).index(kind))
    meshes = []  # (name, material, Mesh)
    lo, hi = [-2.5, -2.5, 0.0], [2.5, 2.5, 1.5]
    g = Mesh()
    if kind != "terrain":
        ground(g)
        meshes.append(("ground", "ground", g))
    if kind == "bumpy":
        m = Mesh()
        bumpy_sphere(m, rng, n, (0, 0, 1.0), 0.9)
        meshes.append(("bumpy", "stuff", m))
        lo, hi = [-2.5, -2.5, 0.0], [2.5, 2.5, 2.0]
    elif kind == "terrain":
        k = max(2, int(math.sqrt(n / 2)))
        waves = sines(rng, 8, 1.0, 60.0, 0.25)
        for j in range(k + 1):
            y = -2.0 + 4.0 * j / k
            for i2 in range(k + 1):
                x = -2.0 + 4.0 * i2 / k
                g.vert(x, y, wave_sum(waves, x, y, 0.0))
        for j in range(k):
            for i2 in range(k):
                a = j * (k + 1) + i2
                b, c, d = a + 1, a + k + 2, a + k + 1
                g.tri(a, b, c)
                g.tri(a, c, d)
        meshes.append(("terrain", "ground", g))
        lo, hi = [-2.0, -2.0, -0.6], [2.0, 2.0, 0.6]
    elif kind == "boxes":
        m = Mesh()
        boxes(m, rng, max(1, n // 12), 2.3)
        meshes.append(("boxes", "stuff", m))
    elif kind == "slivers":
        m = Mesh()
        for _ in range(n):
            c = (rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(0, 1.5))
            th, ph = math.acos(rng.uniform(-1, 1)), rng.uniform(0, 2 * math.pi)
            d = (math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th))
            ln, wd = rng.uniform(0.3, 1.5), rng.uniform(0.001, 0.01)
            # a width direction perpendicular to d
            e = (d[1], -d[0], 0.0) if abs(d[2]) < 0.9 else (0.0, d[2], -d[1])
            en = math.sqrt(sum(x * x for x in e))
            e = tuple(x / en * wd for x in e)
            a = m.vert(*(c[k] - d[k] * ln / 2 for k in range(3)))
            b = m.vert(*(c[k] + d[k] * ln / 2 + e[k] for k in range(3)))
            cc = m.vert(*(c[k] + d[k] * ln / 2 - e[k] for k in range(3)))
            m.tri(a, b, cc)
        meshes.append(("slivers", "stuff", m))
    elif kind == "objects":
        for o in range(max(1, n // 80)):
            c = (rng.uniform(-2.3, 2.3), rng.uniform(-2.3, 2.3), rng.uniform(0.05, 1.5))
            v, f = icosphere(c, 0.01 + 0.06 * rng.random())
            m = Mesh()
            m.v, m.f = v, f
            meshes.append((f"o{o}", "stuff", m))
    elif kind == "mixed":
        m = Mesh()
        bumpy_sphere(m, rng, n * 2 // 3, (0, 0, 1.0), 0.9)
        meshes.append(("bumpy", "stuff", m))
        b = Mesh()
        boxes(b, rng, max(1, n // 3 // 12), 2.3)
        meshes.append(("boxes", "stuff", b))
        lo, hi = [-2.5, -2.5, 0.0], [2.5, 2.5, 2.0]
    out.write("mid 1\n")
    write_frame(out, lo, hi)
    for name, mat, m in meshes:
        write_mesh(out, name, mat, m)


if __name__ == "__main__":
    main()
