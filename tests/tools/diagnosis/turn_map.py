#!/usr/bin/python3
"""turn_map.py BUILD DIR SEEDS [CHANNEL] [--mesh MODEL.obj]: where on the model the turn lives.

DIR is the folder tests/tools/invariance.sh left (BUILD/invariance/, with
SEEDS=N runs model1..N and turned1..N; N >= 2, and the more the quieter).
For seeds i != j the differences D_i = model_i - turned_i and D_j share
only what does not depend on the seed, so mean(D_i D_j) over the pairs
estimates, texel by texel, the square of what turning the model changes
(T^2; tests/tools/diagnosis/common_part.py takes the same product over the
whole texture). The same product of the seeds'
differences, (model_i - model_j)(turned_i - turned_j), has no such part: its
map shows what the estimate's own noise looks like.

Prints T^2 and that null over the texels every run sees, as a ratio the
issue reads (sqrt(1 + T^2 / S^2), S^2 the seeds' mean square difference), and
their shares by the texel's distance (in texels, 8-neighbour steps) to the
edge of what is seen: island borders and what no camera sees; then how few
blocks of 32 x 32 texels hold half of T^2, and the eight that hold the most,
each by the UV of its texel with the most (with --mesh, the model's point
there: DIR/model.obj is the model unturned). Writes, in DIR,
turn_map.exr and turn_null.exr: `Y` the two products averaged over 9 x 9
texels, over the mean squared (negative values as 0), `seen` as the runs'.
Look at them on the model with build/tools/render_texture (`--white 0.01`):

    build/tools/render_texture MESH DIR/turn_map.exr --view "..." --png map.png

Needs numpy (python3-numpy; run it with /usr/bin/python3) and
BUILD/tools/exr_channel. docs/performance.md, "Which pairs the turn is read
from", shows Spot's: speckle like the null's, plus lines along the neck, the
eyes and the roots of the ears; "Where Spot's turn sits" (fourteenth
session) finds half of it in 16 blocks, at the roots of the horns and ears.
"""
import itertools
import os
import struct
import subprocess
import sys
import tempfile

import numpy as np


def read(tool, path, channel, scratch):
    out = os.path.join(scratch, "c.f32")
    r = subprocess.run([tool, path, channel, out], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit("turn_map.py: " + (r.stderr.strip() or "%s: cannot read %s" % (path, channel)))
    w, h = (int(x) for x in r.stdout.split())
    return np.fromfile(out, dtype=np.float32).reshape(h, w).astype(np.float64)


def write_exr(path, channels):
    """An uncompressed scanline EXR of FLOAT channels (name -> H x W array)."""

    def attr(name, kind, data):
        return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(data)) + data

    names = sorted(channels)
    h, w = channels[names[0]].shape
    chlist = b"".join(n.encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for n in names)
    box = struct.pack("<4i", 0, 0, w - 1, h - 1)
    header = (b"\x76\x2f\x31\x01" + struct.pack("<i", 2)
              + attr("channels", "chlist", chlist + b"\0")
              + attr("compression", "compression", b"\0")
              + attr("dataWindow", "box2i", box) + attr("displayWindow", "box2i", box)
              + attr("lineOrder", "lineOrder", b"\0")
              + attr("pixelAspectRatio", "float", struct.pack("<f", 1.0))
              + attr("screenWindowCenter", "v2f", struct.pack("<2f", 0.0, 0.0))
              + attr("screenWindowWidth", "float", struct.pack("<f", 1.0)) + b"\0")
    blocks, offsets, at = [], [], len(header) + 8 * h
    for y in range(h):
        data = b"".join(channels[n][y].astype("<f4").tobytes() for n in names)
        offsets.append(at)
        blocks.append(struct.pack("<ii", y, len(data)) + data)
        at += len(blocks[-1])
    with open(path, "wb") as f:
        f.write(header + struct.pack("<%dQ" % h, *offsets) + b"".join(blocks))


def box_mean(a, k=9):
    p = np.pad(a, k // 2, mode="edge")
    c = np.pad(p.cumsum(0).cumsum(1), ((1, 0), (1, 0)))
    return (c[k:, k:] - c[:-k, k:] - c[k:, :-k] + c[:-k, :-k]) / (k * k)


def distance_to_edge(seen):
    dist = np.zeros(seen.shape, int)
    cur, r = seen.copy(), 0
    while cur.any() and r < 64:
        r += 1
        inner = cur.copy()
        inner[1:] &= cur[:-1]
        inner[:-1] &= cur[1:]
        inner[:, 1:] &= cur[:, :-1]
        inner[:, :-1] &= cur[:, 1:]
        dist[cur & ~inner] = r
        cur = inner
    dist[cur] = r + 1
    return dist


def load_obj(path):
    """An OBJ's positions, UVs and triangles (fans of its faces; faces whose
    corners lack a UV are left out) as arrays: V, T and F[triangle, corner] =
    (position index, UV index)."""
    vs, vts, faces = [], [], []

    def index(text, count):
        i = int(text)
        return i - 1 if i > 0 else count + i  # OBJ's negative indices count back

    with open(path) as f:
        for line in f:
            p = line.split()
            if not p:
                continue
            if p[0] == "v":
                vs.append([float(x) for x in p[1:4]])
            elif p[0] == "vt":
                vts.append([float(x) for x in p[1:3]])
            elif p[0] == "f":
                corners = [(c.split("/") + [""])[:2] for c in p[1:]]
                if not all(t[1] for t in corners):
                    continue
                corners = [(index(t[0], len(vs)), index(t[1], len(vts))) for t in corners]
                for k in range(1, len(corners) - 1):
                    faces.append([corners[0], corners[k], corners[k + 1]])
    return np.array(vs), np.array(vts), np.array(faces, dtype=np.int64).reshape(-1, 3, 2)


def obj_point(mesh, u, v):
    """The point of the mesh at texture UV (u, v) in [0, 1): the first
    triangle that holds it, its UVs read as the texture reads them (REPEAT:
    each triangle moved by whole tiles so that its lowest corner lies in the
    first tile, then asked at (u, v) and one tile further along each axis).
    None where no triangle holds it (padding)."""
    V, T, F = mesh
    if len(F) == 0:
        return None
    uv = T[F[:, :, 1]]  # triangle, corner, (u, v)
    uv = uv - np.floor(uv.min(axis=1, keepdims=True))
    a, b, c = uv[:, 0], uv[:, 1], uv[:, 2]
    d = (b[:, 1] - c[:, 1]) * (a[:, 0] - c[:, 0]) + (c[:, 0] - b[:, 0]) * (a[:, 1] - c[:, 1])
    for du, dv in ((0, 0), (1, 0), (0, 1), (1, 1)):
        x, y = u + du, v + dv
        with np.errstate(divide="ignore", invalid="ignore"):
            l1 = ((b[:, 1] - c[:, 1]) * (x - c[:, 0]) + (c[:, 0] - b[:, 0]) * (y - c[:, 1])) / d
            l2 = ((c[:, 1] - a[:, 1]) * (x - c[:, 0]) + (a[:, 0] - c[:, 0]) * (y - c[:, 1])) / d
        l3 = 1.0 - l1 - l2
        inside = np.flatnonzero((l1 >= -1e-6) & (l2 >= -1e-6) & (l3 >= -1e-6))
        if inside.size:
            k = inside[0]
            return l1[k] * V[F[k, 0, 0]] + l2[k] * V[F[k, 1, 0]] + l3[k] * V[F[k, 2, 0]]
    return None


def main():
    args = sys.argv[1:]
    mesh = None
    if len(args) >= 2 and args[-2] == "--mesh":
        mesh, args = args[-1], args[:-2]
    if (len(args) not in (3, 4) or not args[2].isdigit() or int(args[2]) < 2
            or "--mesh" in args):
        print("usage: turn_map.py BUILD DIR SEEDS [CHANNEL] [--mesh MODEL.obj]  (SEEDS >= 2)",
              file=sys.stderr)
        sys.exit(2)
    if mesh is not None and not os.path.isfile(mesh):
        sys.exit("turn_map.py: %s: no such file" % mesh)
    build, d, n = args[0], args[1], int(args[2])
    channel = args[3] if len(args) == 4 else "Y"
    tool = os.path.join(build, "tools", "exr_channel")
    with tempfile.TemporaryDirectory() as scratch:
        tex = lambda m, s: os.path.join(d, "%s%d" % (m, s), "%s_texture.exr" % m)
        model = [read(tool, tex("model", s), channel, scratch) for s in range(1, n + 1)]
        turned = [read(tool, tex("turned", s), channel, scratch) for s in range(1, n + 1)]
        seen = np.ones(model[0].shape, bool)
        for s in range(1, n + 1):
            seen &= read(tool, tex("model", s), "seen", scratch) > 0
            seen &= read(tool, tex("turned", s), "seen", scratch) > 0
    mean = np.mean([a[seen].mean() for a in model + turned])
    pairs = list(itertools.combinations(range(n), 2))
    turn = np.mean([(model[i] - turned[i]) * (model[j] - turned[j]) for i, j in pairs], axis=0)
    null = np.mean([(model[i] - model[j]) * (turned[i] - turned[j]) for i, j in pairs], axis=0)
    seeds = np.mean([(a[i] - a[j]) ** 2 for a in (model, turned) for i, j in pairs], axis=0)
    turn, null, seeds = turn / mean ** 2, null / mean ** 2, seeds / mean ** 2
    t2, n2, s2 = turn[seen].mean(), null[seen].mean(), seeds[seen].mean()
    print("per texel over %d seen texels: T^2 %.3g (null %+.3g), seeds' S^2 %.3g: ratio %.3f"
          % (seen.sum(), t2, n2, s2, np.sqrt(1.0 + t2 / s2)))
    dist = distance_to_edge(seen)
    print("texels from the edge of what is seen: share of texels, of T^2, of the null, of S^2")
    for lo, hi in ((1, 2), (3, 4), (5, 8), (9, 16), (17, 1 << 30)):
        sel = seen & (dist >= lo) & (dist <= hi)
        if sel.any():
            print("  %2d-%-3s %.3f  T^2 %+.3f  null %+.3f  S^2 %.3f" % (
                lo, str(hi) if hi < 1 << 30 else "", sel.sum() / seen.sum(),
                turn[sel].sum() / turn[seen].sum(), null[sel].sum() / turn[seen].sum(),
                seeds[sel].sum() / seeds[seen].sum()))
    # Hot spots: blocks of 32 x 32 texels by their share of T^2.
    b = 32
    h, w = seen.shape
    hb, wb = (h + b - 1) // b, (w + b - 1) // b

    def block_sums(a):
        padded = np.zeros((hb * b, wb * b))
        padded[:h, :w] = a
        return padded.reshape(hb, b, wb, b).sum(axis=(1, 3))

    blocks = block_sums(np.where(seen, turn, 0.0))
    total = turn[seen].sum()
    order = np.argsort(blocks.ravel())[::-1]
    share = np.cumsum(blocks.ravel()[order]) / total
    used = int(np.count_nonzero(block_sums(seen)))
    half = int(np.searchsorted(share, 0.5)) + 1
    print("blocks of %d x %d texels: %d of the %d with a seen texel hold half of T^2;"
          " the largest eight (share of T^2, UV of the block's texel with the most%s):"
          % (b, b, half, used, ", the point there" if mesh else ""))
    smooth_turn = np.where(seen, box_mean(np.where(seen, turn, 0.0), 5), -np.inf)
    obj = load_obj(mesh) if mesh else None
    for k in order[:8]:
        by, bx = divmod(int(k), wb)
        part = smooth_turn[by * b:(by + 1) * b, bx * b:(bx + 1) * b]
        ty, tx = np.unravel_index(int(np.argmax(part)), part.shape)
        u, v = (bx * b + tx + 0.5) / w, 1.0 - (by * b + ty + 0.5) / h
        where = ""
        if obj is not None:
            point = obj_point(obj, u, v)
            where = ("  (no triangle there: padding)" if point is None
                     else "  at (%.3f, %.3f, %.3f)" % tuple(point))
        print("  %+.3f  u %.3f v %.3f%s" % (blocks.ravel()[k] / total, u, v, where))
    weight = np.maximum(box_mean(seen.astype(float)), 1e-6)
    for name, a in (("turn_map.exr", turn), ("turn_null.exr", null)):
        smooth = np.where(seen, np.maximum(box_mean(np.where(seen, a, 0.0)) / weight, 0.0), 0.0)
        write_exr(os.path.join(d, name),
                  {"Y": smooth.astype(np.float32), "seen": seen.astype(np.float32)})
    print("wrote %s and %s" % (os.path.join(d, "turn_map.exr"), os.path.join(d, "turn_null.exr")))


if __name__ == "__main__":
    main()
