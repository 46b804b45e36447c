// world.h: what the viewer shows, without any GL: a loaded scene, its maps, the
// simulation running on them (the library's wx_sim, as on the command line), and
// the static geometry drawn around it (camera frames, depth samples, emitters,
// bounding box) as coloured vertex lists ready to upload.
//
// A world is built in two halves so that a reload can bake in the background:
// vw_world_parse reads the scene file, vw_world_finish (after any bake) loads
// the maps and creates the simulation. The old world runs until the new one is
// complete; a broken file never replaces it.
//
// Its functions live by concept: world_load.c (parsing, maps, simulation,
// freeing), world_stale.c (when to bake), world_geometry.c (the vertex lists),
// world_layers.c, world_colors.c (substances, deposits, ramps), world_masks.c
// and world_save.c (G); world_internal.h is what they share.
#ifndef VW_WORLD_H
#define VW_WORLD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "model/maps.h"
#include "pipeline/masks_phase.h"
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

/// Where a depth sample lies in its camera's maps, for its deposits.
typedef struct vw_sample {
    /// Its view (input camera and layer: the index of its dirt map in the
    /// simulation, wx_sim_dirt_map), -1: output camera.
    int input;
    int texel;   ///< j * width + i, in its layer
    int layer;   ///< its layer of its camera's maps (0: the first surface the rays meet)
    /// Its normal shading times its layer's (vw_layer_shade): drawn in its
    /// camera's colour times this.
    float shade;
} vw_sample;

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
    /// Scene camera index -> its first view in the simulation (its layer 0;
    /// layer k is view first_view[c] + k), -1 for the output camera. Views go
    /// camera by camera, layer 0 first, as wx_sim_camera_views gives them.
    int *first_view;
    /// The most layers of any camera's maps (docs/design.md section 14; 1: no
    /// camera is layered).
    int max_layers;
    wx_sim *sim;
    /// The substance shown (docs/design.md section 9): particles are coloured
    /// by their load of it, depth samples (with <Substances>) by its amount on
    /// their surface. An index into scene.substances.
    int substance;
    float load_scale;        ///< load of it drawn in full colour (its largest emitter load)

    vw_vertex *lines;        ///< GL_LINES pairs
    int line_count;
    vw_vertex *points;       ///< depth samples
    vw_sample *samples;      ///< per depth sample: its texel
    int point_count;
    vw_range *camera_lines;  ///< per scene camera: frame and viewing direction
    vw_range *camera_points; ///< per scene camera: its depth samples, every layer's
    /// Per scene camera c and layer k below its layers: the depth samples of
    /// that layer, at c * WX_MAX_LAYERS + k (runs of camera_points[c], layer 0
    /// first; vw_world_layer_points).
    vw_range *layer_points;
    vw_range emitter_lines;
    vw_range bbox_lines;
    float frame_lo[3];       ///< box around the camera frames (the initial view)
    float frame_hi[3];
    int sample_stride;       ///< depth samples are every stride-th texel, from stride / 2

    /// The derived mask shown on the depth samples (docs/design.md section
    /// 12), an index into scene.masks; -1: none (the samples' own colours).
    int mask;
    /// Per mask once computed (vw_world_compute_mask): its value at every
    /// depth sample, NaN where the sample's texel has no normal.
    float *mask_values[WX_MAX_MASKS];
    /// Per computed mask: the value drawn at the end of the ramp, 1, or for
    /// Curvature the 99th percentile of |value| over the samples.
    float mask_scale[WX_MAX_MASKS];
    /// The collider over the input cameras' maps, built with the first mask
    /// computed (NULL until then).
    wx_mask_context *mask_context;
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

/// Steps of the whole simulation: the scene's steps times its iterations.
int64_t vw_world_total_steps(const vw_world *world);

/// True when the simulation has run the scene's number of steps in every
/// iteration (docs/design.md section 9).
bool vw_world_finished(const vw_world *world);

/// Writes <camera>_dirt.exr for every input camera and, when the scene has an
/// output camera, gathers the mask from the simulation in memory
/// (wx_gather_simulation: the bytes a gather of those files writes); `saved`
/// receives the mask's path (or the output folder when there is no output
/// camera).
wx_result vw_world_gather(vw_world *world, char saved[WX_PATH_MAX], wx_error *err);

/// Layers of scene camera c's maps (1: not layered).
int vw_world_camera_layers(const vw_world *world, int c);

/// The depth samples of scene camera c shown with `layer` (-1: every layer's,
/// else that layer's; none when the camera has fewer layers).
vw_range vw_world_layer_points(const vw_world *world, int c, int layer);

/// What L shows next (docs/viewer.md): every layer (-1) -> layer 0 -> 1 ->
/// ... -> the deepest of any camera (max_layers - 1) -> every layer; always
/// -1 when no camera is layered.
int vw_world_next_layer(const vw_world *world, int layer);

/// The scene camera of view `view` of the world's simulation (a hit's
/// wx_hit_sample.camera), its layer in *layer (may be NULL); -1 when `view`
/// is no view (a hit on the bounding box or the ground).
int vw_world_view_camera(const vw_world *world, int view, int *layer);

/// Substances of the scene (1 without <Substances>).
int vw_world_substance_count(const vw_world *world);

/// Shows substance s (taken modulo the count): the particles' colour and
/// load_scale, the largest load of s over the emitters; when no emitter
/// carries s (it is only picked up from surfaces), the largest load of any
/// substance, else 1.
void vw_world_show_substance(vw_world *world, int s);

/// Shows the next substance, after the last the first again; returns it.
int vw_world_next_substance(vw_world *world);

/// After a reload: shows the substance of that name if the new scene has one,
/// else the first.
void vw_world_keep_substance(vw_world *world, const char *name);

/// Index of the substance called `name`, or -1.
int vw_world_find_substance(const vw_world *world, const char *name);

/// Name of the shown substance.
const char *vw_world_substance_name(const vw_world *world);

/// Colour of substance s (palette.h), 0..1 per channel.
void vw_world_substance_color(const vw_world *world, int s, float out[3]);

/// True when the depth samples show deposits: scenes with <Substances> (a
/// scene without keeps version 1's look, its samples in their camera's colour).
bool vw_world_shows_deposits(const vw_world *world);

/// Load of the shown substance carried by particle i of a view of the
/// world's simulation (the view holds one load per substance per particle).
static inline double vw_particle_load(const vw_world *world, const wx_particle_view *view,
                                      int64_t i)
{
    int64_t S = world->scene.substance_count > 1 ? world->scene.substance_count : 1;
    return view->load[i * S + world->substance];
}

/// Amount of the shown substance on the surface of depth sample `point` now,
/// or -1 for a sample of the output camera (it has no dirt map).
double vw_world_deposit(const vw_world *world, int point);

/// Depth samples show the amount at this quantile of the non-zero amounts
/// among those drawn, and above, in full colour: surface amounts are
/// heavy-tailed (a few texels where streaks end hold a hundred times the
/// typical amount), so the largest would leave the rest unseen.
#define VW_DEPOSIT_QUANTILE 0.95

/// The amount of the shown substance drawn in full colour on depth samples
/// picked[0..n): VW_DEPOSIT_QUANTILE of their non-zero amounts, 0 when there
/// is none. `scratch` holds n floats.
float vw_world_deposit_scale(const vw_world *world, const uint32_t *picked, size_t n,
                             float *scratch);

/// Copies depth samples picked[0..n) into out, coloured by the deposits of the
/// shown substance: from their camera's shaded colour towards the substance's
/// shaded colour by sqrt(amount / vw_world_deposit_scale), at most 1;
/// output-camera samples and surfaces without any keep their colour.
/// `scratch` holds n floats.
void vw_world_deposit_colors(const vw_world *world, const uint32_t *picked, size_t n,
                             float *scratch, vw_vertex *out);

/// Derived masks (<Masks>, docs/design.md section 12) on the depth samples.
/// A mask is computed once per world (per set of maps) at the samples' own
/// points: for each camera, the grid of its sampled texels (every
/// sample_stride-th texel; its own maps' depth and normal) is evaluated with
/// the library's wx_masks_at_points (the same as wx_masks_at_camera when the
/// stride is 1), with occlusion through the collider over the input cameras'
/// maps, opts' seed and threads. Differences from the mask a gather writes:
/// - Combine terms on substances read 0 (the viewer has no per-square-metre
///   substances before a gather);
/// - Height without min/max spans the y range of the surfaces the input
///   cameras record (the viewer imports no geometry);
/// - Curvature without a radius takes 4 texels of the camera's map, or twice
///   the samples' spacing when they are more than 2 texels apart.
int vw_world_mask_count(const vw_world *world);

/// Index of the mask called `name`, or -1.
int vw_world_find_mask(const vw_world *world, const char *name);

/// What M shows next: -1 (none) -> 0 -> 1 -> ... -> the last -> -1; -1 when
/// the scene has no masks.
int vw_world_next_mask(const vw_world *world);

/// The kind of mask m in words ("accessibility", "exposure", "curvature",
/// "height", "combine").
const char *vw_world_mask_kind_name(const vw_world *world, int m);

/// True when mask m's values at the samples are known (-1: always).
bool vw_world_mask_ready(const vw_world *world, int m);

/// Computes mask m at every depth sample (and the masks it combines, kept
/// too), unless known: may take seconds (accessibility's rays).
wx_result vw_world_compute_mask(vw_world *world, int m, wx_error *err);

/// Shows mask m (-1: none), computing it first when needed; on failure the
/// shown mask is unchanged.
wx_result vw_world_show_mask(vw_world *world, int m, wx_error *err);

/// After a reload: shows the mask of that name if the new scene has one (it
/// is computed), else none.
wx_result vw_world_keep_mask(vw_world *world, const char *name, wx_error *err);

/// Value of the shown mask at depth sample `point` (NaN: none shown, or no value).
float vw_world_mask_value(const vw_world *world, int point);

/// The ramp of the shown mask (palette.h): for a mask in [0, 1],
/// VW_MASK_RAMP from 0 to 1 (values clamped); for Curvature,
/// VW_CURVATURE_RAMP from -mask_scale (concave) through 0 to +mask_scale
/// (convex), clamped.
void vw_world_mask_color(const vw_world *world, float value, float out[3]);

/// Copies depth samples picked[0..n) into out coloured by the shown mask
/// (unshaded: equal values look equal); a sample without a value keeps its
/// colour.
void vw_world_mask_colors(const vw_world *world, const uint32_t *picked, size_t n,
                          vw_vertex *out);

/// Frees everything; the struct is zeroed.
void vw_world_free(vw_world *world);

// Used by the world's files and by tests/test_viewer.c.

/// The geometry with at most `max_samples` depth samples (VW_MAX_DEPTH_SAMPLES;
/// tests take fewer to see a stride).
wx_result vw_world_build_geometry_within(vw_world *world, int64_t max_samples, wx_error *err);

/// The scale of a mask's ramp: 1, or for Curvature the 99th percentile of
/// |value| over the samples (their largest when that is 0; 1 when all are flat).
float vw_world_mask_scale(const vw_world *world, int m, const float *values);

#endif
