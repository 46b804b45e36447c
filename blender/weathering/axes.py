"""Blender's axes and the scene's: the one place where they meet.

Blender is Z-up; a weathering scene (docs/design.md section 2) is Y-up, with
gravity along -Y. The add-on converts in exactly one way, here:

    scene (x, y, z) = (X, Z, -Y)        of Blender's (X, Y, Z)
    Blender (X, Y, Z) = (x, -z, y)      of the scene's (x, y, z)

It is a rotation of -90 degrees about X (determinant +1), so it maps points
and directions alike and keeps cross products: a camera's right = forward x up
in Blender stays right = forward x up in the scene. It is what Blender's OBJ
exporter does with forward '-Z' and up 'Y' (OBJ_FORWARD, OBJ_UP: the file is
Y-up), and what its importer undoes with its default axes, so the exported
meshes and the output camera (converted with to_scene) land in the same world.
"""

# The OBJ exporter's axis settings that give to_scene (bpy.ops.export_scene.obj
# axis_forward / axis_up; bpy.ops.wm.obj_export forward_axis / up_axis).
OBJ_FORWARD = "-Z"
OBJ_UP = "Y"
OBJ_FORWARD_ENUM = "NEGATIVE_Z"   # the same, spelled for bpy.ops.wm.obj_export
OBJ_UP_ENUM = "Y"


def to_scene(v):
    """A Blender point or direction (X, Y, Z) as the scene's (x, y, z) = (X, Z, -Y)."""
    return (float(v[0]), float(v[2]), -float(v[1]))


def to_blender(v):
    """A scene point or direction (x, y, z) as Blender's (X, Y, Z) = (x, -z, y)."""
    return (float(v[0]), -float(v[2]), float(v[1]))
