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

/// What every target of one frame shares: the collider over the input cameras
/// and Height's default range.
typedef struct wx_mask_context {
    bool ready;
    wx_collider collider;
    float *zero_impact; ///< the collider's impact planes (unused here), zeros
    float height_min, height_max;
} wx_mask_context;

/// Builds the context from the input cameras' maps (depth and normal), when the
/// scene has masks (else leaves it not ready). Height's default range is the
/// geometry's bounds when the run imported it (scene->has_bounds), else the y
/// range of the surfaces the input cameras record.
wx_result wx_mask_context_init(const wx_scene *scene, const wx_maps *in_maps,
                               wx_mask_context *ctx, wx_error *err);

void wx_mask_context_free(wx_mask_context *ctx);

/// The masks at a grid of points (sim/masks.h), `substances` their values of
/// the scene's substances: out[m] per mask.
wx_result wx_masks_at_points(const wx_scene *scene, const wx_run_def *opts,
                             const wx_mask_context *ctx, const wx_mask_points *points,
                             const float *const *substances, float *const *out, wx_error *err);

/// The masks at the texels of a camera's depth and normal maps (the output
/// camera's: the mask's surface points).
wx_result wx_masks_at_camera(const wx_scene *scene, const wx_run_def *opts,
                             const wx_mask_context *ctx, const wx_camera *camera,
                             const wx_maps *maps, const float *const *substances,
                             float *const *out, wx_error *err);

#endif
