#!/usr/bin/env python3
"""surface_probe.py OUT.txt [OTHER.txt]: tests/tools/surface_probe.c's points by band.

Bands of 10 degrees of the surface normal's angle from +Y (0: facing up;
on a sphere, its colatitude). Per band: the points, the collider's distance
from the smooth surface along the normal (mean and RMS, in texels), the
notches (more than a quarter of a texel inside), and which cameras call a
point a fifth of a texel inside free there (bit c: input camera c, in the
scene's order), the commonest masks first.

With OTHER.txt (the same mesh turned about the vertical, run and probed
alike: its points come in the same order), also the RMS of the difference
between the two distances point by point: the part of the collision
surface that turns with the model in the camera grid.

Needs numpy (Debian's python3-numpy).
"""
import collections
import sys

import numpy as np


def load(path):
    a = np.loadtxt(path)
    if a.ndim != 2 or a.shape[1] != 9:
        sys.exit(f"{path}: not surface_probe's output (9 numbers a line)")
    return a


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    a = load(sys.argv[1])
    b = load(sys.argv[2]) if len(sys.argv) == 3 else None
    if b is not None and len(b) != len(a):
        sys.exit("the two files hold different points (not the same mesh?)")
    up = np.degrees(np.arccos(np.clip(a[:, 4], -1.0, 1.0)))
    dist, vetoes = a[:, 6], a[:, 8].astype(int)
    print("normal   points   mean     RMS   notches  vetoing cameras" +
          ("   turned-this RMS" if b is not None else ""))
    for lo in range(0, 180, 10):
        m = (up >= lo) & (up < lo + 10) & np.isfinite(dist)
        if not m.any():
            continue
        d = dist[m]
        notch = m & (dist < -0.25)
        masks = collections.Counter(vetoes[notch]).most_common(3)
        line = (f"{lo:3d}-{lo + 10:3d} {m.sum():8d} {d.mean():+.4f} {np.sqrt((d * d).mean()):.4f}"
                f" {notch.sum():8d}  " + ", ".join(f"{k:#x}: {n}" for k, n in masks))
        if b is not None:
            diff = b[m, 6] - d
            diff = diff[np.isfinite(diff)]
            line += f"   {np.sqrt((diff * diff).mean()):.4f}"
        print(line)


if __name__ == "__main__":
    main()
