#!/usr/bin/env python3
"""Ray files for `testbed trace` (docs/trace.md), and a summary of HITS files.

    trace_rays.py random N OUT.bin --box X0 Y0 Z0 X1 Y1 Z1 [--seed S]
        N rays with origins uniform in the box and directions uniform on the
        unit sphere, tmin 0, tmax +inf (the benchmark rays of
        docs/performance.md, "testbed trace").
    trace_rays.py summary HITS.bin
        number of records, hits, misses, and hits per object.

Pure Python (struct), little-endian float32 as the format says.
"""
import argparse
import math
import random
import struct
import sys
from collections import Counter

RAY = struct.Struct("<8f")   # ox oy oz tmin dx dy dz tmax
HIT = struct.Struct("<fIIfffff")  # t object face u v nx ny nz
MISS = 0xFFFFFFFF


def random_rays(n, box, seed, out):
    rng = random.Random(seed)
    x0, y0, z0, x1, y1, z1 = box
    buf = bytearray()
    with open(out, "wb") as f:
        for i in range(n):
            # uniform direction: z uniform in [-1, 1], azimuth uniform
            z = rng.uniform(-1.0, 1.0)
            phi = rng.uniform(0.0, 2.0 * math.pi)
            r = math.sqrt(max(0.0, 1.0 - z * z))
            buf += RAY.pack(rng.uniform(x0, x1), rng.uniform(y0, y1), rng.uniform(z0, z1), 0.0,
                            r * math.cos(phi), r * math.sin(phi), z, math.inf)
            if len(buf) >= 1 << 20:
                f.write(buf)
                buf.clear()
        f.write(buf)


def summary(path):
    data = open(path, "rb").read()
    if len(data) % HIT.size:
        sys.exit("%s: %d bytes is not a multiple of %d" % (path, len(data), HIT.size))
    per_object = Counter()
    for t, obj, face, u, v, nx, ny, nz in HIT.iter_unpack(data):
        per_object[obj] += 1
    n = len(data) // HIT.size
    misses = per_object.pop(MISS, 0)
    print("%d records, %d hits, %d misses" % (n, n - misses, misses))
    for obj in sorted(per_object):
        print("  object %d: %d" % (obj, per_object[obj]))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("random")
    r.add_argument("n", type=int)
    r.add_argument("out")
    r.add_argument("--box", type=float, nargs=6, required=True, metavar=("X0", "Y0", "Z0", "X1", "Y1", "Z1"))
    r.add_argument("--seed", type=int, default=1)
    s = sub.add_parser("summary")
    s.add_argument("hits")
    a = p.parse_args()
    if a.cmd == "random":
        random_rays(a.n, a.box, a.seed, a.out)
    else:
        summary(a.hits)


if __name__ == "__main__":
    main()
