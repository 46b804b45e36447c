"""The Blender add-on (blender/weathering/), run headless (make test-blender).

    blender -b --factory-startup --python tests/blender/test_addon.py -- BUILD [--render PNG]

BUILD is the build folder (absolute or relative to the repository) holding the
`weathering` program. The script registers the add-on from the repository
(sys.path + import + register, no installation), points its `program`
preference at BUILD/weathering, builds a cube and a UV sphere beside it under
an orthographic three-quarter camera with a non-square render, runs
bpy.ops.weathering.run() with the rain preset and a small particle count into
BUILD/blender-test/addon/, and checks:

- it returns {'FINISHED'}; every object's material holds the image nodes (one
  per texture channel, the projected mask) fed by a UV Map node naming the
  object's active UV map, and the main channel mixed into the Base Color;
- the texture's texels on the cube's top face are dirtier than on its sides
  (the split single-channel EXR read through bpy.data.images, the texels
  mapped to faces through the cube's own UV layout);
- the axes: the exported OBJ is Blender's geometry in scene axes (axes.py),
  the scene's output <View> is Blender's camera converted to Y up, the mask's
  worldToCamera is the camera's, and worldToNDC puts every bounding-box corner
  where Blender's camera sees it (all to 1e-4);
- bad input: a program path that does not exist gives {'CANCELLED'} with an
  error report naming it, and no traceback;
- UDIM: a cube whose top face's UVs lie in tile 1002 gets tiles="udim", the
  tiles 1001 and 1002 as files, and tiled images (<UDIM> in their path) whose
  tile 1002 holds the dirtier top; a plane whose UVs are one point gets no
  TextureMap (BUILD/blender-test/addon-udim/).

With --render PNG it also renders the weathered objects with EEVEE (a ground
plane, a sun) into PNG (docs/images/blender-addon.png). Prints one line per
check and ends with "N passed, M failed"; the exit status is non-zero when a
check failed. Uses only Blender's Python (no numpy).
"""

import array
import contextlib
import io
import math
import os
import re
import sys
import time
import traceback

import bpy
from bpy_extras.object_utils import world_to_camera_view
from mathutils import Vector

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(REPO, "blender"))

import weathering                                   # noqa: E402  (the add-on)
from weathering import axes, exr, scene_xml         # noqa: E402

TOL = 1e-4
PARTICLES = 60000
RESOLUTION = 256

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


def finish():
    print("%d passed, %d failed" % (passed, failed))
    sys.stdout.flush()
    sys.exit(1 if failed else 0)


def close(a, b, tol=TOL):
    return len(a) == len(b) and all(abs(x - y) <= tol * max(1.0, abs(y)) for x, y in zip(a, b))


def run_operator():
    """bpy.ops.weathering.run(): (result set or None, error text or None,
    what went to stderr). A script's operator call raises RuntimeError with the
    message when the operator reported an error."""
    err = io.StringIO()
    result = message = None
    with contextlib.redirect_stderr(err):
        try:
            result = bpy.ops.weathering.run()
        except RuntimeError as e:
            message = str(e)
    return result, message, err.getvalue()


# --- The scene --------------------------------------------------------------

def build_scene(folder):
    scene = bpy.context.scene
    bpy.ops.mesh.primitive_cube_add(size=2.0, location=(0.0, 0.0, 1.0))
    cube = bpy.context.active_object
    cube.name = "Cube"
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, location=(3.0, 0.5, 1.0), segments=32,
                                         ring_count=16)
    sphere = bpy.context.active_object
    sphere.name = "Sphere"
    bpy.ops.object.shade_smooth()

    # A three-quarter view from the front right, above (Blender's front is -Y).
    data = bpy.data.cameras.new("shot")
    data.type = "ORTHO"
    data.ortho_scale = 7.0
    camera = bpy.data.objects.new("shot", data)
    scene.collection.objects.link(camera)
    target = Vector((1.5, 0.25, 1.0))
    camera.location = target + Vector((7.0, -9.0, 7.0))
    camera.rotation_euler = (target - camera.location).to_track_quat("-Z", "Y").to_euler()
    scene.camera = camera
    scene.render.resolution_x, scene.render.resolution_y = 640, 480
    scene.render.resolution_percentage = 100
    bpy.context.view_layer.update()

    bpy.ops.object.select_all(action="DESELECT")
    cube.select_set(True)
    sphere.select_set(True)
    bpy.context.view_layer.objects.active = cube

    settings = scene.weathering
    settings.preset = "rain"
    settings.particle_count = PARTICLES
    settings.resolution = RESOLUTION
    settings.output_folder = folder
    return scene, cube, sphere, camera


# --- Reading results --------------------------------------------------------

def image_pixels(image):
    w, h = image.size
    pixels = array.array("f", bytes(4 * 4 * w * h))
    image.pixels.foreach_get(pixels)
    return w, h, pixels


def inside(poly, x, y):
    """x, y inside the convex polygon poly (either winding)?"""
    sign = 0
    n = len(poly)
    for k in range(n):
        (ax, ay), (bx, by) = poly[k], poly[(k + 1) % n]
        cross = (bx - ax) * (y - ay) - (by - ay) * (x - ax)
        if cross != 0:
            s = 1 if cross > 0 else -1
            if sign == 0:
                sign = s
            elif s != sign:
                return False
    return True


def face_means(obj, image, tile=None):
    """{'top': mean, 'side': mean, 'bottom': mean} of the image's R over the
    texels whose centre lies in a face of obj's active UV layout, by the
    face's normal in world space. With tile = (u, v), the image is that UV
    tile's (UDIM): only the faces inside it count, moved onto [0,1]^2."""
    w, h, pixels = image_pixels(image)
    mesh = obj.data
    uv = mesh.uv_layers.active.data
    normal_matrix = obj.matrix_world.to_3x3()
    sums = {"top": [0.0, 0], "side": [0.0, 0], "bottom": [0.0, 0]}
    for poly in mesh.polygons:
        n = (normal_matrix @ poly.normal).normalized()
        kind = "top" if n.z > 0.99 else "bottom" if n.z < -0.99 else "side" if abs(n.z) < 0.01 else None
        if kind is None:
            continue
        corners = [tuple(uv[i].uv) for i in poly.loop_indices]
        if tile is not None:
            corners = [(a - tile[0], b - tile[1]) for a, b in corners]
            if not all(-1e-6 <= c <= 1 + 1e-6 for corner in corners for c in corner):
                continue
        us, vs = [c[0] for c in corners], [c[1] for c in corners]
        for j in range(max(0, int(min(vs) * h) - 1), min(h, int(max(vs) * h) + 2)):
            for i in range(max(0, int(min(us) * w) - 1), min(w, int(max(us) * w) + 2)):
                if inside(corners, (i + 0.5) / w, (j + 0.5) / h):
                    sums[kind][0] += pixels[4 * (j * w + i)]
                    sums[kind][1] += 1
    return {k: (s / c if c else float("nan"), c) for k, (s, c) in sums.items()}


def obj_bounds(path):
    lo = [math.inf] * 3
    hi = [-math.inf] * 3
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                v = [float(s) for s in line.split()[1:4]]
                lo = [min(a, b) for a, b in zip(lo, v)]
                hi = [max(a, b) for a, b in zip(hi, v)]
    return lo, hi


def expected_camera(scene, camera):
    """The Blender camera, in scene axes: eye, unit right/up/forward, width,
    height (orthographic, AUTO sensor fit, no shift: as build_scene makes it)."""
    rot = camera.matrix_world.to_3x3().normalized()
    right = Vector(axes.to_scene(rot.col[0].normalized()))
    up = Vector(axes.to_scene(rot.col[1].normalized()))
    forward = Vector(axes.to_scene(-rot.col[2].normalized()))
    eye = Vector(axes.to_scene(camera.matrix_world.translation))
    r = scene.render
    aspect = r.resolution_x / r.resolution_y
    s = camera.data.ortho_scale
    width, height = (s, s / aspect) if aspect >= 1 else (s * aspect, s)
    return eye, right, up, forward, width, height


# --- The test ---------------------------------------------------------------

def main(build, render_png):
    program = os.path.join(build, "weathering")
    folder = os.path.join(build, "blender-test", "addon")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    weathering.register()
    prefs = bpy.context.preferences
    addon = prefs.addons.get("weathering") or prefs.addons.new()
    addon.module = "weathering"
    check(addon.preferences is not None and addon.preferences.program == "weathering",
          "the add-on registers from the repository; its program preference defaults to "
          "'weathering'")
    addon.preferences.program = program
    scene, cube, sphere, camera = build_scene(folder)

    # Bad input first: a program that does not exist.
    addon.preferences.program = os.path.join(build, "no-such-weathering")
    result, message, stderr = run_operator()
    check(result is None and message is not None and "no-such-weathering" in message
          and "does not exist" in message and scene.weathering.status.startswith("failed")
          and "Traceback" not in stderr,
          "a missing program: {'CANCELLED'} with an error report naming it, no traceback "
          "(%s)" % (message or result).strip().replace("\n", " "))
    addon.preferences.program = program

    t0 = time.time()
    result, message, stderr = run_operator()
    seconds = time.time() - t0
    if not check(result == {"FINISHED"},
                 "bpy.ops.weathering.run() (rain, %d particles, %d px) returns {'FINISHED'} "
                 "in %.1f s (%s)" % (PARTICLES, RESOLUTION, seconds, message or result)):
        if stderr.strip():
            print(stderr)
        log = os.path.join(folder, "weathering.log")
        if os.path.isfile(log):
            print(open(log).read()[-3000:])
        return
    print("     %s" % scene.weathering.status)

    # The materials.
    for obj in (cube, sphere):
        mat = obj.active_material
        nodes = mat.node_tree.nodes if mat is not None and mat.use_nodes else []
        images = {n.label: n for n in nodes if n.type == "TEX_IMAGE"}
        uv_nodes = [n for n in nodes if n.type == "UVMAP"]
        uv_name = obj.data.uv_layers.active.name
        fed = all(n.inputs["Vector"].links and n.inputs["Vector"].links[0].from_node == uv_nodes[0]
                  for label, n in images.items() if not label.startswith("mask")) if uv_nodes else False
        principled = [n for n in nodes if n.type == "BSDF_PRINCIPLED"]
        base = principled[0].inputs["Base Color"] if principled else None
        mixed = bool(base and base.links and base.links[0].from_node.name == "weathering:mix")
        check(mat is not None and {"Y", "seen"} <= set(images) and "mask Y (shot)" in images
              and all(n.image is not None and n.image.colorspace_settings.name == "Non-Color"
                      for n in images.values())
              and len(uv_nodes) == 1 and uv_nodes[0].uv_map == uv_name and fed and mixed,
              "%s's material %s: image nodes %s (Non-Color), fed by a UV Map node naming %s; "
              "the mix on its Base Color"
              % (obj.name, mat.name if mat else None, ", ".join(sorted(images)), uv_name))

    # The texture: the cube's top face dirtier than its sides.
    tex = [n for n in cube.active_material.node_tree.nodes
           if n.type == "TEX_IMAGE" and n.label == "Y"]
    if tex:
        image = tex[0].image
        means = face_means(cube, image)
        top, side = means["top"][0], means["side"][0]
        print("     %s: mean per square metre top %.4g (%d texels), sides %.4g (%d), bottom %.4g (%d)"
              % (os.path.basename(image.filepath), top, means["top"][1], side, means["side"][1],
                 means["bottom"][0], means["bottom"][1]))
        check(means["top"][1] > 100 and means["side"][1] > 400 and top > 1.5 * side,
              "the cube's top face is dirtier than its sides in the split texture (%.4g > 1.5 x %.4g)"
              % (top, side))
    seen = [n for n in cube.active_material.node_tree.nodes
            if n.type == "TEX_IMAGE" and n.label == "seen"]
    if seen:
        means = face_means(cube, seen[0].image)
        # The sphere hides part of the cube's +X side from the 'right' camera.
        check(means["top"][0] > 0.99 and means["side"][0] > 0.75,
              "the texture's seen channel: the cube's top all seen (%.3f), its sides mostly "
              "(%.3f: the sphere hides part of one from the input camera on that side)"
              % (means["top"][0], means["side"][0]))

    # The axes: the OBJ, the scene's <View>, the mask's header.
    depsgraph = bpy.context.evaluated_depsgraph_get()
    corners = [cube.matrix_world @ Vector(c) for c in cube.bound_box]
    scene_pts = [axes.to_scene(c) for c in corners]
    want_lo = [min(p[k] for p in scene_pts) for k in range(3)]
    want_hi = [max(p[k] for p in scene_pts) for k in range(3)]
    lo, hi = obj_bounds(os.path.join(folder, "meshes", "Cube.obj"))
    check(close(lo, want_lo) and close(hi, want_hi),
          "meshes/Cube.obj is the cube in scene axes (Y up): bounds %s .. %s"
          % (" ".join("%.4g" % v for v in lo), " ".join("%.4g" % v for v in hi)))

    eye, right, up, forward, width, height = expected_camera(scene, camera)
    tree = scene_xml.load(os.path.join(folder, "scene.xml"))
    view = scene_xml.view(tree)
    direction = (Vector(view["target"]) - Vector(view["eye"])).normalized()
    check(close(view["eye"], eye) and close(direction, forward) and close(view["up"], up)
          and close((view["width"], view["height"]), (width, height))
          and view["resolution"] == (RESOLUTION, round(RESOLUTION * height / width)),
          "scene.xml's output <View> is Blender's camera in scene axes: eye %s, direction %s, "
          "up %s, %.4g x %.4g, %d x %d px"
          % (" ".join("%.4g" % v for v in view["eye"]), " ".join("%.4g" % v for v in direction),
             " ".join("%.4g" % v for v in view["up"]), view["width"], view["height"],
             *view["resolution"]))

    header = exr.read_header(os.path.join(folder, "out", "mask.exr"))
    w2c = exr.matrix(header, "worldToCamera")
    ndc = exr.matrix(header, "worldToNDC")
    want = []
    for k in range(3):
        want += [right[k], up[k], forward[k], 0.0]
    want += [-eye.dot(right), -eye.dot(up), -eye.dot(forward), 1.0]
    check(w2c is not None and close(w2c, want),
          "mask.exr's worldToCamera is Blender's camera (right, up, forward columns; "
          "eye %s)" % " ".join("%.4g" % v for v in eye))
    worst = 0.0
    if ndc is not None:
        for obj in (cube, sphere):
            for c in obj.bound_box:
                p = obj.matrix_world @ Vector(c)
                x, y, z = axes.to_scene(p)
                u = x * ndc[0] + y * ndc[4] + z * ndc[8] + ndc[12]
                v = 1.0 - (x * ndc[1] + y * ndc[5] + z * ndc[9] + ndc[13])
                seen_at = world_to_camera_view(scene, camera, p)
                worst = max(worst, abs(u - seen_at.x), abs(v - seen_at.y))
    check(ndc is not None and worst <= TOL,
          "mask.exr's worldToNDC puts every bounding-box corner where Blender's camera sees it "
          "(largest difference %.2g of the frame)" % worst)
    del depsgraph

    # A second run replaces the add-on's nodes (no stacking) and the original
    # base colour comes back when they are removed.
    def ours(obj):
        return sorted(n.name for n in obj.active_material.node_tree.nodes)
    first = ours(cube)
    result, message, _ = run_operator()
    second = ours(cube)
    mat = cube.active_material
    principled = [n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED"][0]
    colour = tuple(mat.node_tree.nodes["weathering:mix"].inputs["Color1"].default_value)
    weathering.shading.clear(mat)
    left = [n.name for n in mat.node_tree.nodes if n.name.startswith("weathering:")]
    check(result == {"FINISHED"} and second == first and
          not left and not principled.inputs["Base Color"].links
          and close(tuple(principled.inputs["Base Color"].default_value), colour),
          "a second run replaces the add-on's %d nodes; removing them gives the Base Color back"
          % len([n for n in first if n.startswith("weathering:")]))

    # A perspective camera: an orthographic frame at its position and direction
    # that holds every object.
    camera.data.type = "PERSP"
    view, notes = weathering.job.camera_view(scene, camera, [cube, sphere], 256, False)
    camera.data.type = "ORTHO"
    eye, right, up, forward, _, _ = expected_camera(scene, camera)
    direction = (Vector(view["target"]) - Vector(view["eye"])).normalized()
    holds = all(abs((Vector(axes.to_scene(o.matrix_world @ Vector(c))) - eye).dot(right))
                <= view["width"] / 2 and
                abs((Vector(axes.to_scene(o.matrix_world @ Vector(c))) - eye).dot(up))
                <= view["height"] / 2 for o in (cube, sphere) for c in o.bound_box)
    check(close(view["eye"], eye) and close(direction, forward) and holds
          and any("perspective camera approximated by an orthographic one" in t for _, t in notes),
          "a perspective camera: same eye and direction, a %.3g x %.3g frame holding the "
          "objects, and the note '%s'" % (view["width"], view["height"],
                                         notes[0][1] if notes else ""))

    udim_object(scene, folder)

    if render_png:
        render(scene, cube, sphere, render_png)


def udim_object(scene, folder):
    """A cube whose top face's UVs are moved into UDIM tile 1002 (the rest in
    1001), weathered with a plane whose UVs are all one point: init reads the
    cube's layout as UDIM, the run writes Tiles_texture.1001.exr and .1002.exr,
    and the add-on loads each channel as one tiled image (source 'TILED',
    <UDIM> in its path, tiles 1001 and 1002 read from their files); the top,
    in tile 1002, is dirtier than the sides. The plane's layout covers no
    texel: no TextureMap, the camera mask only."""
    bpy.ops.mesh.primitive_cube_add(size=2.0, location=(-3.5, 0.0, 1.0))
    obj = bpy.context.active_object
    obj.name = "Tiles"
    uv = obj.data.uv_layers.active.data
    for poly in obj.data.polygons:
        if poly.normal.z > 0.99:
            for i in poly.loop_indices:
                uv[i].uv.x += 1.0
    bpy.ops.mesh.primitive_plane_add(size=2.0, location=(-3.5, -3.0, 0.0))
    flat = bpy.context.active_object
    flat.name = "Flat"
    for loop in flat.data.uv_layers.active.data:
        loop.uv = (0.5, 0.5)
    bpy.ops.object.select_all(action="DESELECT")
    obj.select_set(True)
    flat.select_set(True)
    bpy.context.view_layer.objects.active = obj
    settings = scene.weathering
    saved = settings.output_folder
    settings.output_folder = os.path.join(os.path.dirname(folder), "addon-udim")
    out = os.path.join(settings.output_folder, "out")
    try:
        result, message, stderr = run_operator()
        if not check(result == {"FINISHED"}, "a UDIM object: the run returns {'FINISHED'} (%s)"
                     % (message or result)):
            print(stderr)
            return
        tree = scene_xml.load(os.path.join(settings.output_folder, "scene.xml"))
        tex = [t for t in tree.getroot().iter("TextureMap")]
        flat_mesh = [m for m in tree.getroot().iter("Mesh") if m.get("file") == "meshes/Flat.obj"]
        flat_nodes = {n.label for n in flat.active_material.node_tree.nodes
                      if n.type == "TEX_IMAGE"}
        check(len(flat_mesh) == 1 and flat_mesh[0].find("TextureMap") is None
              and flat_nodes == {"mask Y (shot)"},
              "a plane whose UVs are one point: no TextureMap, the camera mask only (%s)"
              % ", ".join(sorted(flat_nodes)))
        written = sorted(f for f in os.listdir(out) if f.startswith("Tiles_texture."))
        tile_files = [f for f in written if re.match(r"Tiles_texture\.[0-9]{4}\.exr$", f)]
        check(len(tex) == 1 and tex[0].get("tiles") == "udim" and "Tiles_texture.exr" not in written
              and tile_files == ["Tiles_texture.1001.exr", "Tiles_texture.1002.exr"],
              "its TextureMap is tiles=\"udim\" (init's choice) and the run wrote the tiles "
              "1001 and 1002 only: %s" % ", ".join(tile_files))
        nodes = obj.active_material.node_tree.nodes
        images = {n.label: n.image for n in nodes if n.type == "TEX_IMAGE"
                  and not n.label.startswith("mask")}
        tiled = all(im is not None and im.source == "TILED" and "<UDIM>" in im.filepath
                    and sorted(t.number for t in im.tiles) == [1001, 1002]
                    and all(tuple(t.size) == (RESOLUTION, RESOLUTION) for t in im.tiles)
                    and im.colorspace_settings.name == "Non-Color"
                    for im in images.values())
        check({"Y", "seen"} <= set(images) and tiled,
              "its image nodes %s hold tiled images %s with tiles 1001 and 1002 of %d x %d "
              "read from their files" % (", ".join(sorted(images)),
                                         images["Y"].filepath if "Y" in images else None,
                                         RESOLUTION, RESOLUTION))
        top = face_means(obj, shading_image(os.path.join(out, "Tiles_texture.1002_Y.exr")),
                         tile=(1, 0))["top"]
        side = face_means(obj, shading_image(os.path.join(out, "Tiles_texture.1001_Y.exr")),
                          tile=(0, 0))["side"]
        print("     UDIM: top (tile 1002) %.4g (%d texels), sides (tile 1001) %.4g (%d)"
              % (top[0], top[1], side[0], side[1]))
        check(top[1] > 100 and side[1] > 400 and top[0] > 1.5 * side[0],
              "the top face in tile 1002 is dirtier than the sides in tile 1001 "
              "(%.4g > 1.5 x %.4g)" % (top[0], side[0]))
    finally:
        settings.output_folder = saved
        bpy.data.objects.remove(obj)
        bpy.data.objects.remove(flat)


def shading_image(path):
    """One file as an image of its own (a tile's split channel)."""
    return bpy.data.images.load(path, check_existing=True)


def render(scene, cube, sphere, path):
    """The default house (xml_scenes/meshes/building.obj) weathered by the
    add-on with the rain preset's own particle count, rendered with EEVEE in
    sunlight through a three-quarter camera."""
    for obj in (cube, sphere):
        bpy.data.objects.remove(obj)
    before = set(bpy.data.objects)
    bpy.ops.import_scene.obj(filepath=os.path.join(REPO, "xml_scenes", "meshes", "building.obj"))
    house = [o for o in bpy.data.objects if o not in before]
    bpy.ops.mesh.primitive_plane_add(size=60.0, location=(0.0, 0.0, -0.01))
    ground = bpy.context.active_object
    mat = bpy.data.materials.new("ground")
    mat.use_nodes = True
    mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.3, 0.3, 0.28, 1)
    ground.data.materials.append(mat)
    bpy.ops.object.select_all(action="DESELECT")
    for o in house:
        o.select_set(True)
    bpy.context.view_layer.objects.active = house[0]

    camera = scene.camera
    target = Vector((0.5, 0.0, 5.6))
    camera.location = target + Vector((14.0, -24.0, 9.0))
    camera.rotation_euler = (target - camera.location).to_track_quat("-Z", "Y").to_euler()
    camera.data.ortho_scale = 21.5
    scene.render.resolution_x, scene.render.resolution_y = 960, 720
    settings = scene.weathering
    settings.particle_count = 0
    settings.particle_scale = 2.0
    settings.resolution = 1024
    # The walls hold tens per square metre, the roof and the ground thousands:
    # full at 100 shows the walls' streaks (the roof saturates).
    settings.full_amount = 100.0
    settings.output_folder = os.path.join(os.path.dirname(settings.output_folder), "addon-house")
    t0 = time.time()
    result, message, _ = run_operator()
    if not check(result == {"FINISHED"}, "the add-on weathers the house (%s, %.1f s)"
                 % (message or result, time.time() - t0)):
        return

    sun = bpy.data.lights.new("sun", "SUN")
    sun.energy = 3.5
    sun.angle = math.radians(2.0)
    sun_obj = bpy.data.objects.new("sun", sun)
    scene.collection.objects.link(sun_obj)
    sun_obj.rotation_euler = (math.radians(55), 0.0, math.radians(35))
    world = bpy.data.worlds.new("sky")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.55, 0.62, 0.72, 1)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.8
    scene.world = world
    scene.render.engine = "BLENDER_EEVEE"
    scene.eevee.taa_render_samples = 32
    scene.eevee.use_soft_shadows = True
    scene.eevee.use_gtao = True
    scene.eevee.shadow_cascade_size = "4096"
    scene.view_settings.view_transform = "Filmic"
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGB"
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    check(os.path.isfile(path), "rendered the weathered house into " + path)


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    render_png = None
    if "--render" in args:
        k = args.index("--render")
        render_png = os.path.abspath(args[k + 1]) if k + 1 < len(args) else None
        del args[k:k + 2]
    if len(args) != 1:
        print("usage: blender -b --factory-startup --python %s -- BUILD [--render PNG]"
              % sys.argv[0])
        check(False, "arguments")
        finish()
    build = args[0] if os.path.isabs(args[0]) else os.path.join(REPO, args[0])
    try:
        main(build, render_png)
    except Exception:
        traceback.print_exc()
        check(False, "the test ran to its end without an exception")
    finish()
