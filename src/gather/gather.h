// gather.h: the output mask (docs/design.md section 5, thesis 4.8.4.4 improved).
//
// First pass: every output texel with a surface is turned into its world point,
// projected into every input camera, and takes that camera's dirt where the
// camera sees the same point (depth agreement, same side of the surface),
// converted to dirt per square metre of surface and summed over the cameras.
// Second pass: a weighted mean over output texels within `radius` world units,
// weight max(0, Nq.Np) * (1 - r/radius), so it never smooths across creases or
// depth jumps. docs/mask.md describes the file and every choice made here.
#ifndef WX_GATHER_H
#define WX_GATHER_H

#include <stdbool.h>
#include <stdio.h>
#include <stdint.h>

#include "core/error.h"
#include "gather/adaptive.h"
#include "gather/target.h"
#include "model/camera.h"
#include "model/maps.h"
#include "model/scene.h"
#include "model/stats.h"

/// |N.view| is clamped to at least this when the footprint of an input texel on
/// the surface (head-on texel area / |N.view|) is computed. It must equal the
/// clamp `bake` uses when it stores density x area / |N.view| (bake.c
/// MIN_COSINE), so that initial dirt density survives the round trip exactly.
#define WX_GATHER_AREA_MIN_COS 1e-3f

/// Depth tolerance of the visibility test: this many texels of the input camera,
/// divided by max(|N.view|, WX_GATHER_TOL_MIN_COS) of the input texel.
#define WX_GATHER_DEPTH_TOL_TEXELS 1.5f
#define WX_GATHER_TOL_MIN_COS 0.1f

/// How the first pass reads an input camera's dirt.
typedef enum wx_gather_sampling {
    WX_GATHER_BILINEAR, ///< the four texels around the point, each tested, renormalised (default)
    WX_GATHER_NEAREST,  ///< the one texel the point falls in (the thesis)
} wx_gather_sampling;

/// One camera's maps as the gather reads them: views into memory the caller
/// owns. Row 0 is the top, texel (i, j) at j*width + i (maps.h).
typedef struct wx_gather_view {
    const wx_camera *camera; ///< orthographic matrices (the map size is taken from width/height)
    int width;
    int height;
    const float *depth;  ///< width*height; +inf, NaN, <= 0 or >= 1e30: no surface
    const float *normal; ///< 3*width*height, interleaved, world-space unit normals
    const float *dirt;   ///< width*height dirt amounts (input cameras; unused for the output)
    /// What a simulation adds (both NULL for a dirt map no simulation wrote: its
    /// dirt is then exact, never smoothed by the adaptive pass): the dirt it
    /// started from and the impacts at each texel (maps.h).
    const float *initial;
    const float *hits;
    /// The share of each texel's surface this camera owns (model/ownership.h),
    /// input cameras only; NULL: wx_gather_compute works it out itself.
    const float *owned;
    /// A layer of a layered camera (model/maps.h `outward`): its normals point
    /// out of the solid, so ownership reads them (model/ownership.h).
    bool outward;
    /// A layer view's texels' other crossings, as baked (model/maps.h
    /// crossing_depth...): a point nearer one of those is not this view's.
    const float *crossing_depth, *crossing_normal;
    int crossing_layers, crossing_layer;
} wx_gather_view;

/// The share of each texel's surface every input camera owns
/// (wx_owned_fraction of model/ownership.h), for the views whose `owned` is
/// NULL: one malloc'd block, the planes of those views one after the other in
/// their order (*owned NULL when every view has its own). The caller frees it.
wx_result wx_gather_owned(const wx_gather_view *views, int count, int threads, float **owned,
                          wx_error *err);

/// Everything the gather needs, in memory. Zero-initialise or start from
/// wx_default_gather_def(), then fill the views.
typedef struct wx_gather_def {
    wx_target target;             ///< where the mask is evaluated: the output camera's texels
    const wx_gather_view *inputs; ///< input cameras with their dirt
    int input_count;
    float radius;                 ///< second-pass radius in world units; 0 = no second pass
    /// Instead of the radius: smoothing that follows the density of impacts
    /// (gather/adaptive.h), aiming at relative noise `noise` within max_radius.
    bool adaptive;
    float noise;
    float max_radius;
    wx_second_pass second_pass;   ///< weighted mean (default) or the thesis' weighted sum
    bool normalize;               ///< divide the final mask by its maximum (when > 0)
    wx_gather_sampling sampling;
    int threads;                  ///< worker threads; <= 1 runs on the calling thread only
    bool quiet;                   ///< no progress bar
} wx_gather_def;

/// What a gather found.
typedef struct wx_gather_stats {
    int64_t surface_texels; ///< output texels with a surface
    int64_t dirty_texels;   ///< output texels whose final value is > 0
    double max_value;       ///< largest mask value before normalisation
    double first_pass_s;    ///< wall-clock seconds of the first pass
    double second_pass_s;   ///< wall-clock seconds of the second pass
    /// Adaptive smoothing only: the impacts aimed at, the median and the largest
    /// radius given (world units), and the texels with some impact within
    /// max_radius but fewer than K (their noise stays above the aim).
    double target_hits;
    double median_radius;
    double largest_radius;
    int64_t capped_texels;
    /// The noise the capped texels keep, their median (relative standard
    /// deviation; 0 when none is capped), and counted by bins (adaptive.h).
    double capped_noise;
    int64_t capped_noise_bins[WX_NOISE_BINS];
} wx_gather_stats;

/// The --stats figures (model/stats.h) of an output named `file`, smoothed
/// adaptively at noise `aim`, from its gather's stats.
static inline wx_noise_figures wx_gather_noise_figures(const char *file, double aim,
                                                       const wx_gather_stats *st)
{
    wx_noise_figures f = { .aim = aim,
                           .target_hits = st->target_hits,
                           .surface_texels = st->surface_texels,
                           .capped_texels = st->capped_texels,
                           .capped_noise = st->capped_noise };
    snprintf(f.file, sizeof f.file, "%s", file);
    return f;
}

/// The rows mapping a point into the texel space of an input camera (texel
/// centres at integers, row 0 at the top): x = cx . (p, 1), y = cy . (p, 1),
/// depth = cd . (p, 1), p in world space, or in the space `from` maps to world
/// (row vectors: [p 1] * from = [world 1]; NULL: p is a world point). `wtc` is
/// the camera's affine world-to-map matrix (wx_matrix_to_affine).
void wx_gather_view_rows(const wx_gather_view *view, const double wtc[16], const double from[16],
                         double cx[4], double cy[4], double cd[4]);

/// The frame of an input camera as the first pass uses it: the unit viewing
/// direction, the visibility test's depth tolerance (WX_GATHER_DEPTH_TOL_TEXELS
/// times the texel's larger side) and the area of a texel seen head-on. False
/// when the camera is not orthographic or its frame is degenerate.
bool wx_gather_view_frame(const wx_gather_view *view, float ray[3], float *tol_world,
                          double *head_area);

/// Defaults: no cameras, radius 0, weighted mean, bilinear, 1 thread, quiet.
wx_gather_def wx_default_gather_def(void);

/// A view of a camera and its loaded maps (the dirt plane may be NULL).
wx_gather_view wx_gather_view_from_maps(const wx_camera *camera, const wx_maps *maps);

/// The neighbourhood of the second pass of `radius` over `target` (only its
/// camera and size are read: depth and normal may be NULL), for checking a scene
/// before any work: `texels` gets the output texels around each texel it visits.
/// WX_BAD_VALUE (WX_CAUSE_BAD_VALUE) when that is over the limit the gather takes.
wx_result wx_gather_check_radius(const wx_target *target, float radius, int *texels,
                                 wx_error *err);

/// Computes the mask into mask_out (target width*height floats, row 0 = top; 0
/// where the target has no surface). stats may be NULL. Fails with
/// WX_BAD_INPUT on a missing map, a size mismatch, a camera that is not
/// orthographic or a bad radius; WX_FAIL when out of memory.
wx_result wx_gather_compute(const wx_gather_def *def, float *mask_out, wx_gather_stats *stats,
                            wx_error *err);

/// OpenEXR's worldToNDC of a camera: [x y z 1] * M = [u, 1 - v, d, 1].
void wx_mask_world_to_ndc(const wx_camera *camera, float m[16]);

/// OpenEXR's worldToCamera of a camera: [x y z 1] * M = [(u - 0.5) * width_ws,
/// (v - 0.5) * height_ws, d, 1] (left-handed, origin at the centre of the eye plane).
void wx_mask_world_to_camera(const wx_camera *camera, float m[16]);

#endif
