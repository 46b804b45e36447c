// maps.h: the four maps of one camera, in memory, in the layout the simulation
// and the gather read (DESIGN section 2).
//
// Row 0 is the top scanline (EXR order): texel (i, j) is at index j*width + i.
// Depth holds +inf where there is no surface (NaN, d <= 0 and d >= 1e30 in a file
// are turned into +inf on loading).
#ifndef WX_MAPS_H
#define WX_MAPS_H

#include <stdbool.h>

#include "error.h"
#include "exr_io.h"

typedef struct wx_maps {
    int width;
    int height;
    float *depth;   ///< width*height, d or +inf
    float *normal;  ///< 3*width*height, interleaved x y z, world space, unit
    float *impact;  ///< 2*width*height, interleaved absorption, bounce
    float *dirt;    ///< width*height, dirt amount on the texel's surface patch
    float *deposit; ///< width*height, deposit fraction
    float *erosion; ///< width*height, erosion fraction
    /// The dirt map file's header attributes (camera matrices, name), kept so
    /// that the simulated dirt map is written with them without reading the
    /// file again.
    int dirt_attr_count;
    wx_attr *dirt_attrs;
} wx_maps;

/// Which maps to load.
enum {
    WX_MAPS_DEPTH = 1 << 0,
    WX_MAPS_NORMAL = 1 << 1,
    WX_MAPS_IMPACT = 1 << 2,
    WX_MAPS_DIRT = 1 << 3,
    WX_MAPS_ALL = 15,
    /// With WX_MAPS_DIRT: read the dirt plane from channel "initialDirt" when the
    /// file has it (a dirt map written by `simulate`), else from R.
    WX_MAPS_INITIAL_DIRT = 1 << 4,
};

/// Name of the channel in which a simulated dirt map keeps its initial dirt.
#define WX_INITIAL_DIRT_CHANNEL "initialDirt"

/// Loads the maps selected by `which` from the given paths (NULL or "" for a map
/// not wanted). Depth reads channel R or Z, normal R G B, impact R G, dirt R G B.
/// All loaded maps must have the same size; a mismatch names both files.
wx_result wx_maps_load(wx_maps *maps, unsigned which, const char *depth_path,
                       const char *normal_path, const char *impact_path,
                       const char *dirt_path, wx_error *err);

/// Frees every plane; the struct is zeroed.
void wx_maps_free(wx_maps *maps);

/// True when a stored depth value means "no surface" (NaN, <= 0, >= 1e30, inf).
static inline bool wx_depth_is_empty(float d)
{
    return !(d > 0.0f && d < 1e30f);
}

#endif
