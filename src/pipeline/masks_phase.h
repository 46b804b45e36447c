// masks_phase.h: the derived masks of a scene (docs/design.md section 12,
// docs/masks.md) at the output camera's texels and at a TextureMap's: the
// collider built from the input cameras' maps in memory, the surface points
// made from the target, sim/masks.c run over them.
#ifndef WX_MASKS_PHASE_H
#define WX_MASKS_PHASE_H

#include <stdbool.h>

#include "core/error.h"
#include "model/camera.h"
#include "model/maps.h"
#include "model/scene.h"
#include "pipeline/pipeline.h"
#include "sim/collider.h"
#include "sim/masks.h"

/// What every target shares, in one frame or over every frame of a run: the
/// collider over the input cameras, Height's default range, and the masks that
/// depend on the geometry alone as the first frame computed them.
typedef struct wx_mask_context {
    bool ready;
    wx_collider collider;
    float *zero_impact; ///< the collider's impact planes (unused here), zeros
    float height_min, height_max;
    /// When kept (the run gathers several frames): known[slot * mask_count + m],
    /// geometric mask m (wx_mask_is_geometric) at the points of target `slot`
    /// (WX_MASK_SLOT_OUTPUT, wx_mask_slot_texture) once computed, else NULL.
    float **known;
    int slots, mask_count;
    /// Per mask, for each Noise mask: its remap table (sim/noise.h), built
    /// once from the scene's surface sample (scene->surface_sample) or, without
    /// one, from the input cameras' surface texels weighted by their area.
    double *noise_tables[WX_MAX_MASKS];
    /// The frame being gathered: i after iteration i, 0 for the final mask
    /// (what <Term age> reads: i / iterations, 1 for the final mask).
    int frame;
} wx_mask_context;

/// The targets a context keeps masks for: the output camera, then each file of
/// each TextureMap (one, or one per UDIM tile: wx_texture_file_count).
#define WX_MASK_SLOT_OUTPUT 0

/// The slot of file f of TextureMap t.
int wx_mask_slot_texture(const wx_scene *scene, int t, int f);

/// Builds the context from the input cameras' maps (depth and normal), when the
/// scene has masks, or a TextureMap and a layered camera (its collider tells
/// the faces the layers hold but nothing reaches: wx_masks_unsee_enclosed);
/// else leaves it not ready. Height's default range is the
/// geometry's bounds when the run imported it (scene->has_bounds), else the y
/// range of the surfaces the input cameras record. With `keep`, the context
/// keeps the geometric masks of each target after their first computation and
/// copies them in later frames (same values: they read only the depth and
/// normal maps, which a simulation leaves alone); the maps must outlive it.
wx_result wx_mask_context_init(const wx_scene *scene, const wx_maps *in_maps, bool keep,
                               wx_mask_context *ctx, wx_error *err);

/// Whether a run of `scene` gathers more than its final frame (an `every` of the
/// mask or of a TextureMap that some iteration before the last meets): a
/// context kept over the frames saves the geometric masks' rays.
bool wx_masks_worth_keeping(const wx_scene *scene);

void wx_mask_context_free(wx_mask_context *ctx);

/// The masks at a grid of points (sim/masks.h), the points of target `slot`
/// (-1, or a context that keeps nothing: none kept), `substances` their values
/// of the scene's substances: out[m] per mask.
wx_result wx_masks_at_points(const wx_scene *scene, const wx_run_def *opts, wx_mask_context *ctx,
                             int slot, const wx_mask_points *points,
                             const float *const *substances, float *const *out, wx_error *err);

/// The masks at the texels of a camera's depth and normal maps (the output
/// camera's, slot WX_MASK_SLOT_OUTPUT: the mask's surface points).
wx_result wx_masks_at_camera(const wx_scene *scene, const wx_run_def *opts, wx_mask_context *ctx,
                             int slot, const wx_camera *camera, const wx_maps *maps,
                             const float *const *substances, float *const *out, wx_error *err);

#endif
