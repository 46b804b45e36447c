// world_internal.h: what the files of the viewer's world (world_*.c) share
// beyond world.h: the geometry's builder, the selection the deposits' and the
// masks' scales use, and the palette's bytes as floats.
#ifndef VW_WORLD_INTERNAL_H
#define VW_WORLD_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "world.h"

/// Builds the world's static geometry (world_geometry.c) with at most
/// VW_MAX_DEPTH_SAMPLES depth samples.
wx_result vw_world_build_geometry(vw_world *world, wx_error *err);

/// The k-th smallest of a[0..n) (0-based, n > 0; a is reordered): Hoare's
/// selection (world_masks.c; the deposits' scale takes it too).
float vw_select_kth(float *a, size_t n, size_t k);

/// A colour of palette.h as floats, 0..1 per channel.
static inline void vw_to_float_color(const uint8_t rgb[3], float out[3])
{
    for (int k = 0; k < 3; ++k) {
        out[k] = (float)rgb[k] / 255.0f;
    }
}

#endif
