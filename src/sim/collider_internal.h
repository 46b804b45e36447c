// collider_internal.h: what the files of the projected-maps collider share
// (collider_build.c builds it, collider.c holds the point rule and the swept
// test, collider_coarse.c the coarse test). Private to src/sim/.
#ifndef WX_COLLIDER_INTERNAL_H
#define WX_COLLIDER_INTERNAL_H

#include "sim/collider.h"

// What crossing k of a texel bounds, in a camera with layered maps (docs/physics.md,
// "Layered maps"), once the crossings are reduced to the outline of the solids
// (classify_layers):
//  - ENTER: it enters a solid that crossing k + 1 (LEAVE) leaves: [d_k, d_k+1];
//  - SHEET: one-sided (a crossing no other one closes: a pane, an open sheet),
//    a slab `sheet` thick on the inner side of its normal (sheet_start);
//  - TAIL: solid from d_k on: what lies behind the last layer is unknown when
//    every layer holds a crossing.
// The FACING bit is set where the crossing enters (n . view <= 0).
enum {
    WX_ROLE_NONE = WX_OUTLINE_NONE,
    WX_ROLE_ENTER = WX_OUTLINE_ENTER,
    WX_ROLE_LEAVE = WX_OUTLINE_LEAVE,
    WX_ROLE_SHEET = WX_OUTLINE_SHEET,
    WX_ROLE_TAIL = WX_OUTLINE_TAIL,
    WX_ROLE_KIND = 7,
    WX_ROLE_FACING = 8,
    /// A fill (collider_fill.c): solid where the camera missed a surface
    /// another camera records; no surface of its own, it gives a hit only
    /// where every camera that agrees holds a fill (pick_camera).
    WX_ROLE_FILL = 16,
};

/// Adds the fills every camera needs where it sees a surface edge-on and says
/// "not behind" inside it (collider_fill.c); axes[c] is camera c's unit axis
/// towards it. Runs once, after the crossings are widened and before the
/// coarse pyramids are built from them.
wx_result wx_collider_fill_missed(wx_collider *collider, const double (*axes)[3], wx_error *err);

#endif
