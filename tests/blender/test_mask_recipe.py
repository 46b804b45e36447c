"""docs/mask.md's Blender recipe, run for real (make test-blender).

    blender -b --factory-startup --python tests/blender/test_mask_recipe.py -- \
        DOCS OBJ OUT [OUT...]

DOCS is docs/mask.md, OBJ the scenes' mesh, each OUT a folder that `weathering
run` wrote mask.exr and mask.png into (tests/blender/run.sh runs both). For each
OUT, in a new empty Blender scene, the script takes the python blocks that
docs/mask.md marks `<!-- blender-recipe: NAME -->` (projection, camera, render),
fills in their placeholders from mask.exr's header (read here, no OpenEXR module
needed), runs them in that order on the imported mesh, and compares the render
with mask.exr and with mask.png, the 8-bit preview: the rendered values go
through the preview's transform (docs/mask.md, "The PNG preview") and must
correlate with mask.png's grey over the texels it marks as surface.

Prints one line per check and ends with "N passed, M failed"; the exit status is
non-zero when a check failed. Uses only Blender's Python (Debian's Blender has
no numpy).
"""

import array
import math
import os
import re
import struct
import sys
import time
import traceback

import bpy

MIN_CORRELATION = 0.99   # Pearson, preview grey of the render vs mask.png
MIN_COVERAGE = 0.99      # texels where the render and mask.png agree on surface
MIN_EXACT = 0.99         # surface texels whose rendered value is the mask's

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
    return ok


def finish():
    print("%d passed, %d failed" % (passed, failed))
    sys.stdout.flush()
    sys.exit(1 if failed else 0)


# --- The mask's header ------------------------------------------------------

def read_exr_header(path):
    """Attributes of a single-part EXR: {name: (type, value)}; m44f as 16 floats
    (row by row), box2i as (xmin, ymin, xmax, ymax), string as str, others raw."""
    with open(path, "rb") as f:
        data = f.read(1 << 20)
    if data[:4] != b"\x76\x2f\x31\x01":
        raise ValueError("%s: not an OpenEXR file" % path)
    version = struct.unpack_from("<i", data, 4)[0]
    if version & 0xFF != 2 or version & (1 << 12 | 1 << 13):
        raise ValueError("%s: version field %#x, expected a single-part file" % (path, version))
    pos = 8
    attributes = {}

    def cstring():
        nonlocal pos
        end = data.index(b"\0", pos)
        text = data[pos:end].decode("latin-1")
        pos = end + 1
        return text

    while True:
        name = cstring()
        if not name:
            return attributes
        kind = cstring()
        size = struct.unpack_from("<i", data, pos)[0]
        pos += 4
        raw = data[pos:pos + size]
        if len(raw) != size:
            raise ValueError("%s: header cut short in %s" % (path, name))
        pos += size
        if kind == "m44f":
            value = list(struct.unpack("<16f", raw))
        elif kind == "box2i":
            value = struct.unpack("<4i", raw)
        elif kind == "string":
            value = raw.decode("utf-8", "replace")
        else:
            value = raw
        attributes[name] = (kind, value)


# --- The recipe, from the docs ----------------------------------------------

MARK = re.compile(r"^<!-- blender-recipe: (\w+) -->\s*$")


def recipe_blocks(docs):
    """{name: (first code line number, code)} of the marked ```python blocks."""
    lines = open(docs, encoding="utf-8").read().split("\n")
    blocks = {}
    i = 0
    while i < len(lines):
        mark = MARK.match(lines[i])
        i += 1
        if not mark:
            continue
        if i >= len(lines) or lines[i].strip() != "```python":
            raise ValueError("%s:%d: the mark %s is not followed by a ```python fence"
                             % (docs, i, mark.group(1)))
        i += 1
        start = i
        while i < len(lines) and lines[i].strip() != "```":
            i += 1
        if mark.group(1) in blocks:
            raise ValueError("%s: two blocks marked %s" % (docs, mark.group(1)))
        blocks[mark.group(1)] = (start + 1, "\n".join(lines[start:i]) + "\n")
    return blocks


def fill(code, pattern, replacement):
    """Replaces the one line matching pattern (from its start); returns
    (code, number of lines matched)."""
    return re.subn(r"^" + pattern + r".*$", lambda m: replacement, code, flags=re.M)


def run_block(docs, name, line, code):
    # Padding keeps the docs' line numbers in tracebacks.
    exec(compile("\n" * (line - 1) + code, docs, "exec"), {"__name__": "recipe_" + name})


# --- Pixels -----------------------------------------------------------------

def load_pixels(path):
    """(width, height, RGBA floats, bottom row first) of an image file, as stored."""
    image = bpy.data.images.load(path)
    image.colorspace_settings.name = "Non-Color"
    width, height = image.size
    pixels = array.array("f", bytes(4 * 4 * width * height))
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return width, height, pixels


def preview_grey(value, p99):
    """docs/mask.md's preview: round(255 * min(1, Y / p99) ^ (1 / 2.2))."""
    if value <= 0.0 or p99 <= 0.0:
        return 0
    return int(math.floor(255.0 * min(1.0, value / p99) ** (1.0 / 2.2) + 0.5))


def pearson(xs, ys):
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxy = sxx = syy = 0.0
    for x, y in zip(xs, ys):
        dx, dy = x - mx, y - my
        sxy += dx * dy
        sxx += dx * dx
        syy += dy * dy
    return sxy / math.sqrt(sxx * syy) if sxx > 0 and syy > 0 else float("nan")


# --- The test ---------------------------------------------------------------

def main(docs, obj_path, out):
    mask_exr = os.path.join(out, "mask.exr")
    mask_png = os.path.join(out, "mask.png")
    render_exr = os.path.join(out, "blender_render.exr")

    header = read_exr_header(mask_exr)
    ndc = header.get("worldToNDC", (None, None))[1]
    w2c = header.get("worldToCamera", (None, None))[1]
    window = header.get("dataWindow", (None, None))[1]
    if not check(isinstance(ndc, list) and isinstance(w2c, list) and window is not None,
                 "mask.exr's header holds worldToNDC, worldToCamera and dataWindow"):
        return
    width, height = window[2] - window[0] + 1, window[3] - window[1] + 1
    print("     mask %d x %d, worldToNDC %s" % (width, height, " ".join("%g" % v for v in ndc)))

    blocks = recipe_blocks(docs)
    if not check(sorted(blocks) == ["camera", "projection", "render"],
                 "docs/mask.md marks the recipe blocks projection, camera, render (found %s)"
                 % ", ".join(sorted(blocks))):
        return
    numbers = lambda m: "[" + ", ".join(repr(v) for v in m) + "]"
    fills = {
        "projection": [(r"NDC = \[\.\.\.\]", "NDC = " + numbers(ndc)),
                       (r'MASK = "/path/to/mask\.exr"', "MASK = %r" % mask_exr)],
        "camera": [(r"W = \[\.\.\.\]", "W = " + numbers(w2c)),
                   (r"NDC = \[\.\.\.\]", "NDC = " + numbers(ndc)),
                   (r"WIDTH_PX, HEIGHT_PX = \d+, \d+", "WIDTH_PX, HEIGHT_PX = %d, %d" % (width, height))],
        "render": [(r'scene\.render\.filepath = "/path/to/render\.exr"',
                    "scene.render.filepath = %r" % render_exr)],
    }
    code = {}
    all_filled = True
    for name, subs in fills.items():
        line, text = blocks[name]
        for pattern, replacement in subs:
            text, count = fill(text, pattern, replacement)
            if count != 1:
                print("     block %s: %d lines match %s, expected 1" % (name, count, pattern))
                all_filled = False
        code[name] = (line, text)
    if not check(all_filled, "every placeholder of the recipe is filled in exactly once"):
        return

    # The scene: the OBJ alone, imported with the default axes, selected.
    bpy.ops.wm.read_factory_settings(use_empty=True)
    before = set(bpy.data.objects)
    if hasattr(bpy.ops.wm, "obj_import"):
        bpy.ops.wm.obj_import(filepath=obj_path)
    else:
        bpy.ops.import_scene.obj(filepath=obj_path)
    imported = [o for o in bpy.data.objects if o not in before]
    bpy.ops.object.select_all(action="DESELECT")
    for o in imported:
        o.select_set(True)
    bpy.context.view_layer.objects.active = imported[0] if imported else None
    slots = [s for o in imported for s in o.material_slots]
    print("     imported %s, %d material slots" % (", ".join(o.name for o in imported), len(slots)))
    if not check(len(imported) == 1 and len(slots) >= 2,
                 "the OBJ imports as one mesh object with several materials"):
        return

    run_block(docs, "projection", *code["projection"])
    mask_image = [i for i in bpy.data.images if i.filepath == mask_exr]
    projected = 0
    for slot in slots:
        mat = slot.material
        if mat is None or not mat.use_nodes:
            continue
        texture = [n for n in mat.node_tree.nodes
                   if n.type == "TEX_IMAGE" and mask_image and n.image == mask_image[0]]
        output = mat.node_tree.get_output_node("ALL")
        surface = output.inputs["Surface"].links if output else []
        if (len(texture) == 1 and surface and surface[0].from_node.type == "EMISSION"
                and surface[0].from_node.inputs["Color"].links
                and surface[0].from_node.inputs["Color"].links[0].from_node == texture[0]):
            projected += 1
    check(projected == len(slots),
          "every material slot shows the projected mask (%d of %d: %s)"
          % (projected, len(slots), ", ".join(s.material.name if s.material else "-" for s in slots)))

    run_block(docs, "camera", *code["camera"])
    scene = bpy.context.scene
    check(scene.camera is not None and scene.camera.data.type == "ORTHO"
          and (scene.render.resolution_x, scene.render.resolution_y) == (width, height)
          and scene.render.resolution_percentage == 100,
          "the scene's camera is orthographic, %d x %d pixels" % (width, height))

    t0 = time.time()
    run_block(docs, "render", *code["render"])
    print("     render (%s) took %.1f s" % (scene.render.engine, time.time() - t0))
    if not check(os.path.isfile(render_exr), "the render wrote " + render_exr):
        return

    rw, rh, render = load_pixels(render_exr)
    mw, mh, mask = load_pixels(mask_exr)
    pw, ph, png = load_pixels(mask_png)
    if not check((rw, rh) == (mw, mh) == (pw, ph) == (width, height),
                 "render, mask.exr and mask.png are %d x %d (%d x %d, %d x %d, %d x %d)"
                 % (width, height, rw, rh, mw, mh, pw, ph)):
        return

    n = width * height
    positive = sorted(mask[4 * i] for i in range(n) if mask[4 * i] > 0.0)
    p99 = positive[int(math.floor(0.99 * (len(positive) - 1)))] if positive else 0.0
    print("     mask: %d positive texels, p99 %g, max %g"
          % (len(positive), p99, positive[-1] if positive else 0.0))

    rendered, expected = [], []
    agree = exact = surface = 0
    for i in range(n):
        png_surface = png[4 * i + 3] > 0.5
        render_surface = render[4 * i + 3] > 0.5
        agree += png_surface == render_surface
        if not png_surface:
            continue
        surface += 1
        r, y = render[4 * i], mask[4 * i]
        exact += abs(r - y) <= 1e-5 * max(1.0, abs(y))
        rendered.append(preview_grey(r, p99))
        expected.append(int(round(png[4 * i] * 255.0)))
    correlation = pearson(rendered, expected) if surface > 1 else float("nan")
    differ = [abs(a - b) for a, b in zip(rendered, expected) if a != b]
    print("     %d surface texels in mask.png; the render's preview grey differs from"
          " mask.png's in %d, by at most %d" % (surface, len(differ), max(differ, default=0)))
    check(agree >= MIN_COVERAGE * n,
          "render and mask.png agree on surface / no surface: %.6f of the texels (>= %g)"
          % (agree / n, MIN_COVERAGE))
    check(surface > 0 and exact >= MIN_EXACT * surface,
          "rendered value = mask.exr's Y (within 1e-5): %.6f of the surface texels (>= %g)"
          % (exact / max(surface, 1), MIN_EXACT))
    check(correlation >= MIN_CORRELATION,
          "Pearson correlation of the render's preview grey with mask.png: %.6f (>= %g)"
          % (correlation, MIN_CORRELATION))


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if len(args) < 3:
        print("usage: blender -b --factory-startup --python %s -- DOCS OBJ OUT [OUT...]"
              % sys.argv[0])
        check(False, "arguments")
        finish()
    for out in args[2:]:
        print("== %s" % out)
        try:
            main(args[0], os.path.abspath(args[1]), os.path.abspath(out))
        except Exception:
            traceback.print_exc()
            check(False, "the test of %s ran to its end without an exception" % out)
    finish()
