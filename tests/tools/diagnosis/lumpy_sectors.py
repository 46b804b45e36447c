#!/usr/bin/env python3
"""lumpy_sectors.py FILE.f32...: the lumpy sphere's three lumps, one run.

tests/tools/lumpy_sphere.sh's sphere is the same in each third of a turn
(its lumps go as sin 3 theta and its 24 segments are 3 x 8), and its
equirectangular layout puts each third in a third of the texture's columns.
In one run its lumps lie at three angles to the cameras' axes (the axes
repeat every 90 degrees, the lumps every 120), so how far the thirds differ
beyond their noise is what the camera grid does to the rain, measured without
turning the model (issue 25 item 1; docs/performance.md, "Four more variants
and two measurements for item 1").

Each argument is the `Y` channel of one seed's TextureMap (1024 x 1024 floats,
build/tools/exr_channel FILE.exr Y OUT.f32). The texture is binned in cells of
5 x 5 degrees (colatitude x longitude), averaged over the seeds; per band of
10 degrees of colatitude it prints the band's mean, the RMS over the band's
cells of each third's deviation from the mean of the three (over the band's
mean), and the same figure's noise: the RMS over the seeds of each seed's
deviation from the seeds' mean, divided by sqrt(seeds).
"""
import array
import math
import sys

W = 1024
ROWS, COLS = 36, 72  # cells of 5 x 5 degrees


def binned(path):
    a = array.array("f")
    with open(path, "rb") as f:
        a.frombytes(f.read())
    total = [[0.0] * COLS for _ in range(ROWS)]
    count = [[0] * COLS for _ in range(ROWS)]
    for y in range(W):
        r = min(ROWS - 1, int((y + 0.5) / W * ROWS))
        row_t, row_c = total[r], count[r]
        for x in range(W):
            c = min(COLS - 1, int((x + 0.5) / W * COLS))
            row_t[c] += a[y * W + x]
            row_c[c] += 1
    return [[total[r][c] / count[r][c] for c in range(COLS)] for r in range(ROWS)]


def thirds(cells, r):
    third = COLS // 3
    return [[cells[r][k * third + c] for c in range(third)] for k in range(3)]


def deviation(cells, rows):
    """RMS over the rows' cells of each third minus the thirds' mean."""
    s, n = 0.0, 0
    for r in rows:
        t = thirds(cells, r)
        for c in range(len(t[0])):
            m = (t[0][c] + t[1][c] + t[2][c]) / 3.0
            for k in range(3):
                s += (t[k][c] - m) ** 2
                n += 1
    return math.sqrt(s / n)


def main():
    seeds = [binned(p) for p in sys.argv[1:]]
    n = len(seeds)
    mean = [[sum(s[r][c] for s in seeds) / n for c in range(COLS)] for r in range(ROWS)]
    # Each seed's deviation from the seeds' mean, for the noise below.
    resid = [[[s[r][c] - mean[r][c] for c in range(COLS)] for r in range(ROWS)] for s in seeds]
    print("colatitude   mean       thirds   noise")
    for band in range(0, ROWS, 2):
        rows = (band, band + 1)
        m = sum(mean[r][c] for r in rows for c in range(COLS)) / (2 * COLS)
        if m <= 0.0:
            continue
        dev = deviation(mean, rows)
        # The noise of that figure: each seed's own thirds' deviation about the
        # seeds' mean, over sqrt(seeds).
        noise = math.sqrt(sum(deviation(x, rows) ** 2 for x in resid) / n / max(1, n - 1))
        print("%3d-%3d  %10.1f   %.4f   %.4f" % (band * 5, band * 5 + 10, m, dev / m, noise / m))


if __name__ == "__main__":
    main()
