"""Weathering: particle-driven dirt, dust, soot, moss, rust and peeling paint
for the selected meshes, computed by the `weathering` command line (docs/blender.md).

View3D > Sidebar > Weathering: a preset, a particle count, a resolution, Run.
bpy.ops.weathering.run() does the same from a script; under `blender -b` it
runs to completion and returns {'FINISHED'} (or {'CANCELLED'} with an error
report)."""

bl_info = {
    "name": "Weathering",
    "author": "weathering project",
    "version": (1, 0, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > Weathering",
    "description": "Particle-driven weathering masks (rain, dust, soot, moss, rust, paint) from the "
                   "weathering command line, loaded back as textures and a camera mask",
    "category": "Material",
}

if "bpy" in locals():                       # F8 / script reload
    import importlib
    for _m in (axes, cli, exr, scene_xml, shading, job):   # noqa: F821
        importlib.reload(_m)

import os
import traceback

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

from . import axes, cli, exr, scene_xml, shading, job

PRESETS = (
    ("rain", "Rain", "Rain slanting in a steady wind: streaks below what sticks out, washed tops"),
    ("dust", "Dust", "Dust settling from still air: tops and ledges gather it"),
    ("soot", "Soot", "Soot on a turbulent breeze: a film on the windward side, some underneath"),
    ("moss", "Moss", "Five rainy spells: moss grows where the water stays, sheltered and shaded"),
    ("rust", "Rust", "Six rainy spells: rust blooms where the water stays, spreading while wet"),
    ("old_paint", "Old paint", "Six rainy spells: paint cracks where the rain beats, peels if wet"),
)


def program_setting(context):
    """The add-on preference `program` when set to anything but its default
    'weathering'; else $WEATHERING_PROGRAM when set (for `blender --addons
    weathering`, which enables the add-on without a preferences entry); else
    'weathering', found on PATH."""
    addon = context.preferences.addons.get(__package__)
    prefs = addon.preferences if addon is not None else None
    program = prefs.program.strip() if prefs is not None else ""
    if program and program != "weathering":
        return program
    return os.environ.get("WEATHERING_PROGRAM") or program or "weathering"


class WeatheringPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    program: StringProperty(
        name="Program", default="weathering", subtype="FILE_PATH",
        description="The weathering command line: a name found on PATH, or an absolute path "
                    "(e.g. /path/to/repository/build/weathering)")

    def draw(self, context):
        self.layout.prop(self, "program")


class WeatheringSettings(bpy.types.PropertyGroup):
    preset: EnumProperty(name="Preset", items=PRESETS, default="rain")
    particle_scale: FloatProperty(
        name="Particles x", default=1.0, min=0.001, soft_max=10.0,
        description="Multiplies the preset's particle count (when Count is 0)")
    particle_count: IntProperty(
        name="Count", default=0, min=0, soft_max=10000000,
        description="Particles over the whole run (all iterations); 0: the preset's count "
                    "times Particles x")
    resolution: IntProperty(
        name="Resolution", default=1024, min=16, max=16384,
        description="Texels across the larger side of the maps: the input cameras, the "
                    "textures and the camera mask")
    use_render_resolution: BoolProperty(
        name="Mask at render size", default=False,
        description="The camera mask takes the render's pixel size instead of Resolution")
    iterations: IntProperty(
        name="Iterations", default=0, min=0, max=100000,
        description="Iterations of the simulation (ageing rules between them); 0: the preset's")
    full_amount: FloatProperty(
        name="Fully dirty at", default=0.0, min=0.0,
        description="Amount per square metre the material shows as fully weathered; 0: the "
                    "95th percentile of the result")
    output_folder: StringProperty(
        name="Folder", default="", subtype="DIR_PATH",
        description="Where the scene, meshes and results go; empty: NAME_weathering next to "
                    "the saved .blend, else a temporary folder")
    status: StringProperty(name="Status", default="")
    last_folder: StringProperty(name="Results", default="")


_running = None      # the operator instance of the run in progress (one at a time)


class WEATHERING_OT_run(bpy.types.Operator):
    """Weather the selected meshes (all meshes when none is selected) with the
    weathering command line and load the results into their materials"""
    bl_idname = "weathering.run"
    bl_label = "Run Weathering"
    bl_options = {"REGISTER"}

    def _report_notes(self, job_):
        for level, text in job_.notes:
            self.report({level}, text)

    def _fail(self, context, message):
        context.scene.weathering.status = "failed: " + message
        self.report({"ERROR"}, message)
        return {"CANCELLED"}

    def _start(self, context, progress):
        settings = context.scene.weathering
        self.job = job.Job(context, settings, program_setting(context))
        self.job.prepare(context)
        self.job.start(progress=progress)
        settings.last_folder = self.job.folder

    def _end(self, context):
        self.job.finish(context)
        self._report_notes(self.job)
        context.scene.weathering.status = "done: %d object(s)" % len(self.job.weathered)
        return {"FINISHED"}

    def execute(self, context):
        """Runs to completion (a script's bpy.ops.weathering.run(), blender -b)."""
        if _running is not None:
            return self._fail(context, "a weathering run is already in progress")
        try:
            self._start(context, progress=False)
            self.job.process.wait()
            return self._end(context)
        except (cli.CommandError, scene_xml.SceneError, ValueError, OSError) as e:
            return self._fail(context, str(e))
        except Exception as e:      # a bug of the add-on: the console has the details
            traceback.print_exc()
            return self._fail(context, "weathering add-on: internal error: %s" % e)

    def invoke(self, context, event):
        """From the panel: runs in the background, the UI stays live (Esc stops it)."""
        global _running
        if bpy.app.background:
            return self.execute(context)
        if _running is not None:
            return self._fail(context, "a weathering run is already in progress")
        try:
            self._start(context, progress=True)
        except (cli.CommandError, scene_xml.SceneError, ValueError, OSError) as e:
            return self._fail(context, str(e))
        except Exception as e:
            traceback.print_exc()
            return self._fail(context, "weathering add-on: internal error: %s" % e)
        _running = self
        self.ticks = 0
        wm = context.window_manager
        wm.progress_begin(0, 100)
        self.timer = wm.event_timer_add(0.2, window=context.window)
        wm.modal_handler_add(self)
        context.scene.weathering.status = "running"
        return {"RUNNING_MODAL"}

    def _stop(self, context):
        global _running
        _running = None
        wm = context.window_manager
        wm.event_timer_remove(self.timer)
        wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)
        for area in context.screen.areas if context.screen else []:
            area.tag_redraw()

    def modal(self, context, event):
        process = self.job.process
        if event.type == "ESC" and event.value == "PRESS":
            process.cancel()
            self._stop(context)
            return self._fail(context, "weathering run stopped (Esc)")
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        status = process.poll()
        if status is None:
            self.ticks += 1
            spinner = "|/-\\"[self.ticks % 4]
            if process.fraction is not None:
                context.window_manager.progress_update(100.0 * process.fraction)
                text = "Weathering: %s (%.0f%% of the run)" % (process.label,
                                                              100.0 * process.fraction)
            else:
                context.window_manager.progress_update(self.ticks % 100)
                text = "Weathering: running %s" % spinner
            context.scene.weathering.status = text[len("Weathering: "):]
            if context.workspace is not None:
                context.workspace.status_text_set(text + "  (Esc: stop)")
            for area in context.screen.areas if context.screen else []:
                if area.type == "VIEW_3D":
                    area.tag_redraw()
            return {"PASS_THROUGH"}
        self._stop(context)
        try:
            return self._end(context)
        except (cli.CommandError, scene_xml.SceneError, ValueError, OSError) as e:
            return self._fail(context, str(e))
        except Exception as e:
            traceback.print_exc()
            return self._fail(context, "weathering add-on: internal error: %s" % e)


class VIEW3D_PT_weathering(bpy.types.Panel):
    bl_label = "Weathering"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Weathering"

    def draw(self, context):
        settings = context.scene.weathering
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(settings, "preset")
        col = layout.column(align=True)
        col.prop(settings, "particle_count")
        row = col.row()
        row.enabled = settings.particle_count == 0
        row.prop(settings, "particle_scale")
        layout.prop(settings, "resolution")
        layout.prop(settings, "use_render_resolution")
        layout.prop(settings, "iterations")
        layout.prop(settings, "full_amount")
        layout.prop(settings, "output_folder")
        selected = [o for o in context.selected_objects if o.type == "MESH"]
        camera = context.scene.camera
        box = layout.box()
        box.label(text="%d selected mesh(es)" % len(selected) if selected
                  else "no mesh selected: all visible meshes", icon="MESH_DATA")
        box.label(text="output camera: %s" % (camera.name if camera else "init's view"),
                  icon="CAMERA_DATA")
        row = layout.row()
        row.scale_y = 1.4
        row.enabled = _running is None
        row.operator(WEATHERING_OT_run.bl_idname, icon="PLAY")
        if settings.status:
            layout.label(text=settings.status)
        if settings.last_folder:
            layout.label(text=settings.last_folder, icon="FILE_FOLDER")


classes = (WeatheringPreferences, WeatheringSettings, WEATHERING_OT_run, VIEW3D_PT_weathering)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.weathering = bpy.props.PointerProperty(type=WeatheringSettings)


def unregister():
    if _running is not None:            # a run in progress: stop the program
        _running.job.process.cancel()
    del bpy.types.Scene.weathering
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
