#!/usr/bin/env python3
"""old_house_seasons.py BUILD RUN_DIR OUT.png: the picture of xml_scenes/
old_house.xml in the README: its mask after seasons 4, 8, 12 and 20 side by
side at half size, painted as a person sees it: paint darkened by the stains,
bare plaster where it peeled, dark cracks, orange rust, over the sky where the
output camera sees no surface. Reads the frames with BUILD/tools/exr_channel
(make build/tools/exr_channel); pure Python otherwise."""
import os
import struct
import subprocess
import sys
import tempfile
import zlib


def channel(tool, exr, name, tmp):
    path = os.path.join(tmp, "c.f32")
    subprocess.run([tool, exr, name, path], check=True, stdout=subprocess.DEVNULL)
    data = open(path, "rb").read()
    return struct.unpack("%df" % (len(data) // 4), data)


def main():
    build, run, out = sys.argv[1:4]
    tool = os.path.join(build, "tools", "exr_channel")
    frames = ["0004", "0008", "0012", "0020"]
    with tempfile.TemporaryDirectory() as tmp:
        depth = channel(tool, os.path.join(run, "out_depth.exr"), "R|Z|depth", tmp)
        size = int(round(len(depth) ** 0.5))
        half = size // 2
        out_w = len(frames) * half + (len(frames) - 1) * 4
        rows = [[(255, 255, 255)] * out_w for _ in range(half)]
        for k, f in enumerate(frames):
            exr = os.path.join(run, "mask.%s.exr" % f)
            rust, crack, peel, stains = (channel(tool, exr, c + ".Y", tmp)
                                         for c in ("rust", "crack", "peel", "stains"))
            for y in range(half):
                for x in range(half):
                    i = 2 * y * size + 2 * x
                    if not depth[i] < 1e30:
                        col = (200, 214, 232)
                    else:
                        s = min(1.0, max(0.0, stains[i])) * 0.35
                        col = [c * (1 - s) + 120 * s for c in (205, 196, 178)]
                        if peel[i] > 0:
                            col = (150, 140, 128)
                        if crack[i] > 0:
                            col = (40, 36, 32)
                        if rust[i] > 0:
                            col = (170, 80, 30)
                        col = tuple(int(max(0, min(255, c))) for c in col)
                    rows[y][k * (half + 4) + x] = col
    raw = b"".join(b"\x00" + bytes(v for px in row for v in px) for row in rows)

    def chunk(tag, data):
        return (struct.pack(">I", len(data)) + tag + data
                + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF))

    png = (b"\x89PNG\r\n\x1a\n"
           + chunk(b"IHDR", struct.pack(">IIBBBBB", out_w, half, 8, 2, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))
    with open(out, "wb") as f:
        f.write(png)


if __name__ == "__main__":
    main()
