#!/usr/bin/env python3
"""city.py: a city of N copies of the default house for weathering's scale-out
measurements and tests (docs/tiles.md).

    python3 tests/tools/city.py N --out DIR [--spacing 16] [--drops 75000]
                                [--texel 0.015625] [--map-width 0] [--texture 256]

writes DIR/city.obj (N houses on a square grid, `spacing` metres apart, each
with its UVs in its own UDIM tile 1001 + k, so the TextureMap writes one file a
house), DIR/building.mtl, and DIR/city.xml: rain from a box over the whole
city as the shipped house's (the same drops per square metre: `drops` a
house), front, back and top cameras over the city (4 layers on the sides), a
top output camera and the UDIM TextureMap. The maps' texel is `texel` metres
(the house's own 1.56 cm by default) unless `map-width` fixes the width of the
largest map in texels.
"""
import argparse
import math
import os
import shutil

HERE = os.path.dirname(os.path.abspath(__file__))
MESHES = os.path.join(HERE, "..", "..", "xml_scenes", "meshes")


def read_house():
    vs, vts, vns, body = [], [], [], []
    with open(os.path.join(MESHES, "building.obj")) as f:
        for line in f:
            if line.startswith("v "):
                vs.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("vt "):
                vts.append([float(x) for x in line.split()[1:3]])
            elif line.startswith("vn "):
                vns.append(line)
            elif line.startswith("f ") or line.startswith("usemtl"):
                body.append(line)
    return vs, vts, vns, body


def shift_face(line, dv, dvt, dvn):
    out = ["f"]
    for corner in line.split()[1:]:
        parts = corner.split("/")
        idx = [dv, dvt, dvn]
        out.append("/".join(str(int(p) + idx[k]) if p else "" for k, p in enumerate(parts)))
    return " ".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("n", type=int)
    ap.add_argument("--out", required=True)
    ap.add_argument("--spacing", type=float, default=16.0)
    ap.add_argument("--drops", type=int, default=75000, help="drops per house")
    ap.add_argument("--texel", type=float, default=1.0 / 64.0)
    ap.add_argument("--map-width", type=int, default=0)
    ap.add_argument("--texture", type=int, default=256, help="texels of each house's UDIM tile")
    a = ap.parse_args()
    if not 1 <= a.n <= 1000:
        raise SystemExit("city.py: N from 1 to 1000 (one UDIM tile a house)")
    os.makedirs(a.out, exist_ok=True)
    shutil.copy(os.path.join(MESHES, "building.mtl"), os.path.join(a.out, "building.mtl"))
    vs, vts, vns, body = read_house()
    cols = math.ceil(math.sqrt(a.n))
    rows = math.ceil(a.n / cols)
    with open(os.path.join(a.out, "city.obj"), "w") as f:
        f.write("# city.py: %d copies of the default house, %g m apart\nmtllib building.mtl\n"
                % (a.n, a.spacing))
        for k in range(a.n):
            cx = (k % cols - (cols - 1) / 2) * a.spacing
            cz = (k // cols - (rows - 1) / 2) * a.spacing
            for v in vs:
                f.write("v %.4f %.4f %.4f\n" % (v[0] + cx, v[1], v[2] + cz))
            for t in vts:
                f.write("vt %.7f %.7f\n" % (t[0] + k % 10, t[1] + k // 10))
            for n in vns:
                f.write(n)
            for line in body:
                f.write(shift_face(line, k * len(vs), k * len(vts), k * len(vns))
                        if line.startswith("f ") else line)
    # Extents: the houses' ground slabs span 14 m, roofs 12.25 m high.
    wx = (cols - 1) * a.spacing + 14.0
    wz = (rows - 1) * a.spacing + 14.0
    size = max(wx, wz) + 20.0
    texel = a.texel if a.map_width <= 0 else max(wx, wz, 16.0) / a.map_width

    def px(w):
        return max(16, int(round(w / texel)))

    h = 16.0
    drops = a.drops * a.n
    out_w = min(2048, px(wx + 2))
    out_h = out_w * px(wz + 2) // px(wx + 2)
    # The shipped house's rain box is 14 x 13 m over one house; here it
    # covers the city with the same margins.
    x0, x1 = -wx / 2, wx / 2
    z0, z1 = -wz / 2 + 3.0, wz / 2 + 2.0
    scene = f"""<?xml version="1.0" encoding="UTF-8"?>
<!-- city.py: {a.n} houses ({cols} x {rows}, {a.spacing} m apart), {a.drops} drops a house,
     maps at {texel:.4f} m a texel. -->
<Weathering name="city{a.n}">
  <Solver>
    <BoundingBox size="{size:.1f}" centerX="0" centerY="10" centerZ="0"/>
    <Simulation timeStep="0.01" steps="600" seed="1"/>
  </Solver>
  <ForceFields>
    <Gravity acceleration="9.8"/>
    <Wind strength="2" dirX="0" dirY="0" dirZ="-1"/>
    <Turbulence strength="0.5" frequency="0.3" octaves="3"/>
  </ForceFields>
  <Emitters>
    <BoxEmitter name="rain" minX="{x0:.2f}" minY="20" minZ="{z0:.2f}" maxX="{x1:.2f}" maxY="20" maxZ="{z1:.2f}"
                dirX="0" dirY="-1" dirZ="-0.35" spread="5"
                rate="{drops / 4.0:.1f}" start="0" end="4" speed="8" mass="1" dirt="0.05"
                maxCollisions="150"/>
  </Emitters>
  <Collider resilience="0.2" friction="0.97" adherence="2" deposit="1" erosion="1">
    <ProjectedMaps>
      <Ortho cameraName="front" layers="4">
        <View eye="0 6 {size / 2:.1f}" target="0 6 0" up="0 1 0" width="{wx + 2:.2f}" height="{h}" resolution="{px(wx + 2)} {px(h)}"/>
      </Ortho>
      <Ortho cameraName="back" layers="4">
        <View eye="0 6 {-size / 2:.1f}" target="0 6 0" up="0 1 0" width="{wx + 2:.2f}" height="{h}" resolution="{px(wx + 2)} {px(h)}"/>
      </Ortho>
      <Ortho cameraName="top">
        <View eye="0 30 0" target="0 0 0" up="0 0 -1" width="{wx + 2:.2f}" height="{wz + 2:.2f}" resolution="{px(wx + 2)} {px(wz + 2)}"/>
      </Ortho>
      <Ortho cameraName="out" out="true">
        <View eye="0 30 0" target="0 0 0" up="0 0 -1" width="{wx + 2:.2f}" height="{wz + 2:.2f}" resolution="{out_w} {out_h}"/>
        <OutputMap file="city_mask.exr" width="{out_w}" height="{out_h}"/>
      </Ortho>
    </ProjectedMaps>
  </Collider>
  <Geometry>
    <Mesh file="city.obj">
      <Surface material="wall" absorption="0.0" bounce="0.1" dirt="0" deposit="0.03" erosion="0.02"/>
      <Surface material="sill" absorption="0.0" bounce="0.1" dirt="2000" deposit="0.2" erosion="0.6"/>
      <Surface material="glass" absorption="0.0" bounce="0.05" dirt="0" deposit="0.1" erosion="0.3"/>
      <Surface material="roof" absorption="0.1" bounce="0.2" dirt="0" deposit="0.2" erosion="0.2"/>
      <Surface material="*" absorption="0.5" bounce="0.2" dirt="0" deposit="0.5" erosion="0.1"/>
      <TextureMap file="city_texture.exr" resolution="{a.texture}" padding="4" tiles="udim"/>
    </Mesh>
  </Geometry>
</Weathering>
"""
    with open(os.path.join(a.out, "city.xml"), "w") as f:
        f.write(scene)
    print("%s: %d houses, maps %d x %d texels (top), %d drops"
          % (os.path.join(a.out, "city.xml"), a.n, px(wx + 2), px(wz + 2), drops))


if __name__ == "__main__":
    main()
