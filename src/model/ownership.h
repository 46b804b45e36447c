// ownership.h: which input camera a surface point belongs to. Every deposit,
// every initial amount and every hit is stored once, in the map of the camera
// that sees its point most head-on (docs/design.md sections 3 and 4); the
// simulation's collider (sim/collider.c), the bake's initial dirt
// (raster/bake.c) and the gather's first pass (gather/gather.c) must agree on
// that camera, or a band of surface along the border between two cameras'
// parts is counted twice or not at all (the seams of docs/mask.md). This is
// the rule, in one place.
//
// A texel at that border is owned in part: the gather divides what it holds by
// the share of its surface it owns (wx_owned_fraction), so the border leaves
// no seam whichever way the cameras' texel grids cross it.
#ifndef WX_OWNERSHIP_H
#define WX_OWNERSHIP_H

#include <stdbool.h>
#include <stddef.h>

#include "core/error.h"
#include "model/camera.h"

/// An input camera's depth map as the rule reads it.
typedef struct wx_owner_view {
    const wx_camera *camera;
    const float *depth; ///< width*height; empty texels as model/maps.h says
    int width, height;
    float view[3];  ///< unit viewing direction
    float texel_ws; ///< the larger side of a texel, world units
    /// A layer of a layered camera (docs/design.md section 14): its outward
    /// normals (3*width*height interleaved), so a surface facing away from the
    /// camera is seen by the layer that holds it, and the side of a thin plate
    /// is told by the normal rather than by the viewing direction. NULL (what
    /// wx_owner_view_init sets): a one-layer map, whose surfaces face the view.
    const float *normal;
} wx_owner_view;

/// Fills a view (the viewing direction and texel size from the camera).
void wx_owner_view_init(wx_owner_view *view, const wx_camera *camera, const float *depth,
                        int width, int height);

/// Whether `view` sees the world point p of a surface with unit normal n: the
/// surface faces the view (n . view <= 0; for a layer, n agrees in side with
/// the normal the layer records at p's texel), p projects into its frame onto a
/// texel with a surface, and both that texel's
/// depth and the depth between texel centres (bilinear where the four texels
/// around p hold a surface) agree with p's within half a texel plus one
/// texel's worth of the surface's slope in this view (the collider's rule; for
/// a layer, the slope of the surface it records there, else of n).
bool wx_owner_sees(const wx_owner_view *view, const double p[3], const float n[3]);

/// The view that owns p: of the views that see it, the one that sees it most
/// head-on (largest |N . view|, N read for a layer as the normal it records at
/// p's texel, as the collider's pick_camera reads each camera, else n; a
/// layer sees p to the precision of the surface it records there), ties
/// within 1e-4 to a view outside the
/// surface (a layer whose camera n faces, n . view < 0, over one that sees it
/// through the solid: two cameras facing each other always tie), then to the
/// one listed first; -1
/// when no view sees it. `known` (-1: none) is a view known to see p (its
/// test is skipped).
int wx_owner_of(const wx_owner_view *views, int count, const double p[3], const float n[3],
                int known);

/// The share of each texel of view c's surface that view c owns, in [0, 1]
/// (0 where the texel has no surface), into out[width*height]: the texel's
/// centre decides, and a texel whose neighbours are not all decided alike is
/// cut into 4 x 4 points, each decided on its own. Those points lie on the
/// surface only to view c's precision (its tolerance at the texel), so another
/// view sees one when its surface lies within that of it, or within its own
/// tolerance when that is larger; a point view c would not see itself (its
/// depth between neighbours that hold other surfaces) takes the centre's
/// verdict. Normals are read as
/// nx[t*stride] ... (interleaved: stride 3; planes: stride 1). Rows are shared
/// among `threads` workers; the result does not depend on their number.
/// WX_FAIL when out of memory.
wx_result wx_owned_fraction(const wx_owner_view *views, int count, int c, const float *nx,
                            const float *ny, const float *nz, size_t stride, int threads,
                            float *out, wx_error *err);

#endif
