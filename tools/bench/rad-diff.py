#!/usr/bin/env python3
"""Difference between two radiosity --patches CSVs of the same mesh: the
area-weighted RMS of B_a - B_b over every element and channel, relative to
the area-weighted RMS of the reflected radiosity of A (B - E would need the
emission; the walls' B is what a viewer sees, so plain B of A is used), and
the largest per-element relative difference.
  rad-diff.py A.csv B.csv
"""
import csv, math, sys

def read(path):
    rows = list(csv.reader(open(path)))
    head = rows[0]
    first = head.index('nz') + 1  # the channels follow the normal
    return [(float(r[head.index('area')]), [float(x) for x in r[first:]]) for r in rows[1:]]

a, b = read(sys.argv[1]), read(sys.argv[2])
if len(a) != len(b):
    sys.exit('rad-diff: %d and %d elements: not the same mesh' % (len(a), len(b)))
num = den = 0.0
worst = 0.0
for (wa, ba), (_, bb) in zip(a, b):
    for x, y in zip(ba, bb):
        num += wa * (x - y) ** 2
        den += wa * x * x
    ma = math.sqrt(sum(x * x for x in ba)) or 1e-300
    worst = max(worst, math.sqrt(sum((x - y) ** 2 for x, y in zip(ba, bb))) / ma)
print('relative RMS difference %.3e, largest per element %.3e' % (math.sqrt(num / den) if den else 0.0, worst))
