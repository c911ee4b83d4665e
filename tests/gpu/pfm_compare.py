"""Compares two PFM files for the GPU script tests (called by the nmse and
mapcmp helpers of gpu_test.sh; b is the reference):
  pfm_compare.py nmse A.pfm B.pfm    colour (PF): sum (a - b)^2 / sum b^2
  pfm_compare.py mapcmp A.pfm B.pfm  grey (Pf, a sample map):
                                     "differing-pixels total-A total-B min-A max-A pixels"
"""
import struct
import sys


def rd(path, magic, channels):
    with open(path, 'rb') as f:
        assert f.readline().strip() == magic
        w, h = map(int, f.readline().split())
        s = float(f.readline())
        n = w * h * channels
        return struct.unpack(('<' if s < 0 else '>') + '%df' % n, f.read(4 * n))


def main(what, pa, pb):
    if what == 'nmse':
        a, b = rd(pa, b'PF', 3), rd(pb, b'PF', 3)
        assert len(a) == len(b)
        num = sum((x - y) ** 2 for x, y in zip(a, b))
        den = sum(y * y for y in b)
        print('%.6g' % (num / den if den > 0 else float('inf')))
    elif what == 'mapcmp':
        a, b = rd(pa, b'Pf', 1), rd(pb, b'Pf', 1)
        assert len(a) == len(b)
        print(sum(x != y for x, y in zip(a, b)), int(sum(a)), int(sum(b)), int(min(a)), int(max(a)), len(a))
    else:
        sys.exit('pfm_compare.py: unknown comparison %r (nmse or mapcmp)' % what)


if __name__ == '__main__':
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(*sys.argv[1:])
