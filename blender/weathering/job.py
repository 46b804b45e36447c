"""One weathering run from Blender: export, generate, edit, run, load back.

    job = Job(context, settings, program)
    job.prepare(context)        # export OBJs, `weathering init`, edit scene.xml
    job.start(progress=...)     # `weathering run scene.xml --out out` (background)
    ... job.process.poll() until it returns the exit status ...
    job.finish(context)         # `weathering split`, images, nodes

Every failure the user can act on is a CommandError (cli.py) or SceneError
(scene_xml.py) with a message; the operator reports it."""

import contextlib
import io
import math
import os
import re
import tempfile
import time

import bpy
from mathutils import Vector

from . import axes, cli, exr, scene_xml, shading
from .cli import CommandError

_session_folder = None

# Blender's unit scale (metres per Blender unit) -> `weathering init --units`.
_UNITS = ((1.0, "m"), (0.01, "cm"), (0.001, "mm"), (0.0254, "in"), (0.3048, "ft"))


def output_folder(path):
    """The folder the add-on works in: `path` when given (Blender's // allowed),
    else BLENDNAME_weathering/ next to the saved .blend, else a temporary
    folder made once per Blender session."""
    global _session_folder
    path = (path or "").strip()
    if path:
        return os.path.abspath(bpy.path.abspath(path))
    if bpy.data.filepath:
        base = os.path.splitext(bpy.path.basename(bpy.data.filepath))[0]
        return os.path.join(os.path.dirname(bpy.data.filepath), base + "_weathering")
    if _session_folder is None or not os.path.isdir(_session_folder):
        _session_folder = tempfile.mkdtemp(prefix="blender-weathering-")
    return _session_folder


def target_objects(context):
    """The selected mesh objects, or every visible mesh object when none is
    (meshes without faces left out)."""
    selected = [o for o in context.selected_objects if o.type == "MESH"]
    if not selected:
        selected = [o for o in context.view_layer.objects if o.type == "MESH" and o.visible_get()]
    return [o for o in selected if o.data.polygons]


def file_name(name, used):
    """A plain file name for an object (letters, digits, '_', '-', '.'), unique."""
    base = "".join(c if (c.isascii() and c.isalnum()) or c in "_-." else "_" for c in name)
    base = base.strip(".") or "object"
    candidate, k = base, 1
    while candidate.lower() in used:
        k += 1
        candidate = "%s_%d" % (base, k)
    used.add(candidate.lower())
    return candidate


def _legacy_obj_exporter():
    try:
        bpy.ops.export_scene.obj.get_rna_type()
        return True
    except (KeyError, AttributeError):
        return False


def export_obj(context, objects, path):
    """Writes `objects` (world space, modifiers applied) to one OBJ with UVs,
    normals and material names, Y up (axes.OBJ_FORWARD / axes.OBJ_UP)."""
    layer = context.view_layer
    selected = [o for o in layer.objects if o.select_get()]
    active = layer.objects.active
    try:
        for o in selected:
            o.select_set(False)
        for o in objects:
            o.select_set(True)
        layer.objects.active = objects[0]
        if _legacy_obj_exporter():        # Blender 3.x: the io_scene_obj add-on
            with contextlib.redirect_stdout(io.StringIO()):    # its progress chatter
                result = bpy.ops.export_scene.obj(
                    filepath=path, check_existing=False, use_selection=True,
                    use_mesh_modifiers=True, use_normals=True, use_uvs=True, use_materials=True,
                    use_triangles=False, axis_forward=axes.OBJ_FORWARD, axis_up=axes.OBJ_UP,
                    global_scale=1.0, path_mode="AUTO")
        else:                             # Blender 4: the C++ exporter
            result = bpy.ops.wm.obj_export(
                filepath=path, check_existing=False, export_selected_objects=True,
                apply_modifiers=True, export_normals=True, export_uv=True,
                export_materials=True, forward_axis=axes.OBJ_FORWARD_ENUM,
                up_axis=axes.OBJ_UP_ENUM, global_scale=1.0)
    finally:
        for o in layer.objects:
            o.select_set(o in selected)
        layer.objects.active = active
    if "FINISHED" not in result or not os.path.isfile(path):
        raise CommandError("Blender's OBJ export of %s failed" % ", ".join(o.name for o in objects))


def world_corners(objects):
    return [o.matrix_world @ Vector(c) for o in objects for c in o.bound_box]


def camera_view(scene, camera, objects, resolution, use_render_resolution):
    """The output camera's <View> (scene axes) for a Blender camera object, and
    notes [(level, text)]. Orthographic: eye = the camera's position (plus its
    shift), target = eye + viewing direction, up = its local Y, width x height
    = ortho_scale over the render's aspect as Blender fits it. Perspective:
    the same position and direction with a frame covering `objects`."""
    render = scene.render
    cam = camera.data
    notes = []
    rot = camera.matrix_world.to_3x3().normalized()
    right = rot.col[0].normalized()
    up = rot.col[1].normalized()
    forward = -rot.col[2].normalized()
    eye = camera.matrix_world.translation.copy()
    aspect = (render.resolution_x * render.pixel_aspect_x) / (
        render.resolution_y * render.pixel_aspect_y)
    corners = world_corners(objects)
    if cam.type == "ORTHO":
        s = cam.ortho_scale
        horizontal = aspect >= 1.0 if cam.sensor_fit == "AUTO" else cam.sensor_fit == "HORIZONTAL"
        width, height = (s, s / aspect) if horizontal else (s * aspect, s)
        eye = eye + right * (cam.shift_x * s) + up * (cam.shift_y * s)
    else:
        notes.append(("WARNING", "perspective camera approximated by an orthographic one "
                                 "(same position and direction, a frame covering the objects)"))
        hw = max(abs((c - eye).dot(right)) for c in corners) * 1.05
        hh = max(abs((c - eye).dot(up)) for c in corners) * 1.05
        if hw < hh * aspect:
            hw = hh * aspect
        else:
            hh = hw / aspect
        width, height = 2.0 * hw, 2.0 * hh
    depths = [(c - eye).dot(forward) for c in corners]
    if min(depths) < 0.0:
        back = -min(depths) + 0.05 * (max(depths) - min(depths)) + 1e-3
        eye = eye - forward * back
        notes.append(("WARNING", "the objects reach behind the camera: the output camera's eye "
                                 "moved %.3g back along its view (same picture)" % back))
        depths = [d + back for d in depths]
    centre = sum(corners, Vector()) / len(corners)
    distance = (centre - eye).dot(forward)
    if not distance > 1e-6:
        distance = 1.0
    target = eye + forward * distance
    if use_render_resolution:
        scale = render.resolution_percentage / 100.0
        px = max(1, int(round(render.resolution_x * scale)))
        py = max(1, int(round(render.resolution_y * scale)))
    elif width >= height:
        px, py = resolution, max(1, int(round(resolution * height / width)))
    else:
        px, py = max(1, int(round(resolution * width / height))), resolution
    view = {"eye": axes.to_scene(eye), "target": axes.to_scene(target), "up": axes.to_scene(up),
            "width": width, "height": height, "resolution": (px, py)}
    return view, notes


def _units(scene):
    settings = scene.unit_settings
    if settings.system == "NONE":
        return []
    for metres, name in _UNITS:
        if math.isclose(settings.scale_length, metres, rel_tol=1e-6):
            return ["--units", name]
    return []


def _tile_file(texture):
    """A pattern matching the tiles tiles="udim" writes for `texture`
    (BASE.1001.exr ...), the tile number its group 1."""
    base = texture[:-4] if texture.endswith(".exr") else texture
    return re.compile(re.escape(base) + r"\.(1[0-9]{3}|2000)\.exr$")


def udim_tiles(folder, texture):
    """[(tile number, path)] of the UDIM tiles of `texture` in `folder`, by
    tile number (BASE.1001.exr ...; frames BASE.1001.0003.exr are not tiles)."""
    pattern = _tile_file(texture)
    found = []
    for name in os.listdir(folder) if os.path.isdir(folder) else []:
        m = pattern.match(name)
        if m and 1001 <= int(m.group(1)) <= 2000:
            found.append((int(m.group(1)), os.path.join(folder, name)))
    return sorted(found)


def remove_tiles(folder, texture):
    """Removes an earlier run's UDIM files of `texture` (the tiles, their
    previews, frames and split channels: BASE.TTTT*), so that Blender, which
    finds a tiled image's tiles on disk, sees only this run's."""
    base = texture[:-4] if texture.endswith(".exr") else texture
    pattern = re.compile(re.escape(base) + r"\.[0-9]{4}[._]")
    for name in os.listdir(folder) if os.path.isdir(folder) else []:
        if pattern.match(name):
            try:
                os.remove(os.path.join(folder, name))
            except OSError:
                pass


def split(program, path):
    """`weathering split FILE`: {channel: path of its single-channel EXR}."""
    folder = os.path.dirname(path)
    stdout, _ = cli.run([program, "split", path], cwd=folder)
    base = os.path.splitext(os.path.basename(path))[0]
    channels = {}
    for line in stdout.splitlines():
        line = line.strip()
        if not line:
            continue
        written = line if os.path.isabs(line) else os.path.join(folder, line)
        name = os.path.splitext(os.path.basename(written))[0]
        if name.startswith(base + "_"):
            name = name[len(base) + 1:]
        channels[name] = written
    if not channels:
        raise CommandError("weathering split %s wrote no file" % path)
    return channels


class Job:
    def __init__(self, context, settings, program):
        self.program_setting = program
        self.preset = settings.preset
        self.particle_count = settings.particle_count
        self.particle_scale = settings.particle_scale
        self.iterations = settings.iterations
        self.resolution = settings.resolution
        self.use_render_resolution = settings.use_render_resolution
        self.full_amount = settings.full_amount
        self.folder = output_folder(settings.output_folder)
        self.out = os.path.join(self.folder, "out")
        self.scene_path = os.path.join(self.folder, "scene.xml")
        self.notes = []
        self.objects = []        # [(object name, mesh file, texture file or None, uv map)]
        self.process = None
        self.started = time.time()
        self.weathered = []

    # --- before the run ----------------------------------------------------

    def prepare(self, context):
        self.program = cli.find_program(bpy.path.abspath(self.program_setting)
                                        if self.program_setting.startswith("//")
                                        else self.program_setting)
        objects = target_objects(context)
        if not objects:
            raise CommandError("no mesh object to weather: select some (or add one)")
        if context.mode != "OBJECT":
            bpy.ops.object.mode_set(mode="OBJECT")
        try:
            os.makedirs(os.path.join(self.folder, "meshes"), exist_ok=True)
            os.makedirs(self.out, exist_ok=True)
        except OSError as e:
            raise CommandError("cannot make the output folder %s: %s" % (self.folder, e.strerror))

        # One OBJ of everything for init (it frames the cameras and the emitter
        # on its bounds), one per object for the run (each its own TextureMap).
        export_obj(context, objects, os.path.join(self.folder, "mesh.obj"))
        used = {"mesh"}
        meshes = []
        for obj in objects:
            name = file_name(obj.name, used)
            rel = "meshes/%s.obj" % name
            export_obj(context, [obj], os.path.join(self.folder, rel))
            uv = obj.data.uv_layers.active
            texture = name + "_texture.exr" if uv is not None and obj.data.polygons else None
            attrs = None
            if texture is None:
                self.notes.append(("INFO", "%s has no UV map: it gets the camera mask only" % obj.name))
            else:
                # How `init` reads this object's UVs alone: tiles="udim" for a
                # UDIM layout, no TextureMap when the layout covers no texel.
                attrs = self.texture_layout(context, rel)
                if attrs is None:
                    self.notes.append(("WARNING", "%s's UV map covers no texel (its faces have no "
                                                  "area in UV): it gets the camera mask only"
                                       % obj.name))
                    texture = None
                remove_tiles(self.out, name + "_texture.exr")
            tiles = attrs.get("tiles", "repeat").strip() if attrs else None
            self.objects.append((obj.name, rel, texture, uv.name if uv is not None else None,
                                 tiles))
            meshes.append((rel, texture, attrs))

        args = [self.program, "init", "mesh.obj", "--preset", self.preset, "-o", "scene.xml",
                "--force", "--resolution", str(self.resolution)] + _units(context.scene)
        cli.run(args, cwd=self.folder)

        tree = scene_xml.load(self.scene_path)
        scene_xml.set_meshes(tree, meshes, self.resolution)
        camera = context.scene.camera
        if camera is not None and camera.type == "CAMERA":
            view, notes = camera_view(context.scene, camera, objects, self.resolution,
                                      self.use_render_resolution)
            scene_xml.set_view(tree, **view)
            self.notes.extend(notes)
            where = "the output camera is %s" % camera.name
        else:
            self.notes.append(("INFO", "no active camera: the output camera is init's "
                                       "three-quarter view"))
            where = "the output camera is init's three-quarter view"
        if self.iterations > 0:
            scene_xml.set_iterations(tree, self.iterations)
        if self.particle_count > 0:
            scene_xml.set_particles(tree, self.particle_count)
        elif self.particle_scale != 1.0:
            scene_xml.scale_particles(tree, self.particle_scale)
        self.particles = scene_xml.particles(tree)
        self.mask_file = scene_xml.output_map_file(tree) or "mask.exr"
        scene_xml.save(tree, self.scene_path,
                       "Edited by Blender's weathering add-on: one <Mesh> per object, %s, "
                       "about %d particles." % (where, round(self.particles)))

    def texture_layout(self, context, rel):
        """The <TextureMap> attributes `weathering init` writes for the mesh
        `rel` alone (resolution, tiles), or None when it writes none."""
        layout = rel[:-4] + ".layout.xml"
        args = [self.program, "init", rel, "--preset", self.preset, "-o", layout, "--force",
                "--resolution", str(self.resolution), "-q"] + _units(context.scene)
        cli.run(args, cwd=self.folder)
        path = os.path.join(self.folder, layout)
        try:
            return scene_xml.texture_map_attributes(scene_xml.load(path))
        finally:
            try:
                os.remove(path)
            except OSError:
                pass

    # --- the run -------------------------------------------------------------

    def start(self, progress):
        self.process = cli.Process([self.program, "run", "scene.xml", "--out", "out"],
                                   cwd=self.folder, log=os.path.join(self.folder, "weathering.log"),
                                   progress=progress)

    # --- after the run -------------------------------------------------------

    def finish(self, context):
        self.process.check()
        mask = None
        mask_path = os.path.join(self.out, self.mask_file)
        if os.path.isfile(mask_path):
            header = exr.read_header(mask_path)
            ndc = exr.matrix(header, "worldToNDC")
            channels = split(self.program, mask_path)
            name = shading.main_channel(self.preset, list(channels))
            if ndc is not None and name is not None:
                mask = (name, shading.load_image(channels[name]), ndc)
        colour = shading.LOOKS.get(self.preset, shading.LOOKS["rain"])[1]

        # A material two weathered objects share gets a copy per object (their
        # textures differ).
        owners = {}
        for name, _, _, _, _ in self.objects:
            obj = bpy.data.objects.get(name)
            if obj is None:
                self.notes.append(("WARNING", "%s disappeared during the run" % name))
                continue
            if not obj.material_slots:
                obj.data.materials.append(None)
            for slot in obj.material_slots:
                if slot.material is None:
                    slot.material = bpy.data.materials.new(obj.name + " weathered")
                    slot.material.use_nodes = True
                elif owners.get(slot.material.name, obj.name) != obj.name:
                    copy = slot.material.copy()
                    copy.name = "%s %s" % (slot.material.name, obj.name)
                    slot.link = "OBJECT"
                    slot.material = copy
                owners.setdefault(slot.material.name, obj.name)

        for name, _, texture, uv_map, tiles in self.objects:
            obj = bpy.data.objects.get(name)
            if obj is None:
                continue
            channels = []
            numbers = []
            if texture is not None and tiles == "udim":
                channels, numbers = self.load_udim(texture)
            elif texture is not None:
                path = os.path.join(self.out, texture)
                if not os.path.isfile(path):
                    raise CommandError("weathering run wrote no %s" % path)
                files = split(self.program, path)
                channels = [(c, shading.load_image(p)) for c, p in sorted(files.items())]
            main = shading.main_channel(self.preset, [c for c, _ in channels])
            source = dict(channels).get(main)
            if source is None and mask is not None:
                main, source = "mask", mask[1]
            if self.full_amount > 0:
                full = self.full_amount
            else:
                full = shading.fully_dirty(source) if source is not None else 1.0
            done = set()
            for slot in obj.material_slots:
                if slot.material is None or slot.material.name in done:
                    continue
                done.add(slot.material.name)
                shading.weather(slot.material, uv_map, channels, main, mask, colour, full)
            self.weathered.append({"object": name, "texture": texture, "channels":
                                   [c for c, _ in channels], "main": main, "full": full,
                                   "tiles": numbers})
        self.notes.append(("INFO", "weathered %d object(s) with %s (%d particles) in %.1f s; "
                                   "files in %s" % (len(self.weathered), self.preset,
                                                    round(self.particles),
                                                    time.time() - self.started, self.folder)))

    def load_udim(self, texture):
        """A tiles="udim" texture: each tile split (BASE.1001_Y.exr ...), each
        channel's tiles one tiled image read through Blender's <UDIM> token
        (BASE.<UDIM>_Y.exr). Returns ([(channel, image)], [tile numbers])."""
        tiles = udim_tiles(self.out, texture)
        if not tiles:
            raise CommandError("weathering run wrote no tile of %s (%s.1001.exr ...) in %s"
                               % (texture, texture[:-4], self.out))
        numbers = [n for n, _ in tiles]
        patterns = {}
        for number, path in tiles:
            for channel, written in split(self.program, path).items():
                folder, base = os.path.split(written)
                tile = ".%d" % number
                at = base.rfind(tile + "_")
                if at < 0:
                    raise CommandError("weathering split %s wrote %s, not a tile's file"
                                       % (path, written))
                patterns[channel] = os.path.join(
                    folder, base[:at] + "." + shading.UDIM + base[at + len(tile):])
        channels = [(c, shading.load_tiles(p, numbers)) for c, p in sorted(patterns.items())]
        return channels, numbers
