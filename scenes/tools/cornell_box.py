#!/usr/bin/env python3
"""Writes the bundled Cornell Box scenes from the published data.

    python3 scenes/tools/cornell_box.py          # (re)write the four files
    python3 scenes/tools/cornell_box.py --check  # exit 1 if a committed file differs

Files written (paths relative to the repository root):

    scenes/cornell-box.mid                        spectral materials and light
    scenes/cornell-box-rgb.mid                    the same scene in linear sRGB
    scenes/cornell-box-spheres.mid                spectral, a mirror and a glass sphere instead of the blocks
    scenes/tests/cornell-box-coplanar-light.mid   the light left coplanar with the ceiling

Sources: the Cornell University Program of Computer Graphics "Cornell Box
Data" (geometry, camera and light typed below as published;
scenes/data/cornell-box-reflectance.csv holds the measured reflectances), the
CIE 1931 2-degree colour matching functions and the CIE D65 table shipped in
util/color/.

The RGB variant is computed here in plain Python, independently of
util/color, by the same definitions (docs/color.md): spectra linear between
samples and zero outside their range; integrals of products of piecewise-linear
functions computed exactly (Simpson's rule on every interval between merged
breakpoints is exact for the cubic pieces); reflectance under D65 with white
Y = 1, X = int(R S xbar) / int(S ybar); emission X = int(M xbar) dlambda (lambda
in nm); linear sRGB from XYZ by the inverse of the matrix built from the sRGB
primaries and the D65 white (0.3127, 0.3290). tests/scenes/test_cornell_box.c
checks the values written against util/color's own conversion.
"""

import math
import os
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))

# ---------------------------------------------------------------- published data

# Each surface a quadrilateral, vertices (x y z, mm) in published order.
SURFACES = [
    ("floor", "white", "552.8 0 0 | 0 0 0 | 0 0 559.2 | 549.6 0 559.2"),
    ("ceiling", "white", "556 548.8 0 | 556 548.8 559.2 | 0 548.8 559.2 | 0 548.8 0"),
    ("back wall", "white", "549.6 0 559.2 | 0 0 559.2 | 0 548.8 559.2 | 556 548.8 559.2"),
    ("right wall", "green", "0 0 559.2 | 0 0 0 | 0 548.8 0 | 0 548.8 559.2"),
    ("left wall", "red", "552.8 0 0 | 549.6 0 559.2 | 556 548.8 559.2 | 556 548.8 0"),
]
LIGHT = "343 548.8 227 | 343 548.8 332 | 213 548.8 332 | 213 548.8 227"
BLOCKS = [
    ("short block", [
        "130 165 65 | 82 165 225 | 240 165 272 | 290 165 114",
        "290 0 114 | 290 165 114 | 240 165 272 | 240 0 272",
        "130 0 65 | 130 165 65 | 290 165 114 | 290 0 114",
        "82 0 225 | 82 165 225 | 130 165 65 | 130 0 65",
        "240 0 272 | 240 165 272 | 82 165 225 | 82 0 225",
    ]),
    ("tall block", [
        "423 330 247 | 265 330 296 | 314 330 456 | 472 330 406",
        "423 0 247 | 423 330 247 | 472 330 406 | 472 0 406",
        "472 0 406 | 472 330 406 | 314 330 456 | 314 0 456",
        "314 0 456 | 314 330 456 | 265 330 296 | 265 0 296",
        "265 0 296 | 265 330 296 | 423 330 247 | 423 0 247",
    ]),
]
# Relative spectral radiance of the light.
LIGHT_NM = [400, 500, 600, 700]
LIGHT_L = [0.0, 8.0, 15.6, 18.4]
# The lowered light (the published light is at the ceiling's height, 548.8).
LIGHT_Y_LOWERED = "548.7"
# Interior point used to check that every wall faces into the box.
BOX_CENTRE = (278.0, 274.4, 279.6)

# cornell-box-spheres.mid: the two blocks replaced by a mirror sphere (left,
# back: large x and z) and a glass sphere (right, front), as in Jensen's
# photon-mapping box. Name, material, centre x and z, radius (mm); each rests
# SPHERE_GAP above the floor (y = 0), so no ray meets sphere and floor at
# one distance.
SPHERES = [
    ("mirror sphere", "mirror", 380.0, 370.0, 95.0),
    ("glass sphere", "glass", 185.0, 165.0, 95.0),
]
SPHERE_GAP = 0.1
# The smallest gap (mm) the spheres keep from the walls and from each other
# (checked when writing).
SPHERE_CLEARANCE = 20.0


def quad(text):
    return [tuple(v.split()) for v in text.split("|")]


def fnum(v):
    return float(v)


# ---------------------------------------------------------------- spectra

def read_csv(path):
    """Rows of numbers of a CSV with '#' comment lines and one header line."""
    header, rows = None, []
    with open(path, encoding="utf-8") as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            if header is None:
                header = line.split(",")
                continue
            rows.append(line.split(","))
    return header, rows


def table(path):
    header, rows = read_csv(path)
    cols = {name: [r[i] for r in rows] for i, name in enumerate(header)}
    return cols


class Pl:
    """A piecewise-linear function: linear between samples, zero outside."""

    def __init__(self, lam, val):
        self.lam = [float(x) for x in lam]
        self.val = [float(x) for x in val]

    def __call__(self, x):
        lam, val = self.lam, self.val
        if x < lam[0] or x > lam[-1]:
            return 0.0
        lo, hi = 0, len(lam) - 1
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if lam[mid] <= x:
                lo = mid
            else:
                hi = mid
        if x == lam[hi]:
            return val[hi]
        t = (x - lam[lo]) / (lam[hi] - lam[lo])
        return val[lo] + t * (val[hi] - val[lo])


def product_integral(*fs):
    """Exact integral of a product of piecewise-linear functions over the range
    where all are defined (Simpson on each piece: the product is a cubic)."""
    lo = max(f.lam[0] for f in fs)
    hi = min(f.lam[-1] for f in fs)
    pts = sorted({x for f in fs for x in f.lam if lo <= x <= hi} | {lo, hi})
    total = 0.0
    for p, q in zip(pts, pts[1:]):
        # [lo, hi] lies inside every factor's range, so no factor jumps to
        # zero inside a piece.
        def g(x):
            r = 1.0
            for f in fs:
                r *= f(x)
            return r
        m = 0.5 * (p + q)
        total += (q - p) / 6.0 * (g(p) + 4.0 * g(m) + g(q))
    return total


def xyz_to_srgb_matrix():
    prim = [(0.64, 0.33), (0.30, 0.60), (0.15, 0.06)]
    wx, wy = 0.3127, 0.3290
    cols = [(x / y, 1.0, (1.0 - x - y) / y) for x, y in prim]
    w = (wx / wy, 1.0, (1.0 - wx - wy) / wy)
    a = [[cols[j][i] for j in range(3)] for i in range(3)]
    s = solve3(a, w)
    m = [[a[i][j] * s[j] for j in range(3)] for i in range(3)]
    return inverse3(m)


def det3(a):
    return (a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]))


def solve3(a, b):
    d = det3(a)
    out = []
    for k in range(3):
        ak = [[b[i] if j == k else a[i][j] for j in range(3)] for i in range(3)]
        out.append(det3(ak) / d)
    return out


def inverse3(a):
    cols = [solve3(a, [1.0 if i == k else 0.0 for i in range(3)]) for k in range(3)]
    return [[cols[j][i] for j in range(3)] for i in range(3)]


def mat_vec(m, v):
    return [sum(m[i][j] * v[j] for j in range(3)) for i in range(3)]


# ---------------------------------------------------------------- formatting

def g7(x):
    s = "%.7g" % x
    return "0" if s in ("-0", "0") else s


def wrap_list(items, indent, per_line):
    lines = []
    for i in range(0, len(items), per_line):
        lines.append(indent + " ".join(items[i:i + per_line]))
    return lines


def spectrum_lines(nm, values, indent):
    """spectrum([...], [...]) spread over lines, 12 samples a line."""
    out = ["spectrum(", indent + "    ["]
    out += wrap_list(nm, indent + "        ", 12)
    out += [indent + "    ],", indent + "    ["]
    out += wrap_list(values, indent + "        ", 12)
    out += [indent + "    ])"]
    return out


def vertex_text(v):
    return "[" + " ".join(v) + "]"


def newell(pts):
    n = [0.0, 0.0, 0.0]
    for i, a in enumerate(pts):
        b = pts[(i + 1) % len(pts)]
        n[0] += (a[1] - b[1]) * (a[2] + b[2])
        n[1] += (a[2] - b[2]) * (a[0] + b[0])
        n[2] += (a[0] - b[0]) * (a[1] + b[1])
    return n


def centroid(pts):
    return [sum(p[i] for p in pts) / len(pts) for i in range(3)]


def faces_towards(pts, target):
    n = newell(pts)
    c = centroid(pts)
    return sum(n[i] * (target[i] - c[i]) for i in range(3)) > 0.0


def oriented(name, q, inward_to=None, outward_from=None):
    """The quad in published order if its front side (counter-clockwise, MID's
    rule) faces the right way; otherwise reversed, with a note."""
    pts = [tuple(map(fnum, v)) for v in q]
    if inward_to is not None:
        ok = faces_towards(pts, inward_to)
    else:
        c = centroid(pts)
        ok = faces_towards(pts, [2 * c[i] - outward_from[i] for i in range(3)])
    if ok:
        return q, None
    return list(reversed(q)), "%s: vertex order reversed from the published order" % name


# ---------------------------------------------------------------- the scenes

def header(variant):
    return """mid 1
# The Cornell Box: {variant}.
# From the Cornell University Program of Computer Graphics "Cornell Box Data"
# (https://www.graphics.cornell.edu/online/box/data.html).
# Written by scenes/tools/cornell_box.py; edit that script, not this file.
# Conventions (docs/scenes.md):
# - Units: millimetres. The published camera (focal length 0.035 m, film
#   0.025 m x 0.025 m) is given here in mm, as MID wants.
# - Geometry exactly as published: every surface one quad, vertices in the
#   published order. MID's front side is the one from which a face's vertices
#   run counter-clockwise (docs/mid.md, 6.3); the published order already makes
#   every wall, the floor, the ceiling and the light face into the box and
#   every block face point out of its block (checked by the script and by
#   tests/scenes), so no order was reversed.
# - The red (left) wall is NOT planar: its fourth vertex lies 3.2 mm off the
#   plane of the other three. It is kept as the published quad; the meshing
#   module splits it into two triangles explicitly (docs/scenes.md).
# - The light is lowered by 0.1 mm (y = 548.7 instead of the ceiling's 548.8)
#   so rays never meet two coplanar surfaces at the same distance.
#   scenes/tests/cornell-box-coplanar-light.mid keeps the coplanar original.
""".format(variant=variant)


def camera():
    # fov = 2 atan((25 / 2) / 35) = 39.3076481 degrees on a square image.
    return """
# Camera: position 278 273 -800 looking along +z, up +y; a 35 mm lens on a
# 25 mm x 25 mm film gives a vertical (and horizontal) field of view of
# 2 atan(12.5 / 35) = 39.3076481 degrees.
camera "cornell" {
    eye = [278 273 -800]
    look_at = [278 273 -799]
    up = [0 1 0]
    focal_length = 35
    film = [25 25]
    resolution = [512 512]
}
"""


def emission_values():
    """pi L at the published samples, as written in the file."""
    return [g7(math.pi * v) for v in LIGHT_L]


EMISSION_COMMENT = """# Emission. The data give the light's relative spectral radiance at 400, 500,
# 600 and 700 nm: 0, 8, 15.6, 18.4. We take these numbers as absolute spectral
# radiance L in W/(m^2 sr nm). MID's emission is the radiant exitance of a
# diffuse emitter, M = pi L (docs/mid.md, section 7), so the samples below are
# pi times the published ones (the integral of M over 400-700 nm is
# 3280 pi = 10304 W/m^2; over the 130 mm x 105 mm light that is 140.7 W).
"""

SPECTRUM_COMMENT = """# Spectra are linear between samples and zero outside them (docs/mid.md, 7.1,
# and the usual convention for this data): the measured reflectances and the
# light cover 400-700 nm only.
"""


def materials_spectral(refl):
    out = ["", SPECTRUM_COMMENT.rstrip("\n")]
    nm = refl["lambda_nm"]
    for name in ("white", "green", "red"):
        out.append("# Measured Lambertian reflectance, 400-700 nm at 4 nm.")
        out.append('material "%s" {' % name)
        lines = spectrum_lines(nm, refl[name], "    ")
        out.append("    diffuse = " + lines[0])
        out += lines[1:]
        out.append("}")
    out.append(EMISSION_COMMENT.rstrip("\n"))
    out.append("# The data give no reflectance for the light's diffuser: 0.78 grey, the")
    out.append("# value commonly used with this data.")
    out.append('material "light" {')
    out.append("    diffuse = 0.78")
    out.append("    emission = spectrum([%s], [%s])" % (" ".join(str(x) for x in LIGHT_NM),
                                                      " ".join(emission_values())))
    out.append("}")
    return "\n".join(out) + "\n"


def rgb_values(refl):
    cmf = table(os.path.join(ROOT, "util/color/cie1931-2deg-5nm.csv"))
    d65 = table(os.path.join(ROOT, "util/color/cie-d65-5nm.csv"))
    xbar = Pl(cmf["lambda_nm"], cmf["xbar"])
    ybar = Pl(cmf["lambda_nm"], cmf["ybar"])
    zbar = Pl(cmf["lambda_nm"], cmf["zbar"])
    dcol = [k for k in d65 if k != "lambda_nm"][0]
    s = Pl(d65["lambda_nm"], d65[dcol])
    m = xyz_to_srgb_matrix()
    norm = product_integral(s, ybar)
    rgb = {}
    for name in ("white", "green", "red"):
        r = Pl(refl["lambda_nm"], refl[name])
        xyz = [product_integral(r, s, cmf_) / norm for cmf_ in (xbar, ybar, zbar)]
        rgb[name] = mat_vec(m, xyz)
    e = Pl(LIGHT_NM, [float(v) for v in emission_values()])
    xyz = [product_integral(e, cmf_) for cmf_ in (xbar, ybar, zbar)]
    rgb["light"] = mat_vec(m, xyz)
    return rgb


def materials_rgb(refl):
    rgb = rgb_values(refl)
    out = ["",
           "# Linear sRGB (ITU-R BT.709 primaries, D65 white) computed by",
           "# scenes/tools/cornell_box.py from the measured spectra of cornell-box.mid",
           "# (zero outside 400-700 nm, CIE 1931 2-degree observer):",
           "# reflectances seen under illuminant D65 with white Y = 1,",
           "# X = int(R D65 xbar) / int(D65 ybar), then XYZ -> linear sRGB."]
    for name in ("white", "green", "red"):
        out.append('material "%s" {' % name)
        out.append("    diffuse = [%s]" % " ".join(g7(c) for c in rgb[name]))
        out.append("}")
    out.append(EMISSION_COMMENT.rstrip("\n"))
    out += ["# In RGB: X = int(M xbar) dlambda (lambda in nm), then XYZ -> linear sRGB, so",
            "# an RGB white (1 1 1) emitter has int(M ybar) = 1 (util/color's",
            "# convention, tb_smits_emission). Negative channels would be clipped; none are.",
            'material "light" {',
            "    diffuse = 0.78",
            "    emission = [%s]" % " ".join(g7(c) for c in rgb["light"]),
            "}"]
    for k, v in rgb.items():
        if min(v) < 0.0:
            sys.exit("cornell_box.py: %s is out of the sRGB gamut: %r" % (k, v))
    return "\n".join(out) + "\n"


def geometry(light_y, blocks=True):
    out = [""]
    notes = []
    for name, mat, text in SURFACES:
        q, note = oriented(name, quad(text), inward_to=BOX_CENTRE)
        if note:
            notes.append(note)
        if name == "left wall":
            out.append("# Not planar: the fourth vertex is 3.2 mm off the plane of the first three.")
            out.append("# Kept as published; the meshing module splits it explicitly.")
        out.append('polygons "%s" {' % name)
        out.append("    geometry = {")
        out.append("        vertices = [%s]" % " ".join(vertex_text(v) for v in q))
        out.append("        faces = [[0 1 2 3]]")
        out.append("    }")
        out.append('    rendering = { material = "%s" }' % mat)
        out.append("}")
    q, note = oriented("light", quad(LIGHT), inward_to=BOX_CENTRE)
    if note:
        notes.append(note)
    q = [(v[0], light_y, v[2]) for v in q]
    if light_y == "548.8":
        out.append("# The light exactly as published: coplanar with the ceiling (y = 548.8).")
    else:
        out.append("# The light, lowered by 0.1 mm from the published y = 548.8 (coplanar with")
        out.append("# the ceiling) to y = %s." % light_y)
    out.append('polygons "light" {')
    out.append("    geometry = {")
    out.append("        vertices = [%s]" % " ".join(vertex_text(v) for v in q))
    out.append("        faces = [[0 1 2 3]]")
    out.append("    }")
    out.append('    rendering = { material = "light" }')
    out.append("}")
    for name, faces in BLOCKS if blocks else []:
        verts, idx = [], []
        all_pts = [tuple(map(fnum, v)) for f in faces for v in quad(f)]
        c = centroid(all_pts)
        for i, f in enumerate(faces):
            q, note = oriented("%s face %d" % (name, i), quad(f), outward_from=c)
            if note:
                notes.append(note)
            face = []
            for v in q:
                if v not in verts:
                    verts.append(v)
                face.append(verts.index(v))
            idx.append(face)
        out.append("# Top, then four sides, as published; the 8 corners listed once, in order")
        out.append("# of first use. Open at the bottom (it stands on the floor).")
        out.append('polygons "%s" {' % name)
        out.append("    geometry = {")
        out.append("        vertices = [")
        out += ["            " + vertex_text(v) for v in verts]
        out.append("        ]")
        out.append("        faces = [%s]" % " ".join("[" + " ".join(map(str, f)) + "]" for f in idx))
        out.append("    }")
        out.append('    rendering = { material = "white" }')
        out.append("}")
    if notes:
        out.insert(1, "# Orientation fixes: " + "; ".join(notes) + ".")
    return "\n".join(out) + "\n"


SPHERE_MATERIALS = """
# The spheres' materials (MID 1 attributes, docs/mid.md section 7; as
# scenes/showcase.mid). The mirror: black diffuse, specular 0.95 with a
# narrow lobe, so the ray tracer follows a mirror ray. The glass: a smooth
# dielectric of index 1.5 (the tracer weights reflection by the exact
# Fresnel term and refraction by transmission (1 - R)), with a little
# specular for the highlight. Grey values: flat spectra in this spectral scene.
material "mirror" {
    diffuse = 0
    specular = 0.95
    exponent = 10000
}
material "glass" {
    diffuse = 0
    specular = 0.05
    exponent = 10000
    transmission = 1
    ior = 1.5
}
"""


def spheres():
    """The two spheres, checked to rest on the floor inside the box, apart."""
    out = ["# The spheres: radius %s mm, resting %s mm above the floor (centre y = r + %s)."
           % (g7(SPHERES[0][4]), g7(SPHERE_GAP), g7(SPHERE_GAP))]
    lo_x = max(fnum(v[0]) for name, _, t in SURFACES if name == "right wall" for v in quad(t))
    hi_x = min(fnum(v[0]) for name, _, t in SURFACES if name == "left wall" for v in quad(t))
    hi_z = min(fnum(v[2]) for name, _, t in SURFACES if name == "back wall" for v in quad(t))
    for i, (name, mat, x, z, r) in enumerate(SPHERES):
        if not (x - r >= lo_x + SPHERE_CLEARANCE and x + r <= hi_x - SPHERE_CLEARANCE and
                z - r >= SPHERE_CLEARANCE and z + r <= hi_z - SPHERE_CLEARANCE):
            sys.exit("cornell_box.py: %s does not fit in the box" % name)
        for other in SPHERES[:i]:
            if math.hypot(x - other[2], z - other[3]) < r + other[4] + SPHERE_CLEARANCE:
                sys.exit("cornell_box.py: %s is too close to %s" % (name, other[0]))
        out.append('sphere "%s" {' % name)
        out.append("    transform = [scale(%s) translate([%s %s %s])]" % (g7(r), g7(x), g7(r + SPHERE_GAP), g7(z)))
        out.append('    rendering = { material = "%s" }' % mat)
        out.append("}")
    return "\n".join(out) + "\n"


def scenes():
    refl = table(os.path.join(ROOT, "scenes/data/cornell-box-reflectance.csv"))
    spectral = header("spectral materials and light") + camera() + materials_spectral(refl)
    rgb = header("linear sRGB materials and light") + camera() + materials_rgb(refl)
    coplanar = header("spectral; the light coplanar with the ceiling, for tie-breaking tests")
    coplanar = coplanar.replace(
        "# - The light is lowered by 0.1 mm (y = 548.7 instead of the ceiling's 548.8)\n"
        "#   so rays never meet two coplanar surfaces at the same distance.\n"
        "#   scenes/tests/cornell-box-coplanar-light.mid keeps the coplanar original.\n",
        "# - THIS FILE keeps the light as published, coplanar with the ceiling\n"
        "#   (y = 548.8) and overlapping it: rays that hit the light hit the ceiling\n"
        "#   at the same distance. A test case for tie-breaking; the bundled\n"
        "#   scenes/cornell-box.mid lowers the light by 0.1 mm instead.\n")
    coplanar += camera() + materials_spectral(refl)
    sph = header("spectral; a mirror sphere and a glass sphere instead of the two blocks")
    sph = sph.replace(
        "#   every wall, the floor, the ceiling and the light face into the box and\n"
        "#   every block face point out of its block (checked by the script and by\n"
        "#   tests/scenes), so no order was reversed.\n",
        "#   every wall, the floor, the ceiling and the light face into the box\n"
        "#   (checked by the script and by tests/scenes), so no order was reversed.\n"
        "# - The blocks are replaced by a mirror sphere (left, back) and a glass\n"
        "#   sphere (right, front), as in Jensen's photon-mapping box: mirror and\n"
        "#   glass for the ray tracer, caustics for a path tracer, colour bleeding\n"
        "#   on the walls for radiosity (docs/scenes.md).\n")
    sph += camera() + materials_spectral(refl) + SPHERE_MATERIALS + geometry(LIGHT_Y_LOWERED, blocks=False) + spheres()
    return {
        "scenes/cornell-box.mid": spectral + geometry(LIGHT_Y_LOWERED),
        "scenes/cornell-box-rgb.mid": rgb + geometry(LIGHT_Y_LOWERED),
        "scenes/cornell-box-spheres.mid": sph,
        "scenes/tests/cornell-box-coplanar-light.mid": coplanar + geometry("548.8"),
    }


def main():
    check = "--check" in sys.argv[1:]
    bad = 0
    for rel, text in scenes().items():
        path = os.path.join(ROOT, rel)
        if check:
            try:
                with open(path, encoding="utf-8") as f:
                    old = f.read()
            except OSError:
                old = None
            if old != text:
                print("cornell_box.py: %s is not what the script writes (run it to update)" % rel)
                bad = 1
        else:
            os.makedirs(os.path.dirname(path), exist_ok=True)
            with open(path, "w", encoding="utf-8") as f:
                f.write(text)
    return bad


if __name__ == "__main__":
    sys.exit(main())
