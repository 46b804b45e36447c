#!/usr/bin/env python3
"""common_part.py A1 B1 A2 B2 CHANNEL: the part two differences share.

Each argument is a TextureMap EXR's channel extracted with build/tools/exr_channel
(NAME.CHANNEL.f32 and NAME.seen.f32, 1024 x 1024). D1 = A1 - B1 and D2 = A2 - B2
are differences made with independent seeds (A1, B1 seed 1; A2, B2 seed 2), so
what they share is what does not depend on the seed: sqrt(mean(D1 * D2)) over
the texels all four see, averaged in blocks of 1, 4 and 16 texels, over the
mean of B1. Printed with each difference's own RMS (docs/performance.md,
"What turns with the model: the flight or the gather").
"""
import array
import sys

W = 1024


def read(path):
    a = array.array("f")
    with open(path, "rb") as f:
        a.frombytes(f.read())
    return a


def main():
    names, ch = sys.argv[1:5], sys.argv[5]
    values = [read(n + "." + ch + ".f32") for n in names]
    seen = [read(n + ".seen.f32") for n in names]
    ok = [all(s[i] > 0 for s in seen) for i in range(W * W)]
    mean = sum(values[1][i] for i in range(W * W) if ok[i]) / max(1, sum(ok))
    for b in (1, 4, 16):
        n = 0
        s11 = s22 = s12 = 0.0
        for by in range(W // b):
            for bx in range(W // b):
                acc = [0.0] * 4
                k = 0
                for y in range(by * b, by * b + b):
                    for x in range(bx * b, bx * b + b):
                        i = y * W + x
                        if ok[i]:
                            k += 1
                            for q in range(4):
                                acc[q] += values[q][i]
                if k >= max(1, b * b // 2):
                    d1 = (acc[0] - acc[1]) / k / mean
                    d2 = (acc[2] - acc[3]) / k / mean
                    s11 += d1 * d1
                    s22 += d2 * d2
                    s12 += d1 * d2
                    n += 1
        c = s12 / n
        common = "%.4f" % c ** 0.5 if c >= 0 else "-%.4f" % (-c) ** 0.5
        print("block %2d: difference 1 %.4f  difference 2 %.4f  common %s"
              % (b, (s11 / n) ** 0.5, (s22 / n) ** 0.5, common))


if __name__ == "__main__":
    main()
