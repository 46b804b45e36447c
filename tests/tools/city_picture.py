#!/usr/bin/env python3
"""city_picture.py: a district's TextureMaps drawn on its houses, side by side
(docs/scale-out.md, "A city").

    python3 tests/tools/city_picture.py BUILD CITY.obj OUT.png TEXTURE [TEXTURE ...]
            [--view "ex ey ez tx ty tz ux uy uz width height WxH"] [--white X]

Each TEXTURE is a UDIM set (city_texture.<UDIM>.exr, as tests/tools/city.py's
scenes write them), drawn on CITY.obj by BUILD/tools/render_texture (make
build/tools/render_texture) through the same orthographic view with the same
white point (the first texture's own, unless --white), and the pictures are
put side by side, 8 pixels apart. Pure Python otherwise (PNG decoding of
render_texture's 8-bit RGB output included)."""
import argparse
import os
import struct
import subprocess
import tempfile
import zlib


def read_png(path):
    """(width, height, rows of RGB bytes) of an 8-bit RGB, non-interlaced PNG."""
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    pos, idat, w, h = 8, b"", 0, 0
    while pos < len(data):
        n, tag = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if tag == b"IHDR":
            w, h, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert depth == 8 and colour == 2 and interlace == 0, path
        elif tag == b"IDAT":
            idat += body
        pos += 12 + n
    raw = zlib.decompress(idat)
    stride, rows, prev = 3 * w, [], bytearray(3 * w)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - 3] if i >= 3 else 0
            b = prev[i]
            c = prev[i - 3] if i >= 3 else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[i] = (line[i] + pred) & 255
        rows.append(bytes(line))
        prev = line
    return w, h, rows


def write_png(path, w, h, rows):
    raw = b"".join(b"\x00" + r for r in rows)

    def chunk(tag, body):
        return (struct.pack(">I", len(body)) + tag + body
                + struct.pack(">I", zlib.crc32(tag + body) & 0xFFFFFFFF))

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n"
                + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("build")
    ap.add_argument("obj")
    ap.add_argument("out")
    ap.add_argument("textures", nargs="+")
    ap.add_argument("--view", default="50 40 70 0 2 0 0 1 0 75 48 1500x960")
    ap.add_argument("--white", type=float, default=0.0)
    a = ap.parse_args()
    tool = os.path.join(a.build, "tools", "render_texture")
    pictures = []
    with tempfile.TemporaryDirectory() as tmp:
        for k, tex in enumerate(a.textures):
            png = os.path.join(tmp, "%d.png" % k)
            cmd = [tool, a.obj, tex, "--view", a.view, "--png", png]
            if a.white > 0:
                cmd += ["--white", "%g" % a.white]
            told = subprocess.run(cmd, check=True, stdout=subprocess.PIPE, text=True).stdout
            if a.white <= 0:
                a.white = float(told.split()[1])
            pictures.append(read_png(png))
    h = max(p[1] for p in pictures)
    gap = b"\xff" * (3 * 8)
    rows = []
    for y in range(h):
        parts = [p[2][y] if y < p[1] else b"\xff" * (3 * p[0]) for p in pictures]
        rows.append(gap.join(parts))
    w = sum(p[0] for p in pictures) + 8 * (len(pictures) - 1)
    write_png(a.out, w, h, rows)
    print("%s: %d x %d, %d pictures, white %g" % (a.out, w, h, len(pictures), a.white))


if __name__ == "__main__":
    main()
