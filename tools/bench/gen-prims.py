#!/usr/bin/env python3
"""Writes N analytic primitives without lamps (docs/performance.md, "Scale"):
spheres, cubes, cylinders, cones and tori in turn, each rotated about z,
scaled by 0.4 and placed on a square grid; one point light, a camera.
    tools/bench/gen-prims.py 1000000 > prims-1000000.mid"""
import math
import sys

n = int(float(sys.argv[1])) if len(sys.argv) > 1 else 100000
side = max(1, math.isqrt(n - 1) + 1) if n > 1 else 1
h = side / 2
out = sys.stdout
out.write('mid 1\ncamera { eye = [%g %g %g] look_at = [%g %g 0] up = [0 0 1] resolution = [64 48] }\n'
          % (h, -0.6 * side, 0.6 * side, h, h))
out.write('point_light { position = [%g %g %g] intensity = %g }\n' % (h, h, 0.8 * side, side * side))
kinds = ['sphere', 'cube', 'cylinder', 'cone', 'torus']
for i in range(n):
    out.write('%s { transform = [rotate([0 0 1], %d) scale(0.4) translate([%d %d 0])] }\n'
              % (kinds[i % 5], i % 360, i % side, i // side))
