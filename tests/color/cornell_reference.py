#!/usr/bin/env python3
"""Independent reference for tests/color/test_cornell.c: the Cornell Box wall
reflectances (tests/color/data/cornell-box-reflectance.csv) lit by CIE D65,
as CIE XYZ (white Y = 1) and linear sRGB.

Shares no code with util/color. Plain python3, no numpy. It reads the same
published tables (the CSV files) and follows the same stated conventions:
spectra are linear between samples and zero outside their sample range. But the
integrals are computed differently: a midpoint rule with a 0.001 nm step (C uses
the exact Simpson rule on merged breakpoints), and the sRGB matrix is derived
here from the IEC 61966-2-1 primaries and white by Cramer's rule.

Run:  python3 tests/color/cornell_reference.py   (takes a few seconds)
and paste the printed values into test_cornell.c if the inputs ever change.
"""
import bisect
import os

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def read_csv(path):
    """Returns (header, columns) of a CSV with '#' comments and one header line."""
    header, rows = None, []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            if header is None:
                header = line.split(",")
                continue
            rows.append([float(x) for x in line.split(",")])
    return header, [list(c) for c in zip(*rows)]


class Linear:
    """Piecewise-linear function through (xs, ys), zero outside [xs[0], xs[-1]]."""

    def __init__(self, xs, ys):
        self.xs, self.ys = xs, ys

    def __call__(self, x):
        xs, ys = self.xs, self.ys
        if x < xs[0] or x > xs[-1]:
            return 0.0
        i = bisect.bisect_right(xs, x) - 1
        if i >= len(xs) - 1:
            return ys[-1]
        t = (x - xs[i]) / (xs[i + 1] - xs[i])
        return ys[i] + t * (ys[i + 1] - ys[i])


def integrate(f, lo, hi, steps):
    h = (hi - lo) / steps
    return h * sum(f(lo + (k + 0.5) * h) for k in range(steps))


def det3(m):
    return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))


def solve3(m, b):
    """Cramer's rule."""
    d = det3(m)
    out = []
    for c in range(3):
        mc = [[b[r] if k == c else m[r][k] for k in range(3)] for r in range(3)]
        out.append(det3(mc) / d)
    return out


def xyz_of(x, y):
    return [x / y, 1.0, (1.0 - x - y) / y]


def main():
    _, (lam, xbar, ybar, zbar) = read_csv(os.path.join(ROOT, "util/color/cie1931-2deg-5nm.csv"))
    _, (dlam, d65) = read_csv(os.path.join(ROOT, "util/color/cie-d65-5nm.csv"))
    names, cols = read_csv(os.path.join(HERE, "data/cornell-box-reflectance.csv"))
    cmf = [Linear(lam, xbar), Linear(lam, ybar), Linear(lam, zbar)]
    light = Linear(dlam, d65)
    # Everything is zero outside the CMF range 380-780 nm; 400000 midpoints
    # never fall on a sample (all samples are whole nm).
    lo, hi, steps = 380.0, 780.0, 400000

    # sRGB: columns are the primaries' XYZ scaled so that they add up to white.
    prim = [xyz_of(0.64, 0.33), xyz_of(0.30, 0.60), xyz_of(0.15, 0.06)]
    white = xyz_of(0.3127, 0.3290)
    pm = [[prim[c][r] for c in range(3)] for r in range(3)]
    scale = solve3(pm, white)
    rgb_to_xyz = [[pm[r][c] * scale[c] for c in range(3)] for r in range(3)]

    norm = integrate(lambda l: light(l) * cmf[1](l), lo, hi, steps)
    for k, name in enumerate(names[1:], start=1):
        refl = Linear(cols[0], cols[k])
        xyz = [integrate(lambda l: refl(l) * light(l) * c(l), lo, hi, steps) / norm for c in cmf]
        rgb = solve3(rgb_to_xyz, xyz)
        print("%-6s XYZ = {%.9f, %.9f, %.9f}  linear sRGB = {%.9f, %.9f, %.9f}"
              % ((name,) + tuple(xyz) + tuple(rgb)))


if __name__ == "__main__":
    main()
