// bake.h: renders the maps of <View> cameras from the scene's meshes, offscreen
// with OSMesa (GL 4.5 core, llvmpipe), replacing the thesis' Mental Ray passes
// (thesis 4.9.2).
//
// Every camera given by <View> without map files gets, in the output folder,
// <name>_depth.exr (R = d, +inf where no surface), <name>_normal.exr (R,G,B =
// world unit normal facing the camera), and, for input cameras,
// <name>_impact.exr (R absorption, G bounce, B 0) and <name>_dirt.exr (R dirt,
// G deposit, B erosion). Each file's header carries the camera's "WTCMatrix",
// "CTWMatrix" (m44f, row-major) and "cameraName". Initial dirt (DESIGN section
// 3) is stored once: each texel of the input camera that sees its surface patch
// most head-on holds density x texel area / |N.view|, the others 0 (see
// docs/cameras.md for the visibility test).
#ifndef WX_BAKE_H
#define WX_BAKE_H

#include <stdint.h>

#include "error.h"
#include "geometry.h"
#include "pipeline.h"
#include "scene.h"

/// What a bake did and how long it took (wall-clock seconds).
typedef struct wx_bake_stats {
    int cameras;            ///< cameras baked
    int64_t triangles;      ///< triangles drawn per camera (all meshes)
    int64_t vertices;
    double import_s;        ///< Assimp import and flattening, all meshes
    double setup_s;         ///< GL context, shaders, uploads
    double render_s;        ///< draws and readback, all cameras
    double dirt_s;          ///< initial dirt ownership (visibility between cameras)
    double write_s;         ///< waiting for EXR writing (what rendering did not hide)
    double cameras_s;       ///< all cameras: render, dirt and writing, wall-clock
    double total_s;
} wx_bake_stats;

/// Bakes every camera that has a <View> and no map files in the scene (depth_path
/// is ""), then points the camera's *_path fields at the written files. Does
/// nothing when no camera needs baking. WX_BAD_INPUT (message with file and
/// line) for a missing or unsupported mesh, a material no <Surface> matches,
/// maps larger than the renderer allows, or cameras to bake and no geometry;
/// WX_FAIL for GL or I/O failures. Warnings (geometry outside a frame or behind
/// an eye) go to stderr unless opts->quiet.
wx_result wx_bake_scene(wx_scene *scene, const wx_run_options *opts, wx_error *err);

/// wx_bake_scene with the scene's geometry already imported and matched
/// (wx_geometry_load); its mesh arrays are released as they are uploaded.
wx_result wx_bake_geometry(wx_scene *scene, const wx_run_options *opts, wx_geometry *geometry,
                           wx_bake_stats *stats, wx_error *err);

/// wx_bake_scene, also filling `stats` (may be NULL).
wx_result wx_bake_scene_stats(wx_scene *scene, const wx_run_options *opts,
                              wx_bake_stats *stats, wx_error *err);

#endif
