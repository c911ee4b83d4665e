#!/usr/bin/env python3
"""Wall reflectances from virtual instruments against the measured ones.

    reflectance.py OUT.csv [REFLECTANCE.csv]

OUT.csv is `testbed measure scenes/cornell-box.mid --sensors sensors.csv -o OUT.csv`
(this folder's sensors). For each wall and filter, a radiance meter reads the
wall's radiance L and an irradiance meter beside the spot the light E falling
on it, both through the same 10 nm filter; a Lambertian wall has L = rho E / pi,
so pi L / E is its reflectance in the filter's band. The reference is the
Cornell Program of Computer Graphics' spectrophotometer data
(scenes/data/cornell-box-reflectance.csv, 400-700 nm at 4 nm), weighted by the
filter's triangle. Exit status 1 when some ratio is off by more than 4 of its
standard errors plus 1 %.
"""
import csv
import math
import os
import sys


def filter_mean(lam, rho, centre, half):
    """Mean of the piecewise-linear rho under a triangle of half-width `half` (1 nm steps)."""
    num = den = 0.0
    for k in range(-int(half), int(half) + 1):
        x = centre + k
        w = 1.0 - abs(k) / half
        i = max(j for j in range(len(lam) - 1) if lam[j] <= x)
        t = (x - lam[i]) / (lam[i + 1] - lam[i])
        num += w * (rho[i] + t * (rho[i + 1] - rho[i]))
        den += w
    return num / den


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    here = os.path.dirname(os.path.abspath(__file__))
    ref = sys.argv[2] if len(sys.argv) > 2 else os.path.join(here, '..', '..', '..', 'scenes', 'data',
                                                             'cornell-box-reflectance.csv')
    rows = {r['name']: r for r in csv.DictReader(open(sys.argv[1]))}
    data = [l for l in open(ref) if l[:1].isdigit()]
    lam = [float(l.split(',')[0]) for l in data]
    cols = {'back': 1, 'green': 2, 'red': 3}  # lambda_nm,white,green,red; the back wall is white
    bad = 0
    print('%-6s %4s  %9s  %9s  %8s  %s' % ('wall', 'nm', 'pi L / E', 'measured', 'off', 'se'))
    for wall, col in cols.items():
        rho = [float(l.split(',')[col]) for l in data]
        for nm in (450, 550, 650):
            L, E = rows['%s_L%d' % (wall, nm)], rows['%s_E%d' % (wall, nm)]
            l, sl, e, se = (float(L['reading']), float(L['reading_se']), float(E['reading']), float(E['reading_se']))
            r = math.pi * l / e
            sr = r * math.hypot(sl / l, se / e)
            m = filter_mean(lam, rho, nm, 10.0)
            ok = abs(r - m) <= 4.0 * sr + 0.01 * m
            bad += not ok
            print('%-6s %4d  %9.4f  %9.4f  %+7.2f%%  %.2f%%%s' % (wall, nm, r, m, 100 * (r / m - 1), sr / m * 100,
                                                                '' if ok else '  OFF'))
    sys.exit(1 if bad else 0)


main()
