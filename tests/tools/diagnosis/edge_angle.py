#!/usr/bin/python3
"""edge_angle.py BUILD DIR [ANGLE ...]: where a shelter edge lands, against the
angle at which it crosses the input cameras' texels.

The wall and overhang of tests/test_analytic.c's shelter tests (wall x -2..2,
y 0..3.2, z -0.3..0; overhang y 3..3.2 out to z = 1; rain along (0, -1, -1),
so the exact shadow edge on the wall is y = 2), turned ANGLE degrees about the
wall's normal around (0, 2, 0) with the rain, so that the edge runs at ANGLE
to the front camera's rows (turning about the vertical, as the shipped test
does, leaves it along them). The input cameras (front, top, right, 384 px over
6 m: 15.6 mm texels) stay; the output camera turns with the wall, so its rows
follow the edge. For each angle (default 0 30 45) it prints:

- the mask's 50% line (going down from the shelter, per column of two output
  pixels, averaged), its offset above y = 2 in input texels, its RMS along the
  edge and the 10-90% rise in output pixels, as the shipped test measures;
- the deposits' own edge: the front camera's `hits` over a band across the
  edge, divided by the exposed wall's, read as where a sharp edge would put
  that many hits (what the flight and the collider give, before the gather).

EDGE_LAYERS=K gives the three input cameras `layers="K"` (default: one layer).
Environment settings reach the runs, so a build of transplant.patch takes its
switches (WX_NOCLEAN=1, WX_EDGECOV=1, ...). Needs numpy (Debian's python3-numpy:
run it with /usr/bin/python3). docs/performance.md, "The gather's part lies on
the edges".
"""
import math
import os
import subprocess
import sys

import numpy as np

TEXEL = 6.0 / 384  # input texel, m
BOX = [[[-2, 0, -0.3], [2, 3.2, 0]], [[-2, 3, 0], [2, 3.2, 1]]]
FACES = [(5, 6, 7), (5, 7, 8), (2, 1, 4), (2, 4, 3), (1, 5, 8), (1, 8, 4), (6, 2, 3), (6, 3, 7),
         (8, 7, 3), (8, 3, 4), (1, 2, 6), (1, 6, 5)]


def write_scene(d, angle):
    c, s = math.cos(math.radians(angle)), math.sin(math.radians(angle))
    lines = []
    for b in range(2):
        for v in range(8):
            x = BOX[b][1 if v % 4 in (1, 2) else 0][0]
            y = BOX[b][1 if v % 4 >= 2 else 0][1] - 2.0
            z = BOX[b][1 if v >= 4 else 0][2]
            lines.append("v %.7f %.7f %.7f" % (c * x - s * y, 2.0 + s * x + c * y, z))
        lines += ["f %d %d %d" % tuple(k + 8 * b for k in f) for f in FACES]
    with open(os.path.join(d, "wall.obj"), "w") as f:
        f.write("\n".join(lines) + "\n")
    # The rain (0, -1, -1) turned with the wall, scaled to dirY = -1; the
    # emitter square over where it comes from, its rate scaled with its area.
    dx, dz = s / c, -1.0 / c
    cx, cz, half = -4.0 * dx, 4.0826, 2.732051 / c + 0.6
    rate = 3732050 * (2 * half) ** 2 / (2 * 2.732051) ** 2
    layers = os.environ.get("EDGE_LAYERS", "")
    layers = f' layers="{int(layers)}"' if layers else ""
    with open(os.path.join(d, "edge.xml"), "w") as f:
        f.write(f"""<Weathering>
  <Solver>
    <BoundingBox size="20" centerX="0" centerY="2" centerZ="0"/>
    <Simulation timeStep="0.02" steps="120" seed="3"/>
  </Solver>
  <Emitters>
    <BoxEmitter minX="{cx - half}" minY="6" minZ="{cz - half}" maxX="{cx + half}" maxY="6"
                maxZ="{cz + half}" dirX="{dx}" dirY="-1" dirZ="{dz}" rate="{rate:.0f}" end="1"
                speed="10"/>
  </Emitters>
  <Collider>
    <ProjectedMaps>
      <Ortho cameraName="front"{layers}><View eye="0 1.6 10" target="0 1.6 0" up="0 1 0" width="6" height="6" resolution="384"/></Ortho>
      <Ortho cameraName="top"{layers}><View eye="0 10 0.5" target="0 0 0.5" up="0 0 -1" width="6" height="6" resolution="384"/></Ortho>
      <Ortho cameraName="right"{layers}><View eye="10 1.6 0" target="0 1.6 0" up="0 1 0" width="6" height="6" resolution="384"/></Ortho>
      <Ortho cameraName="shot" out="true">
        <View eye="{0.4 * s} {2 - 0.4 * c} 10" target="{0.4 * s} {2 - 0.4 * c} 0" up="{-s} {c} 0"
              width="4" height="4" resolution="512"/>
        <OutputMap file="mask.exr"/>
      </Ortho>
    </ProjectedMaps>
  </Collider>
  <Geometry><Mesh file="wall.obj"><Surface material="*" absorption="1"/></Mesh></Geometry>
</Weathering>
""")


def channel(build, exr, name, shape):
    out = exr + "." + name + ".f32"
    subprocess.run([os.path.join(build, "tools", "exr_channel"), exr, name, out], check=True,
                   stdout=subprocess.DEVNULL)
    return np.nan_to_num(np.fromfile(out, dtype=np.float32).reshape(shape).astype(float))


def crossing(p, level, j0, j1):
    for j in range(j0, j1):
        if p[j] >= level:
            return j - 1 + (level - p[j - 1]) / (p[j] - p[j - 1])
    return float("nan")


def measure(build, d, angle):
    os.makedirs(d, exist_ok=True)
    write_scene(d, angle)
    subprocess.run([os.path.join(build, "weathering"), "run", "edge.xml", "--out", "out", "-q"],
                   cwd=d, check=True)
    # The mask: output pixel (i, j) at x = -2 + 4 (i + 0.5) / 512, y = 3.6 - 4 (j + 0.5) / 512
    # in the wall's own frame.
    m = channel(build, os.path.join(d, "out", "mask.exr"), "Y", (512, 512))
    xs = -2 + 4 * (np.arange(512) + 0.5) / 512
    ys = 3.6 - 4 * (np.arange(512) + 0.5) / 512
    exposed = m[(ys > 0.3) & (ys < 1.7)][:, np.abs(xs) < 1.5].mean()
    j0, j1 = int((3.6 - 2.6) * 512 / 4), int((3.6 - 1.4) * 512 / 4)
    lines, rises = [], []
    for i0 in range(0, 512, 2):
        if abs(-2 + 4 * (i0 + 1) / 512) > 1.5:
            continue
        p = m[:, i0:i0 + 2].mean(axis=1) / exposed
        lines.append(3.6 - 4 * (crossing(p, 0.5, j0, j1) + 0.5) / 512)
        rises.append(crossing(p, 0.9, j0, j1) - crossing(p, 0.1, j0, j1))
    lines = np.array(lines)
    # The deposits: the front camera's hits at its texel centres, in the wall's frame.
    h = channel(build, os.path.join(d, "out", "front_dirt.exr"), "hits", (384, 384))
    c, s = math.cos(math.radians(angle)), math.sin(math.radians(angle))
    k = np.arange(384)
    X, Y = np.meshgrid(-3 + 6 * (k + 0.5) / 384, 1.6 + 3 - 6 * (k + 0.5) / 384)
    xw, yw = c * X + s * (Y - 2), 2 + (-s * X + c * (Y - 2))
    along = np.abs(xw) < 1.4
    lit = h[along & (yw > 1.4) & (yw < 1.8)].mean()
    band = along & (yw > 1.8) & (yw < 2.3)
    deposits = h[band].mean() / lit * 0.5 - 0.2  # m above y = 2
    print(f"angle {angle:4.1f}: mask's 50% line {(lines.mean() - 2) / TEXEL:+.2f} input texels "
          f"(RMS along it {lines.std() / TEXEL:.3f}), rise {np.mean(rises):.1f} pixels; "
          f"deposits' edge {deposits / TEXEL:+.2f} input texels")


def main():
    if len(sys.argv) < 3:
        sys.exit("usage: edge_angle.py BUILD DIR [ANGLE ...]")
    build, d = os.path.abspath(sys.argv[1]), sys.argv[2]
    for a in [float(x) for x in sys.argv[3:]] or [0.0, 30.0, 45.0]:
        measure(build, os.path.join(d, "a%g" % a), a)


if __name__ == "__main__":
    main()
