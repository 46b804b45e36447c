// load.h: what the simulation and the gather read from files before they
// compute: the input cameras' maps.
#ifndef WX_LOAD_H
#define WX_LOAD_H

#include "core/error.h"
#include "gather/gather.h"
#include "model/maps.h"
#include "model/scene.h"
#include "pipeline/pipeline.h"

/// Loads the maps of every input camera (scene order; `maps` has
/// scene->input_count entries) as the simulation reads them: depth, normal,
/// impact and, when the camera has one, its dirt map (from the channel
/// initialDirt when an earlier `simulate` wrote it, so a second run starts
/// where the first started). Errors name the camera and the file. `baked`
/// (NULL: read every file) holds 4 images per scene camera that this run's
/// bake kept (wx_bake_geometry): a camera with them is read from them, not
/// from its files (the same maps), and they are freed once it is loaded.
wx_result wx_load_simulation_maps(const wx_scene *scene, int threads, wx_image *baked,
                                  wx_maps *maps, wx_error *err);

/// Loads the maps of every input camera as the gather reads them: depth,
/// normal, and the dirt `simulate` left in the output folder
/// (<camera>_dirt.exr); without it the camera's scene dirt map, with a note.
/// A dirt map that holds only the baked initial dirt (never simulated) is used
/// with a note too.
wx_result wx_load_gather_maps(const wx_scene *scene, const wx_run_def *opts, wx_maps *maps,
                              wx_error *err);

/// The scene and maps as the gather reads them (docs/design.md section 14):
/// every layer of an input camera is an input camera of its own, with the
/// camera's matrices and a view of that layer's planes (wx_maps_layer_view),
/// in the scene's order, layer 0 first. The cameras array is new when some
/// camera has layers (its strings are borrowed from `scene`); the maps are
/// shallow copies whose `owned` planes (the share of each texel's surface each
/// view owns, model/ownership.h) are computed here once for every gather of
/// the frame, on `threads` workers.
typedef struct wx_layer_scene {
    wx_scene scene;
    wx_maps *maps;
    bool own_cameras; ///< the cameras array is this struct's
    float *owned;     ///< the views' owned planes, one after the other
    /// Per layered camera, its depth planes with the buried crossings made
    /// +inf (wx_maps_bury), which its views read.
    float *buried[WX_MAX_INPUT_CAMERAS];
    int buried_count;
} wx_layer_scene;

/// Points views[0..count) (made by wx_gather_view_from_maps) at substance
/// `substance`'s amount and baseline planes of in_maps (model/maps.h: S planes
/// one after the other), for one gather of that substance.
void wx_gather_views_of_substance(wx_gather_view *views, const wx_maps *in_maps, int count,
                                  int substance);

wx_result wx_layer_scene_init(const wx_scene *scene, const wx_maps *maps, int threads,
                              wx_layer_scene *out, wx_error *err);
void wx_layer_scene_free(wx_layer_scene *layered);

#endif
