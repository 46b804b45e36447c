// maps.h: the four maps of one camera, in memory, in the layout the simulation
// and the gather read (docs/design.md section 2).
//
// Row 0 is the top scanline (EXR order): texel (i, j) is at index j*width + i.
// Depth holds +inf where there is no surface (NaN, d <= 0 and d >= 1e30 in a file
// are turned into +inf on loading).
#ifndef WX_MAPS_H
#define WX_MAPS_H

#include <stdbool.h>

#include "core/error.h"
#include "model/image.h"

typedef struct wx_maps {
    int width;
    int height;
    float *depth;   ///< width*height, d or +inf
    float *normal;  ///< 3*width*height, interleaved x y z, world space, unit
    float *impact;  ///< 2*width*height, interleaved absorption, bounce
    float *dirt;    ///< width*height, dirt amount on the texel's surface patch
    float *deposit; ///< width*height, deposit fraction
    float *erosion; ///< width*height, erosion fraction
    /// What a simulation adds, for the gather (NULL when the dirt map holds no
    /// simulation: a baked or given map): the dirt it started from, and the
    /// impacts that exchanged dirt at each texel.
    float *initial_dirt; ///< width*height
    float *hits;         ///< width*height
    /// The dirt map file's header attributes (camera matrices, name), kept so
    /// that the simulated dirt map is written with them without reading the
    /// file again.
    int dirt_attr_count;
    wx_attr *dirt_attrs;
} wx_maps;

/// Frees every plane; the struct is zeroed.
void wx_maps_free(wx_maps *maps);

/// True when a stored depth value means "no surface" (NaN, <= 0, >= 1e30, inf).
static inline bool wx_depth_is_empty(float d)
{
    return !(d > 0.0f && d < 1e30f);
}

#endif
