// masks.h: the derived masks of docs/design.md section 12 (docs/masks.md):
// accessibility, sun exposure with real shadows, curvature, height and
// Riihiaho's sigmoid combinations, evaluated at the surface points of a target
// (the output camera's texels, a TextureMap's texels).
//
// Accessibility and exposure march rays through the projected-maps collider
// (collider.h), the very geometry the particles hit: a ray from a point
// starts just off the surface (on the ray, within one of the collider's finest
// texels: the lowest of 1/8, 1/4, 1/2 texel up that the collider says is free,
// so that a surface never shadows itself, a crease stays dark and a shadow's
// edge stays put), and is cut into segments of doubling length, each
// cleared by the collider's coarse pyramid when it can be and swept otherwise.
// Directions are stratified per point (a Hammersley set rotated by a hash of
// the seed, the mask and the point), so the result is the same for any thread
// count and 32-64 rays give a smooth mask without a second pass.
// Accessibility goes coarse to fine over the grid of points: every fourth
// point of every fourth row first, and a point between four that lie on its
// surface and agree within 1/16 takes their interpolation without a ray
// (masks.c, REFINE_STRIDE), so the open expanses cost a sixteenth of their rays.
#ifndef WX_MASKS_H
#define WX_MASKS_H

#include <stdbool.h>
#include <stdint.h>

#include "core/error.h"
#include "model/scene.h"
#include "sim/collider.h"

/// Where the masks are evaluated: a width x height grid of surface points
/// (texel (i, j) at j*width + i), views into memory the caller owns.
typedef struct wx_mask_points {
    int width, height;
    const double *position;      ///< 3 per point, world
    const float *normal;         ///< 3 per point, unit, facing out of the surface
    const unsigned char *valid;  ///< 1 where a point is evaluated; the others get 0
    /// The grid's texel size in world units: what Curvature's default radius
    /// (4 texels) and its neighbourhood in the grid are measured in.
    float texel;
} wx_mask_points;

/// Everything the masks need.
typedef struct wx_masks_def {
    const wx_scene *scene;        ///< the masks (in order), the bounding box
    const wx_collider *collider;  ///< the input cameras' maps; NULL: no occluder anywhere
    wx_mask_points points;
    /// The substances' values at the points (per square metre), one plane per
    /// substance of the scene: what a Combine's substance terms read.
    const float *const *substances;
    float height_min, height_max; ///< Height's range where a mask does not give it
    /// Optional (NULL: every mask computed): known[m], when not NULL, holds mask
    /// m's values at these very points (an earlier frame's, for a mask
    /// wx_mask_is_geometric says depends on the geometry alone); they are
    /// copied instead of computed.
    const float *const *known;
    /// Per mask, for each Noise mask: its remap table (WX_NOISE_TABLE_SIZE
    /// quantiles, sim/noise.h), the same for every target; NULL entries (or
    /// NULL): the identity of [-1, 1].
    const double *const *noise_tables;
    /// What a Combine's <Term age="w"> reads, times w: i / iterations for the
    /// frame written after iteration i, 1 for the final mask.
    double age;
    uint64_t seed;
    int threads;
    bool quiet; ///< no progress bar
} wx_masks_def;

/// Fills out[m] (width*height floats) for every mask m of the scene, in order
/// (a Combine reads the masks before it). WX_FAIL when out of memory.
wx_result wx_masks_compute(const wx_masks_def *def, float *const *out, wx_error *err);

/// Whether mask m depends on the geometry alone (every kind but a Combine; a
/// Combine when none of its terms, through the masks it names, reads a
/// substance or the age): its values at a set of points are the same in every
/// frame.
bool wx_mask_is_geometric(const wx_scene *scene, int m);

/// Clears seen[t] (width*height of `points`, 1 where a layer of some camera
/// holds the point) where the surface is enclosed: the collider's point rule
/// puts every start a ray from it would take along its normal (1/8, 1/4, 1/2
/// and 1 of the collider's finest texel up) inside a solid, as for a face
/// buried in another solid or sealed against one, which no particle or ray
/// reaches (docs/texture.md, "seen"). Reads points' position and normal. Only
/// with a layered camera: one layer records no face behind another.
void wx_masks_unsee_enclosed(const wx_collider *collider, const wx_mask_points *points, float *seen,
                             int threads);

/// Riihiaho's sigmoid (his eq. 3.7): (x - o) / (2 sqrt(1/s + (x - o)^2)) + 1/2
/// for steepness s > 0; x itself for s = 0.
double wx_sigmoid(double x, double offset, double steepness);

/// The unit direction of a sun at elevation e and azimuth a (degrees; azimuth
/// from +X towards +Z): (cos e cos a, sin e, cos e sin a).
void wx_sun_direction(double elevation, double azimuth, double out[3]);

/// Rays a mask marches per point (0 for the masks that march none): for the
/// cost estimate of `info`.
int wx_mask_rays(const wx_mask_def *mask);

#endif
