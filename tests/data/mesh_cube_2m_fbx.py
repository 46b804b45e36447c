# Makes tests/data/mesh_cube_2m.fbx and mesh_cube_2m_units.fbx (tests/test_mesh.c):
# a 2 m cube centred at Blender (1, 2, 3), exported with the FBX exporter's
# defaults (centimetres: UnitScaleFactor 1, the object scaled by 100) and with
# "Apply Scalings: FBX Units Scale" (metres: UnitScaleFactor 100, scale 1).
# The exporter's axes (forward -Z, up Y) put Blender (x, y, z) at (x, z, -y),
# so both must import with bounds x 0..2, y 2..4, z -3..-1 (metres).
#   blender -b --factory-startup --python tests/data/mesh_cube_2m_fbx.py -- tests/data
import os
import sys

import bpy

out_dir = sys.argv[sys.argv.index("--") + 1]
bpy.ops.object.select_all(action="SELECT")
bpy.ops.object.delete()
bpy.ops.mesh.primitive_cube_add(size=2.0, location=(1.0, 2.0, 3.0))
bpy.ops.export_scene.fbx(filepath=os.path.join(out_dir, "mesh_cube_2m.fbx"))
bpy.ops.export_scene.fbx(filepath=os.path.join(out_dir, "mesh_cube_2m_units.fbx"),
                         apply_scale_options="FBX_SCALE_UNITS")
