// world.h: what the viewer shows, without any GL: a loaded scene, its maps, the
// simulation running on them (the library's wx_sim, as on the command line), and
// the static geometry drawn around it (camera frames, depth samples, emitters,
// bounding box) as coloured vertex lists ready to upload.
//
// A world is built in two halves so that a reload can bake in the background:
// vw_world_parse reads the scene file, vw_world_finish (after any bake) loads
// the maps and creates the simulation. The old world runs until the new one is
// complete; a broken file never replaces it.
#ifndef VW_WORLD_H
#define VW_WORLD_H

#include <stdbool.h>
#include <stdint.h>

#include "core/error.h"
#include "model/maps.h"
#include "pipeline/pipeline.h"
#include "model/scene.h"
#include "sim/simulate.h"
#include "core/limits.h"

/// Depth samples drawn over all cameras, at most (thesis 4.8.5: "some samples").
#define VW_MAX_DEPTH_SAMPLES 250000

/// A coloured vertex of the static geometry.
typedef struct vw_vertex {
    float position[3];
    float color[3];
} vw_vertex;

/// A run of vertices in one of the world's vertex lists.
typedef struct vw_range {
    int first;
    int count;
} vw_range;

/// Settings that survive reloads (the command line's).
typedef struct vw_settings {
    const char *scene_path;
    const char *out_dir;   ///< NULL: out/<scene name>/
    int threads;           ///< simulation threads, 0 = one per core
    int hit_capacity;      ///< recent hits kept for drawing
} vw_settings;

typedef struct vw_world {
    wx_scene scene;
    wx_run_def opts;
    /// Maps per camera: the scene's input cameras first, in scene order (the
    /// simulation borrows these), then the output camera (depth, normal).
    wx_maps *maps;
    int *camera_maps;        ///< scene camera index -> index into maps
    int *input_camera;       ///< input index -> scene camera index
    wx_sim *sim;
    float load_scale;        ///< particle load drawn fully dirty (largest emitter dirt)

    vw_vertex *lines;        ///< GL_LINES pairs
    int line_count;
    vw_vertex *points;       ///< depth samples
    int point_count;
    vw_range *camera_lines;  ///< per scene camera: frame and viewing direction
    vw_range *camera_points; ///< per scene camera: its depth samples
    vw_range emitter_lines;
    vw_range bbox_lines;
    float frame_lo[3];       ///< box around the camera frames (the initial view)
    float frame_hi[3];
} vw_world;

/// Reads and validates the scene file and sets the run options (output folder,
/// threads). On failure the world is empty and err names the file (and line).
wx_result vw_world_parse(vw_world *world, const vw_settings *settings, wx_error *err);

/// True when `weathering bake` must run before vw_world_finish: some <View>
/// camera of the parsed scene has no maps in the output folder yet; or, on the
/// first load (running == NULL), its maps are older than the scene file or a
/// mesh; or, on a reload, the cameras or the geometry differ from the running
/// world's, a mesh changed, or the running world's gather rewrote the baked
/// <camera>_dirt.exr files (the simulated dirt must not become the next run's
/// initial dirt).
bool vw_world_needs_bake(const vw_world *world, const vw_world *running);

/// Points baked cameras at their maps, loads every map, builds the geometry and
/// creates the simulation at time 0.
wx_result vw_world_finish(vw_world *world, const vw_settings *settings, wx_error *err);

/// Creates the simulation again at time 0 (same maps); on failure the running
/// one is kept.
wx_result vw_world_restart(vw_world *world, const vw_settings *settings, wx_error *err);

/// True when the simulation has run the scene's number of steps.
bool vw_world_finished(const vw_world *world);

/// Writes <camera>_dirt.exr for every input camera and, when the scene has an
/// output camera, gathers the mask; `saved` receives the mask's path (or the
/// output folder when there is no output camera).
wx_result vw_world_gather(vw_world *world, char saved[WX_PATH_MAX], wx_error *err);

/// Frees everything; the struct is zeroed.
void vw_world_free(vw_world *world);

#endif
