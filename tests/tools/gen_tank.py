#!/usr/bin/env python3
"""gen_tank.py OUT_DIR: writes tank.obj and tank.mtl, the steel water tank of
xml_scenes/rusty_tank.xml: a vertical cylinder (radius 1.5 m, 3 m tall) with a
stiffening ring at mid height (a ledge where water lingers), a conical roof
that overhangs the wall by 0.15 m, standing on a 5 x 5 m concrete pad. y up,
metres; materials "iron" (wall, ring, roof) and "concrete" (the pad)."""
import math, os, sys

N = 64
R, H = 1.5, 3.0
out = sys.argv[1] if len(sys.argv) > 1 else "."
v, f = [], {"iron": [], "concrete": []}

def vert(x, y, z):
    v.append((x, y, z))
    return len(v)

def ring(r, y):
    return [vert(r * math.cos(2 * math.pi * k / N), y, r * math.sin(2 * math.pi * k / N)) for k in range(N)]

def band(a, b, mat, outward=True):
    for k in range(N):
        k1 = (k + 1) % N
        quad = (a[k], a[k1], b[k1], b[k]) if outward else (a[k], b[k], b[k1], a[k1])
        f[mat].append(quad)

# Wall from the pad to the ring, the ring (a ledge 0.12 m wide, 0.08 m tall), wall to the roof.
base = ring(R, 0.0)
low = ring(R, 1.46)
ledge_in = ring(R, 1.46)
ledge_out_low = ring(R + 0.12, 1.46)
ledge_out_high = ring(R + 0.12, 1.54)
ledge_top = ring(R, 1.54)
top = ring(R, H)
band(base, low, "iron", outward=False)
band(ledge_in, ledge_out_low, "iron", outward=False)      # underside of the ledge, facing down
band(ledge_out_low, ledge_out_high, "iron", outward=False)
band(ledge_out_high, ledge_top, "iron", outward=False)     # top of the ledge, facing up
band(ledge_top, top, "iron", outward=False)
# Roof: an overhanging eave (underside facing down) and a cone up to the apex.
eave_in = ring(R, H)
eave_out = ring(R + 0.15, H)
band(eave_in, eave_out, "iron", outward=False)  # facing down
cone = ring(R + 0.15, H)
apex = vert(0.0, H + 0.6, 0.0)
for k in range(N):
    f["iron"].append((cone[k], apex, cone[(k + 1) % N]))
# The pad: a 5 x 5 m slab 0.2 m thick, its top at y = 0.
s, t = 2.5, -0.2
c = [vert(x, y, z) for y in (0.0, t) for (x, z) in ((-s, -s), (s, -s), (s, s), (-s, s))]
f["concrete"] += [(c[0], c[3], c[2], c[1]),            # top, facing up
                  (c[4], c[5], c[6], c[7]),            # bottom
                  (c[0], c[1], c[5], c[4]), (c[1], c[2], c[6], c[5]),
                  (c[2], c[3], c[7], c[6]), (c[3], c[0], c[4], c[7])]

os.makedirs(out, exist_ok=True)
with open(os.path.join(out, "tank.mtl"), "w") as m:
    m.write("newmtl iron\nKd 0.35 0.35 0.38\nnewmtl concrete\nKd 0.6 0.6 0.58\n")
with open(os.path.join(out, "tank.obj"), "w") as o:
    o.write("# Steel water tank on a concrete pad (tests/tools/gen_tank.py); y up, metres.\n")
    o.write("mtllib tank.mtl\n")
    for p in v:
        o.write("v %.5f %.5f %.5f\n" % p)
    for mat, faces in f.items():
        o.write("usemtl %s\n" % mat)
        for q in faces:
            o.write("f " + " ".join(str(i) for i in q) + "\n")
print("tank: %d vertices, %d faces" % (len(v), sum(len(q) for q in f.values())))
