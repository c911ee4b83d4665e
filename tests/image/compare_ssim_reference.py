#!/usr/bin/env python3
"""Independent SSIM reference for Testbed's image comparison tests.

Plain Python (no numpy), written from Wang, Bovik, Sheikh and Simoncelli,
"Image quality assessment: from error visibility to structural similarity",
IEEE TIP 13(4), 2004, and their reference MATLAB code (ssim_index.m):
an 11x11 Gaussian window with sigma 1.5 normalised to sum 1, K1 = 0.01,
K2 = 0.03, L = the peak value, statistics over every window that lies wholly
inside the image ("valid" filtering), SSIM = mean of the SSIM map.

Unlike the C code it evaluates each window directly in 2-D and computes the
variances as weighted sums of squared deviations, not E[x^2] - mu^2.

The synthetic image pair (3 channels, exact binary fractions so C and Python
hold identical values):
    a(x, y, c) = ((37x + 91y + 53c + (x*y mod 13)) mod 64) / 64
    b(x, y, c) = a(x, y, c) + (((11x + 7y + 5c) mod 9) - 4) / 16
with y = 0 the top row.

    compare_ssim_reference.py [--peak P]           prints JSON: per-channel SSIM, mean
    compare_ssim_reference.py --write-pfm DIR      also writes DIR/a.pfm and DIR/b.pfm
"""
import json
import math
import os
import struct
import sys

WIDTH, HEIGHT, CHANNELS = 24, 20, 3


def a_val(x, y, c):
    return ((37 * x + 91 * y + 53 * c + (x * y) % 13) % 64) / 64.0


def b_val(x, y, c):
    return a_val(x, y, c) + (((11 * x + 7 * y + 5 * c) % 9) - 4) / 16.0


def gaussian_window(size=11, sigma=1.5):
    r = size // 2
    w = [[math.exp(-((i - r) ** 2 + (j - r) ** 2) / (2.0 * sigma * sigma))
          for i in range(size)] for j in range(size)]
    total = sum(sum(row) for row in w)
    return [[v / total for v in row] for row in w]


def ssim(img_a, img_b, width, height, peak=1.0):
    """img_a, img_b: [y][x] lists of floats. Mean SSIM over valid windows."""
    win = gaussian_window()
    size = len(win)
    c1 = (0.01 * peak) ** 2
    c2 = (0.03 * peak) ** 2
    values = []
    for oy in range(height - size + 1):
        for ox in range(width - size + 1):
            mu_a = sum(win[j][i] * img_a[oy + j][ox + i] for j in range(size) for i in range(size))
            mu_b = sum(win[j][i] * img_b[oy + j][ox + i] for j in range(size) for i in range(size))
            var_a = sum(win[j][i] * (img_a[oy + j][ox + i] - mu_a) ** 2
                        for j in range(size) for i in range(size))
            var_b = sum(win[j][i] * (img_b[oy + j][ox + i] - mu_b) ** 2
                        for j in range(size) for i in range(size))
            cov = sum(win[j][i] * (img_a[oy + j][ox + i] - mu_a) * (img_b[oy + j][ox + i] - mu_b)
                      for j in range(size) for i in range(size))
            values.append(((2 * mu_a * mu_b + c1) * (2 * cov + c2)) /
                          ((mu_a ** 2 + mu_b ** 2 + c1) * (var_a + var_b + c2)))
    return sum(values) / len(values)


def write_pfm(path, fn):
    """Colour PFM: little-endian (scale -1), rows stored bottom to top."""
    with open(path, 'wb') as f:
        f.write(b'PF\n%d %d\n-1.0\n' % (WIDTH, HEIGHT))
        for y in reversed(range(HEIGHT)):
            for x in range(WIDTH):
                f.write(struct.pack('<3f', *(fn(x, y, c) for c in range(CHANNELS))))


def main(argv):
    peak = 1.0
    outdir = None
    args = argv[1:]
    while args:
        if args[0] == '--peak' and len(args) > 1:
            peak = float(args[1])
            args = args[2:]
        elif args[0] == '--write-pfm' and len(args) > 1:
            outdir = args[1]
            args = args[2:]
        else:
            sys.stderr.write(__doc__)
            return 2
    per_channel = []
    for c in range(CHANNELS):
        img_a = [[a_val(x, y, c) for x in range(WIDTH)] for y in range(HEIGHT)]
        img_b = [[b_val(x, y, c) for x in range(WIDTH)] for y in range(HEIGHT)]
        per_channel.append(ssim(img_a, img_b, WIDTH, HEIGHT, peak))
    if outdir:
        os.makedirs(outdir, exist_ok=True)
        write_pfm(os.path.join(outdir, 'a.pfm'), a_val)
        write_pfm(os.path.join(outdir, 'b.pfm'), b_val)
    print(json.dumps({'width': WIDTH, 'height': HEIGHT, 'peak': peak,
                      'ssim': per_channel, 'mean': sum(per_channel) / CHANNELS}))
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
