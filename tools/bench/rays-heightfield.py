#!/usr/bin/env python3
"""Writes a MID scene for `testbed bench rays`: one height-field mesh of
2 N^2 triangles (default N = 250: 125 000 triangles) filling the camera's
view, a quad area light above it and a unit sphere (an analytic primitive,
so Embree's user-geometry path is exercised too). Deterministic: the surface
is a sum of sines, no randomness.

    tools/bench/rays-heightfield.py [N] > /tmp/hf.mid
    tools/bench/rays-heightfield.py --obj [N] > /tmp/hf.obj   # the mesh alone, as OBJ
    tools/bench/rays-heightfield.py --rest                    # the MID text after the mesh

--obj and --rest serve tools/bench/rays-imported.sh, which runs the benchmark
on the same surface imported through Assimp (`testbed import`).
"""
import math
import sys

args = [a for a in sys.argv[1:] if not a.startswith("--")]
n = int(args[0]) if args else 250
out = sys.stdout


def height(x, y):
    return 0.15 * math.sin(3.1 * x) * math.cos(2.3 * y) + 0.05 * math.sin(11.0 * x + 7.0 * y)


def write_rest():
    """Everything but the mesh: the sphere and the lamp (after the materials and camera)."""
    out.write('sphere "ball" {\n    transform = [scale(0.4) translate([0.3 0.2 0.5])]\n'
              '    rendering = { material = "ball" }\n}\n')
    # The lamp faces down: counter-clockwise seen from below.
    out.write('polygons "lamp" {\n    geometry = {\n'
              "        vertices = [[-0.5 -0.5 2.5] [-0.5 0.5 2.5] [0.5 0.5 2.5] [0.5 -0.5 2.5]]\n"
              "        faces = [[0 1 2 3]]\n    }\n"
              '    rendering = { material = "lamp" }\n}\n')


def write_header():
    out.write('camera "bench" {\n    eye = [0 -2.6 1.9]\n    look_at = [0 0 0]\n    up = [0 0 1]\n'
              "    fov = 45\n    resolution = [512 512]\n}\n")
    out.write('material "ground" {\n    diffuse = 0.7\n}\n')
    out.write('material "ball" {\n    diffuse = [0.8 0.3 0.2]\n}\n')
    out.write('material "lamp" {\n    diffuse = 0.8\n    emission = [20 20 20]\n}\n')


if "--obj" in sys.argv:
    for j in range(n + 1):
        y = -2.0 + 4.0 * j / n
        for i in range(n + 1):
            x = -2.0 + 4.0 * i / n
            out.write(f"v {x:.6f} {y:.6f} {height(x, y):.6f}\n")
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i + 1  # OBJ counts from 1
            b, c, d = a + 1, a + n + 2, a + n + 1
            out.write(f"f {a} {b} {c}\nf {a} {c} {d}\n")
    sys.exit(0)
if "--rest" in sys.argv:
    write_header()
    write_rest()
    sys.exit(0)
out.write("mid 1\n")
write_header()
out.write("polygons \"heightfield\" {\n    geometry = {\n        vertices = [\n")
for j in range(n + 1):
    y = -2.0 + 4.0 * j / n
    for i in range(n + 1):
        x = -2.0 + 4.0 * i / n
        z = height(x, y)
        out.write(f"            [{x:.6f} {y:.6f} {z:.6f}]\n")
out.write("        ]\n        faces = [\n")
for j in range(n):
    for i in range(n):
        a = j * (n + 1) + i
        b, c, d = a + 1, a + n + 2, a + n + 1
        # counter-clockwise seen from +z: the front side faces up
        out.write(f"            [{a} {b} {c}] [{a} {c} {d}]\n")
out.write('        ]\n    }\n    rendering = { material = "ground" }\n}\n')
write_rest()
