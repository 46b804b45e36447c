// bake_phase.h: the `bake` phase: the scene's meshes imported and matched, the
// <View> cameras without map files rendered (raster/bake.c), and their maps
// written into the output folder: <camera>_depth.exr, <camera>_normal.exr and,
// for input cameras, <camera>_impact.exr and <camera>_dirt.exr, each with the
// camera's "WTCMatrix", "CTWMatrix" (m44f, row-major) and "cameraName" in its
// header. The cameras' map paths then point at those files.
#ifndef WX_BAKE_PHASE_H
#define WX_BAKE_PHASE_H

#include "core/error.h"
#include "model/geometry.h"
#include "model/scene.h"
#include "pipeline/pipeline.h"
#include "raster/bake.h"

/// Imports every mesh of `scene` and matches each of its materials to a
/// <Surface> (the one naming it, else "*"). WX_BAD_INPUT "scene:LINE: ..." for
/// a camera to bake in a scene without meshes (WX_CAUSE_MISSING), for
/// a mesh that cannot be imported, a material no <Surface> matches, or a
/// <Surface vertexColors> on a material without colours; a mesh without
/// triangles is a warning (unless quiet). On failure `out` is left empty.
wx_result wx_geometry_load(const wx_scene *scene, bool quiet, wx_geometry *out, wx_error *err);

/// Warns (unless quiet) about the input cameras to bake that would record no
/// surface: the meshes' triangles cover less than one texel of their frames
/// (the meshes are edge-on to them, such as a mesh with no thickness along an
/// axis, every vertex at z = 0, seen from the side). A point in such a
/// camera's frame never lies behind a surface it records, so the collider
/// lets every particle through there (docs/physics.md): the run would be all
/// zero. Names each mesh without thickness along an axis. `what` begins the
/// message (the scene file, or the mesh for `init`). Returns the number of
/// such cameras.
int wx_geometry_warn_blind(const wx_scene *scene, const wx_geometry *geometry, const char *what,
                           bool quiet);

/// Renders with the geometry already imported (wx_geometry_load), handing each
/// baked camera's maps to `on_maps` (raster/bake.h) instead of writing them:
/// what the pilot of `info` flies on. `stats` may be NULL.
wx_result wx_bake_geometry_into(const wx_scene *scene, const wx_run_def *opts,
                                wx_geometry *geometry, wx_bake_maps_fn *on_maps, void *user,
                                wx_bake_stats *stats, wx_error *err);

/// Bakes with the geometry already imported (wx_geometry_load);
/// its mesh arrays are released as they are uploaded. When `output_maps` is not
/// NULL and the output camera is baked, its depth and normal are kept there
/// too (the gather of the same run reads them instead of the files). When
/// `kept` is not NULL (4 images per scene camera, zeroed), each baked input
/// camera's images (depth, normal, impact, dirt), as written to its files, are
/// moved there for the simulation of the same run (wx_load_simulation_maps);
/// the caller frees them with wx_image_free. `stats` may be NULL.
wx_result wx_bake_geometry(wx_scene *scene, const wx_run_def *opts, wx_geometry *geometry,
                           wx_maps *output_maps, wx_image *kept, wx_bake_stats *stats,
                           wx_error *err);

/// The whole phase: imports the geometry when some camera is baked, then
/// wx_bake_geometry. `stats` may be NULL.
wx_result wx_bake_scene_stats(wx_scene *scene, const wx_run_def *opts, wx_bake_stats *stats,
                              wx_error *err);

/// wx_bake_scene_stats without the statistics.
wx_result wx_bake_scene(wx_scene *scene, const wx_run_def *opts, wx_error *err);

#endif
