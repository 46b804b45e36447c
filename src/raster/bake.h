// bake.h: renders the maps of <View> cameras from the scene's meshes, offscreen
// with OSMesa (GL 4.5 core, llvmpipe), replacing the thesis' Mental Ray passes
// (thesis 4.9.2). Everything stays in memory: each camera's maps are handed to
// the caller (pipeline/bake_phase.c writes them), and the depth maps of cameras
// the scene gives as files come from the caller too.
//
// Every camera given by <View> without map files gets a depth map (R = d, +inf
// where no surface), a normal map (R,G,B = world unit normal facing the
// camera), and, for input cameras, an impact map (R absorption, G bounce, B 0)
// and a dirt map (R dirt, G deposit, B erosion). Initial dirt (docs/design.md
// section 3) is stored once: each texel of the input camera that sees its
// surface patch most head-on holds density x texel area / |N.view|, the others
// 0 (docs/cameras.md describes the visibility test).
//
// Layers (docs/design.md section 14): an input camera with `layers` K > 1 is
// drawn K times, depth peeling: layer 0 is the nearest crossing of each texel
// centre's view ray with any triangle, front- or back-facing; layer k the next
// one after layer k-1's in the order of a key: d, plus 2e-5 x (1 + |d|) for a
// crossing that enters a solid, the next key larger by more than 1e-5 x (1 +
// |d|). Surfaces 1 mm apart at 50 m are two layers; where two solids touch (a
// post on a floor) the ray leaves one and enters the other at one d, and both
// crossings stay, the leaving one first; one surface met twice is one. Its normals are then the mesh's own, out of
// the solid (with one layer they face the camera, as version 2's). A texel
// with no crossing left holds the background (+inf, 0). Every map holds layer
// 0's channels, then layer 1's named "layer1.R"..., and so on (wx_layer_channel);
// every (input camera, layer) is a view of the initial-dirt ownership, a
// layered camera's views reading its outward normals. The output camera has
// one layer whatever it asks.
//
// Cost: a layered camera costs one draw of every mesh and one readback per
// layer (the layers after the first with no crossing are not drawn), plus a
// copy of the layer before into a texture (16 bytes a texel, in GL) and, for
// the initial dirt, its outward normals interleaved (12 bytes a texel a
// layer); the images handed to on_maps are K times today's. When the
// visibility test keeps every input camera's depth, a layered camera's K depth
// planes and K normal planes are kept too (16 bytes a texel a layer).
#ifndef WX_BAKE_H
#define WX_BAKE_H

#include <stdbool.h>
#include <stdint.h>

#include "core/error.h"
#include "model/geometry.h"
#include "model/image.h"
#include "model/maps.h"
#include "model/scene.h"

/// What a bake did and how long it took (wall-clock seconds).
typedef struct wx_bake_stats {
    int cameras;            ///< cameras baked
    int64_t triangles;      ///< triangles drawn per camera (all meshes)
    int64_t vertices;
    double import_s;        ///< Assimp import and flattening, all meshes
    double setup_s;         ///< GL context, shaders, uploads
    double render_s;        ///< draws and readback, all cameras
    double dirt_s;          ///< initial dirt ownership (visibility between cameras)
    double write_s;         ///< in the caller's on_maps (writing the files; a run's input
                            ///< cameras only hand theirs to a writer thread)
    double cameras_s;       ///< all cameras: render, dirt and on_maps, wall-clock
    double total_s;
} wx_bake_stats;

/// Receives the maps of baked scene camera `camera`: maps[0] depth (R),
/// maps[1] normal (R G B) and, for an input camera, maps[2] impact (R G B) and
/// maps[3] dirt (R G B); count 2 or 4. A layered camera's images hold each
/// layer's channels after the layer before's ("layer1.R" ...). The images are
/// the bake's (valid during the call; the caller may add header attributes).
typedef wx_result wx_bake_maps_fn(int camera, wx_image *maps, int count, void *user,
                                  wx_error *err);

/// What a bake renders, and for whom. Start from wx_default_bake_def().
typedef struct wx_bake_def {
    const wx_scene *scene;    ///< cameras with a <View> and no map files are baked
    wx_geometry *geometry;    ///< meshes matched to surfaces; their arrays are released as uploaded
    /// Per scene camera, the depth map of a camera whose maps the scene gives
    /// (the initial-dirt visibility test needs every input camera's depth when
    /// some surface starts with dirt), or NULL when no such camera is needed.
    const wx_maps *given_depth;
    int threads;              ///< worker threads (the initial dirt's visibility test)
    bool quiet;               ///< no progress bar, no warnings
    wx_bake_maps_fn *on_maps; ///< called once per baked camera, in scene order
    void *user;
} wx_bake_def;

/// Defaults: no scene, one thread, quiet.
wx_bake_def wx_default_bake_def(void);

/// Bakes every camera of def->scene that has a <View> and no map files; does
/// nothing when there is none. def->geometry holds every mesh of the scene,
/// imported (wx_geometry_load refuses a scene with cameras to bake and no mesh).
/// WX_BAD_INPUT (message with file and line) for no triangles or maps larger
/// than the renderer allows; WX_FAIL for GL failures or out of memory; or what on_maps
/// returns. Warnings (geometry outside a frame or behind an eye) go to stderr
/// unless quiet. `stats` may be NULL.
wx_result wx_bake_render(const wx_bake_def *def, wx_bake_stats *stats, wx_error *err);

#endif
