#!/usr/bin/env python3
"""Converts a MID 1 scene (docs/mid.md) to a POV-Ray 3.7 scene with the same
geometry, materials, lights and camera, for the POV-Ray peer benchmark
(tools/bench/povray-showcase.sh, docs/performance.md "Ray tracer vs
POV-Ray"). Writing the POV file from the MID file, rather than by hand,
guarantees that both renderers see the same objects at the same places.

    tools/bench/mid2pov.py SCENE.mid [--light-samples N] [--max-depth D] \
        [--adc-bailout W] [--scale S] > SCENE.pov

Every MID primitive becomes the exact POV-Ray shape (no tessellation):
sphere, box, cylinder/cone (`open` without caps), conic as a `quadric`
intersected with (or, without caps, clipped by) the slab z0 <= z <= z1,
pyramid and regular prism as an intersection of planes (bounded by the
canonical box), a paraboloid as a `poly` (see shape()), profile prism as a
linear `prism`, torus, arches as a box minus the opening, polygons as a
`mesh` (faces fanned to triangles: exact for the convex faces of the
scenes converted so far), and CSG nodes as
`union` / `intersection` / `difference`. MID transforms are composed here
into one affine matrix per object (POV's `matrix` keyword).

Radiometry (so that the two images look alike; the benchmark times, not
the pixel values, are compared): our renderer's Lambert term is
rho/pi * E cos(theta), POV-Ray's is C * rho * cos(theta), so a light's
colour is S/pi times its irradiance at unit distance and every POV pixel
value is S times our radiance (default S = 1: equal to our render with
`--exposure 0`). Point, spot and area lights fall off as
1/d^2 in our renderer; POV-Ray's `fade_power 2` gives 2 / (1 + (d/f)^2),
so with f = 0.01 the colour is scaled by 1/(2 f^2) and the falloff is
1/d^2 to within 1e-4 at d >= 1. The normalised Phong lobe
k_s (n+2)/(2 pi) cos^n(alpha) becomes `phong k_s*(n+2)/2 phong_size n`
(with the light colour's 1/pi)
(POV-Ray's highlight lacks the cos(theta) factor). `specular` also gives a
mirror ray weighted by k_s (`reflection`), `transmission` a Fresnel
dielectric (`reflection { 0 1 fresnel }`, `interior { ior }`, transmit).
An emissive object becomes an `emission` finish (directly visible radiance)
plus, for a sphere, an `area_light` (with the sphere as its `looks_like`) of N = --light-samples jittered samples
(a square grid: N must be a square) in a `circular orient` disc of the
sphere's radius at its centre, which our renderer samples as the sphere
itself; other emitter shapes are refused. `--max-depth D` (our camera ray is
depth 0) is POV-Ray's `max_trace_level D+1` (its camera ray is level 1).
`--adc-bailout W` (default 1/255, POV-Ray's own default, written out so the
setting is visible) is POV-Ray's adaptive depth control; ours is
`testbed render --adc-bailout W`.
"""
import argparse
import math
import re
import sys

# ---------------------------------------------------------------- MID reader

_TOKEN = re.compile(r'\s+|#[^\n]*|(?P<num>[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)'
                    r'|(?P<str>"(?:[^"\\]|\\.)*")|(?P<id>[A-Za-z_][A-Za-z0-9_]*)|(?P<p>[\[\]{}()=])')


def tokens(text):
    pos = 0
    out = []
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if not m:
            raise SystemExit(f"mid2pov: cannot read MID at offset {pos}: {text[pos:pos + 20]!r}")
        pos = m.end()
        if m.group("num"):
            out.append(("num", float(m.group("num"))))
        elif m.group("str"):
            out.append(("str", m.group("str")[1:-1]))
        elif m.group("id"):
            out.append(("id", m.group("id")))
        elif m.group("p"):
            out.append(("p", m.group("p")))
    return out


class Parser:
    def __init__(self, toks):
        self.t = toks
        self.i = 0

    def peek(self, k=0):
        return self.t[self.i + k] if self.i + k < len(self.t) else ("eof", None)

    def take(self, kind=None, value=None):
        tok = self.peek()
        if (kind and tok[0] != kind) or (value is not None and tok[1] != value):
            raise SystemExit(f"mid2pov: expected {kind} {value}, got {tok}")
        self.i += 1
        return tok[1]

    def value(self):
        kind, v = self.peek()
        if kind == "num" or kind == "str":
            self.i += 1
            return v
        if kind == "p" and v == "[":
            self.i += 1
            items = []
            while self.peek() != ("p", "]"):
                items.append(self.value())
            self.i += 1
            return items
        if kind == "p" and v == "{":
            return self.body()
        if kind == "id":
            self.i += 1
            if v in ("true", "false"):
                return v == "true"
            if self.peek() == ("p", "("):
                self.i += 1
                args = []
                while self.peek() != ("p", ")"):
                    args.append(self.value())
                self.i += 1
                return ("call", v, args)
            return ("id", v)
        raise SystemExit(f"mid2pov: unexpected {kind} {v}")

    def body(self):
        """{ attr = value ... child objects ... } -> dict with '_children'."""
        self.take("p", "{")
        attrs = {"_children": []}
        while self.peek() != ("p", "}"):
            name = self.take("id")
            if self.peek() == ("p", "="):
                self.i += 1
                attrs[name] = self.value()
            else:
                label = self.take("str") if self.peek()[0] == "str" else None
                child = self.body()
                child["_kind"], child["_name"] = name, label
                attrs["_children"].append(child)
        self.i += 1
        return attrs

    def file(self):
        self.take("id", "mid")
        self.take("num")
        items = []
        while self.peek()[0] != "eof":
            kind = self.take("id")
            label = self.take("str") if self.peek()[0] == "str" else None
            block = self.body()
            block["_kind"], block["_name"] = kind, label
            items.append(block)
        return items

# ------------------------------------------------------------ affine algebra


def mat_mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def identity():
    return [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]


def op_matrix(op):
    _, name, args = op
    m = identity()
    if name == "translate":
        for i in range(3):
            m[i][3] = args[0][i]
    elif name == "scale":
        s = args[0] if isinstance(args[0], list) else [args[0]] * 3
        for i in range(3):
            m[i][i] = s[i]
    elif name == "rotate":
        ax, deg = args[0], args[1]
        n = math.sqrt(sum(c * c for c in ax))
        x, y, z = (c / n for c in ax)
        c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
        # Exact for multiples of 90 degrees, as the MID reader.
        if deg % 90 == 0:
            q = int(deg // 90) % 4
            c, s = [1, 0, -1, 0][q], [0, 1, 0, -1][q]
        t = 1 - c
        m[0][:3] = [t * x * x + c, t * x * y - s * z, t * x * z + s * y]
        m[1][:3] = [t * x * y + s * z, t * y * y + c, t * y * z - s * x]
        m[2][:3] = [t * x * z - s * y, t * y * z + s * x, t * z * z + c]
    elif name == "matrix":
        v = args[0]
        m = [v[4 * i:4 * i + 4] for i in range(4)]
    else:
        raise SystemExit(f"mid2pov: unknown transform {name}")
    return m


def transform_of(block):
    m = identity()
    for op in block.get("transform", []):
        m = mat_mul(op_matrix(op), m)
    return m


def apply(m, p, w=1.0):
    return [sum(m[i][j] * p[j] for j in range(3)) + m[i][3] * w for i in range(3)]


def fmt(x):
    return f"{x:.9g}"


def vec(v):
    return "<" + ", ".join(fmt(c) for c in v) + ">"


def pov_matrix(m):
    # POV-Ray multiplies row vectors: x' = v00 x + v10 y + v20 z + v30.
    vals = [m[r][c] for c in range(4) for r in range(3)]
    return "matrix <" + ", ".join(fmt(v) for v in vals) + ">"

# ---------------------------------------------------------------- materials


def colour(v):
    if isinstance(v, list):
        return [float(c) for c in v]
    if isinstance(v, tuple):
        raise SystemExit("mid2pov: spectral colours are not converted")
    return [float(v)] * 3


DEFAULT_MAT = {"diffuse": [0.5] * 3, "specular": [0.0] * 3, "exponent": 20.0,
               "transmission": [0.0] * 3, "ior": 1.0, "emission": [0.0] * 3}


class Materials:
    def __init__(self):
        self.named = {}

    def resolve(self, block, base):
        if block is None:
            return base
        mat = dict(self.named[block["material"]] if "material" in block else base)
        for key in ("diffuse", "specular", "transmission", "emission"):
            if key in block:
                mat[key] = colour(block[key])
        for key in ("exponent", "ior"):
            if key in block:
                mat[key] = float(block[key])
        for key in block:
            if key.endswith("_texture"):
                raise SystemExit("mid2pov: textures are not converted")
        return mat


def pov_texture(mat, scale):
    d, s, t, e = mat["diffuse"], mat["specular"], mat["transmission"], mat["emission"]
    n = mat["exponent"]
    glass = max(t) > 0
    if glass:
        pig = f"rgbt <1, 1, 1, {fmt(max(t))}>"
    else:
        pig = "rgb " + vec(d)
    fin = ["ambient 0", "diffuse " + ("0" if glass else "1")]
    if max(e) > 0:
        fin.append("emission " + vec([c / math.pi * scale for c in e]))
    ks = max(s)
    if ks > 0:
        fin.append(f"phong {fmt(ks * (n + 2) / 2)} phong_size {fmt(n)}")
    if glass:
        fin.append("reflection { 0, 1 fresnel on } conserve_energy")
    elif ks > 0:
        fin.append("reflection { rgb " + vec(s) + " }")
    out = "texture { pigment { " + pig + " } finish { " + " ".join(fin) + " } }"
    if glass:
        out += f" interior {{ ior {fmt(mat['ior'])} }}"
    return out

# ---------------------------------------------------------------- geometry

SWAP_YZ = "matrix <1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 0>"   # POV's y-axis shapes onto z


# Intersections of planes are unbounded to POV-Ray's automatic bounding, so
# every ray would test them: bound them by the canonical box as a POV-Ray
# user would.
UNIT_BOUND = "bounded_by { box { <-1, -1, -1>, <1, 1, 1> } }"


def plane(normal, offset):
    """Half-space normal . p <= offset, with the normal made unit length."""
    n = math.sqrt(sum(c * c for c in normal))
    return f"plane {{ {vec([c / n for c in normal])}, {fmt(offset / n)} }}"


def convex_prism(points):
    """Intersection of the slab |z| <= 1 and the edge half-spaces of a convex
    counter-clockwise polygon."""
    parts = [plane([0, 0, 1], 1), plane([0, 0, -1], 1)]
    for k in range(len(points)):
        (x0, y0), (x1, y1) = points[k], points[(k + 1) % len(points)]
        nx, ny = y1 - y0, -(x1 - x0)
        parts.append(plane([nx, ny, 0], nx * x0 + ny * y0))
    return "intersection { " + " ".join(parts) + " " + UNIT_BOUND + " }"


def shape(kind, geo):
    """The canonical MID shape (object space) as POV-Ray SDL."""
    caps = geo.get("caps", True)
    if kind == "sphere":
        return "sphere { <0, 0, 0>, 1 }"
    if kind == "cube":
        return "box { <-1, -1, -1>, <1, 1, 1> }"
    if kind == "cylinder":
        return "cylinder { <0, 0, -1>, <0, 0, 1>, 1" + ("" if caps else " open") + " }"
    if kind == "cone":
        r = float(geo.get("top_radius", 0))
        return f"cone {{ <0, 0, -1>, 1, <0, 0, 1>, {fmt(r)}" + ("" if caps else " open") + " }"
    if kind == "pyramid":
        t = float(geo.get("top", 0))
        if not caps:
            raise SystemExit("mid2pov: open pyramids are not converted")
        a = (1 - t) / 2
        parts = [plane([0, 0, -1], 1)]
        if t > 0:
            parts.append(plane([0, 0, 1], 1))
        for nx, ny in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            parts.append(plane([nx, ny, a], (1 + t) / 2))
        return "intersection { " + " ".join(parts) + " " + UNIT_BOUND + " }"
    if kind == "prism":
        if not caps:
            raise SystemExit("mid2pov: open prisms are not converted")
        if "profile" in geo:
            pts = [(float(p[0]), float(p[1])) for p in geo["profile"]]
            spline = ", ".join(f"<{fmt(x)}, {fmt(y)}>" for x, y in pts + pts[:1])
            return (f"prism {{ linear_sweep linear_spline -1, 1, {len(pts) + 1}, {spline} "
                    f"{SWAP_YZ} }}")
        n = int(geo.get("sides", 3))
        pts = [(math.cos(2 * math.pi * k / n), math.sin(2 * math.pi * k / n)) for k in range(n)]
        return convex_prism(pts)
    if kind == "torus":
        return (f"torus {{ {fmt(float(geo.get('major', 1)))}, {fmt(float(geo.get('minor', 0.25)))} "
                f"{SWAP_YZ} }}")
    if kind == "conic":
        c0, c1, c2 = (float(c) for c in geo.get("coefficients", [1, 0, -1]))
        z0, z1 = (float(z) for z in geo.get("z_range", [-1, 1]))
        # x^2 + y^2 - c2 z^2 - c1 z - c0 <= 0 inside.
        quad = f"quadric {{ <1, 1, {fmt(-c2)}>, <0, 0, 0>, <0, 0, {fmt(-c1)}>, {fmt(-c0)} }}"
        if c2 == 0:
            # POV-Ray 3.7.0 renders nothing for a quadric without a z^2 term
            # (a paraboloid); the same polynomial as a `poly` works.
            quad = f"poly {{ 2, <1, 0, 0, 0, 1, 0, 0, 0, {fmt(-c1)}, {fmt(-c0)}> }}"
        rmax = math.sqrt(max(c0 + c1 * z + c2 * z * z for z in (z0, z1, -c1 / (2 * c2) if c2 else z0)
                             if z0 <= z <= z1))
        slab = plane([0, 0, 1], z1) + " " + plane([0, 0, -1], -z0)
        bound = f"bounded_by {{ box {{ <{fmt(-rmax)}, {fmt(-rmax)}, {fmt(z0)}>, <{fmt(rmax)}, {fmt(rmax)}, {fmt(z1)}> }} }}"
        if caps:
            return f"intersection {{ {quad} {slab} {bound} }}"
        return f"object {{ {quad} clipped_by {{ {slab} }} {bound} }}"
    if kind in ("square_arch", "round_arch"):
        w = float(geo.get("width", 1))
        h = float(geo.get("height", 1.5))
        # The cutter overshoots the block in y and below, so that no
        # coincident faces remain; the opening is the same set.
        if kind == "square_arch":
            cut = f"box {{ <{fmt(-w / 2)}, -2, -2>, <{fmt(w / 2)}, 2, {fmt(-1 + h)}> }}"
        else:
            zs = -1 + h - w / 2
            cut = (f"union {{ box {{ <{fmt(-w / 2)}, -2, -2>, <{fmt(w / 2)}, 2, {fmt(zs)}> }} "
                   f"cylinder {{ <0, -2, {fmt(zs)}>, <0, 2, {fmt(zs)}>, {fmt(w / 2)} }} }}")
        return f"difference {{ box {{ <-1, -1, -1>, <1, 1, 1> }} {cut} }}"
    raise SystemExit(f"mid2pov: primitive {kind} is not converted")


def polygons_mesh(geo, m):
    if "mesh" in geo:
        raise SystemExit("mid2pov: FED mesh files are not converted")
    vs = [apply(m, [float(c) for c in v]) for v in geo["vertices"]]
    tris = []
    for face in geo["faces"]:
        face = [int(i) for i in face]
        for k in range(1, len(face) - 1):
            tris.append((face[0], face[k], face[k + 1]))
    body = " ".join(f"triangle {{ {vec(vs[a])}, {vec(vs[b])}, {vec(vs[c])} }}" for a, b, c in tris)
    return "mesh { " + body + " }"


def convert_object(obj, parent_m, parent_mat, mats, scale, out, indent, top=True):
    kind = obj["_kind"]
    m = mat_mul(parent_m, transform_of(obj)) if top else parent_m
    mat = mats.resolve(obj.get("rendering"), parent_mat)
    pad = "  " * indent
    if kind in ("union", "intersection", "difference"):
        out.append(f"{pad}{kind} {{  // {obj['_name'] or ''}")
        for child in obj["_children"]:
            convert_object(child, m, mat, mats, scale, out, indent + 1)
        out.append(f"{pad}}}")
        return
    geo = obj.get("geometry", {})
    tex = pov_texture(mat, scale)
    if kind == "polygons":
        out.append(f"{pad}object {{ {polygons_mesh(geo, m)} {tex} }}  // {obj['_name'] or ''}")
        return
    out.append(f"{pad}object {{ {shape(kind, geo)} {pov_matrix(m)} {tex} }}  // {obj['_name'] or ''}")


FADE = 0.01     # POV-Ray fade_distance; 2 / (1 + (d/f)^2) ~ 2 f^2 / d^2


def emitter_light(obj, mat, m, samples, scale, mats, out):
    """The area light of an emissive sphere, which carries the sphere itself
    as its `looks_like` object (so the sphere does not block its own light's
    shadow rays, as in our renderer, yet is seen and lit by other lights)."""
    if obj["_kind"] != "sphere" or obj["_children"]:
        raise SystemExit("mid2pov: only emissive spheres become area lights")
    centre = apply(m, [0, 0, 0])
    radius = math.sqrt(sum(m[i][0] ** 2 for i in range(3)))
    n = int(round(math.sqrt(samples)))
    if n * n != samples:
        raise SystemExit("mid2pov: --light-samples must be a square for POV-Ray's area_light grid")
    # Sphere of exitance M: E = M r^2 / d^2 at distance d.
    col = [scale / math.pi * e * radius * radius / (2 * FADE * FADE) for e in mat["emission"]]
    d = 2 * radius
    local = [row[:] for row in m]
    for i in range(3):
        local[i][3] -= centre[i]
    shape_sdl = []
    convert_object(obj, local, DEFAULT_MAT, mats, scale, shape_sdl, 0, top=False)
    out.append(f"light_source {{ <0, 0, 0> rgb {vec(col)} fade_distance {FADE} fade_power 2 "
               f"area_light <{fmt(d)}, 0, 0>, <0, {fmt(d)}, 0>, {n}, {n} circular orient jitter "
               f"looks_like {{ {shape_sdl[0].split('  //')[0]} }} translate {vec(centre)} }}"
               f"  // {obj['_name'] or ''}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--light-samples", type=int, default=4)
    ap.add_argument("--max-depth", type=int, default=5)
    ap.add_argument("--adc-bailout", default="1/255",
                    help="POV-Ray's adc_bailout, an SDL expression (default 1/255)")
    ap.add_argument("--scale", type=float, default=1.0,
                    help="POV colour per unit of our radiance (default 1)")
    args = ap.parse_args()
    with open(args.scene, encoding="utf-8") as f:
        items = Parser(tokens(f.read())).file()

    scale = args.scale
    mats = Materials()
    out = ["// Written by tools/bench/mid2pov.py from " + args.scene + "; do not edit.",
           "#version 3.7;",
           f"global_settings {{ assumed_gamma 1.0 max_trace_level {args.max_depth + 1} "
           f"adc_bailout {args.adc_bailout} ambient_light 0 }}",
           "background { rgb 0 }"]
    for it in items:
        kind = it["_kind"]
        if kind == "material":
            mats.named[it["_name"]] = mats.resolve(it, DEFAULT_MAT)
        elif kind == "camera":
            eye = [float(c) for c in it.get("eye", [0, 0, 0])]
            at = [float(c) for c in it.get("look_at", [0, 0, -1])]
            up = [float(c) for c in it.get("up", [0, 1, 0])]
            res = [int(c) for c in it.get("resolution", [512, 512])]
            if "focal_length" in it or float(it.get("aperture", 0)) > 0:
                raise SystemExit("mid2pov: only pinhole cameras with fov are converted")
            fov = float(it.get("fov", 45))
            f = [a - e for a, e in zip(at, eye)]
            fl = math.sqrt(sum(c * c for c in f))
            f = [c / fl for c in f]
            dot = sum(a * b for a, b in zip(up, f))
            u = [a - dot * b for a, b in zip(up, f)]
            ul = math.sqrt(sum(c * c for c in u))
            u = [c / ul for c in u]
            r = [f[1] * u[2] - f[2] * u[1], f[2] * u[0] - f[0] * u[2], f[0] * u[1] - f[1] * u[0]]
            aspect = res[0] / res[1]
            dlen = 0.5 / math.tan(math.radians(fov) / 2)
            # Explicit vectors (no look_at), so POV-Ray uses them as given:
            # ray = direction + sx right + sy up, sx, sy in [-1/2, 1/2].
            out.append(f"// resolution {res[0]} x {res[1]}")
            out.append(f"camera {{ perspective location {vec(eye)} direction {vec([c * dlen for c in f])} "
                       f"right {vec([c * aspect for c in r])} up {vec(u)} }}")
        elif kind == "point_light":
            m = transform_of(it)
            pos = apply(m, [float(c) for c in it.get("position", [0, 0, 0])])
            col = [scale / math.pi * i / (2 * FADE * FADE) for i in colour(it.get("intensity", 1))]
            out.append(f"light_source {{ {vec(pos)} rgb {vec(col)} fade_distance {FADE} fade_power 2 }}")
        elif kind == "spot_light":
            m = transform_of(it)
            pos = apply(m, [float(c) for c in it.get("position", [0, 0, 0])])
            d = apply(m, [float(c) for c in it.get("direction", [0, 0, -1])], 0.0)
            col = [scale / math.pi * i / (2 * FADE * FADE) for i in colour(it.get("intensity", 1))]
            ang, delta = float(it.get("cone_angle", 30)), float(it.get("cone_delta", 5))
            out.append(f"light_source {{ {vec(pos)} rgb {vec(col)} spotlight point_at "
                       f"{vec([p + c for p, c in zip(pos, d)])} radius {fmt(ang - delta)} "
                       f"falloff {fmt(ang)} tightness 0 fade_distance {FADE} fade_power 2 }}")
        elif kind == "directional_light":
            m = transform_of(it)
            d = apply(m, [float(c) for c in it.get("direction", [0, 0, -1])], 0.0)
            col = [scale / math.pi * e for e in colour(it.get("irradiance", 1))]
            far = [-1000 * c for c in d]
            out.append(f"light_source {{ {vec(far)} rgb {vec(col)} parallel point_at <0, 0, 0> }}")
        else:
            mat = mats.resolve(it.get("rendering"), DEFAULT_MAT)
            if max(mat["emission"]) > 0:
                emitter_light(it, mat, transform_of(it), args.light_samples, scale, mats, out)
            else:
                convert_object(it, identity(), DEFAULT_MAT, mats, scale, out, 0)
    sys.stdout.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
