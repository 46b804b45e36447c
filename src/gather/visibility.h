// visibility.h: the test by which a texel of an input camera's map vouches for
// a surface point (docs/mask.md, "First pass"): the texel's depth agrees with
// the point's depth in that camera, and its normal with the point's. Shared by
// the mask's first pass (gather.c) and the texture's sampling (texture.c), so
// that both outputs judge visibility alike.
#ifndef WX_VISIBILITY_H
#define WX_VISIBILITY_H

#include <math.h>

#include "model/maps.h"

// Normals at right angles (a crease) give weight 0 even when rounding (or a
// fused multiply-add) leaves their dot product a few ulps above 0.
#define WX_VISIBILITY_NORMAL_EPSILON 1e-6f

// Relative depth epsilon added to the visibility tolerance (float rounding of d).
#define WX_VISIBILITY_DEPTH_EPSILON_REL 1e-5f

/// The agreement N . N_texel (> 0) when the input texel of depth `depth` and
/// unit normal nt, in a camera looking along unit `ray` with depth tolerance
/// tol_world (world units, head-on), sees the point at depth dp with unit
/// normal n; 0 when it does not. *cos_view gets |N_texel . ray|.
static inline float wx_visible_agreement(float depth, const float nt[3], const float ray[3],
                                         float tol_world, float min_cos, float dp,
                                         const float n[3], float *cos_view)
{
    if (wx_depth_is_empty(depth)) {
        return 0.0f;
    }
    float c = fabsf(nt[0] * ray[0] + nt[1] * ray[1] + nt[2] * ray[2]);
    // Across a texel the depth of a surface at slope theta changes by texel *
    // tan(theta), so the tolerance is tol_world / max(|N.view|, min_cos) (times
    // cos_tol here).
    float cos_tol = c > min_cos ? c : min_cos;
    float epsilon = WX_VISIBILITY_DEPTH_EPSILON_REL * (1.0f + fabsf(depth));
    if (!(fabsf(dp - depth) * cos_tol <= tol_world + epsilon * cos_tol)) {
        return 0.0f;
    }
    // Same side of the surface and not across a crease.
    float agree = n[0] * nt[0] + n[1] * nt[1] + n[2] * nt[2];
    if (!(agree > WX_VISIBILITY_NORMAL_EPSILON)) {
        return 0.0f;
    }
    *cos_view = c;
    return agree;
}

#endif
