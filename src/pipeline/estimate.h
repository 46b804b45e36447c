// estimate.h: what `weathering info` tells of a scene before any run, from
// the layers that know it: the particles an emitter sends, the rays the
// derived masks cast, a texture's coverage on a small raster. The memory a run
// needs is memory.h's; the pilot's share of particles that miss, pilot.h's.
#ifndef WX_ESTIMATE_H
#define WX_ESTIMATE_H

#include <stdint.h>

#include "core/error.h"
#include "model/mesh.h"
#include "model/scene.h"

/// The particles emitter `e` of the scene sends in one iteration (each
/// iteration emits again): its count at the end of the simulated time.
int64_t wx_emitter_particles(const wx_scene *scene, int e);

/// The rays the derived masks cast at most: each mask's rays a point
/// (sim/masks.h) at every target texel, the mask's and every texture's, which
/// `points` gets.
double wx_masks_rays(const wx_scene *scene, double *points);

/// A texture's coverage estimated on a raster of at most 1024 texels a side
/// (the padding scaled with it), for one of its files.
typedef struct wx_texture_coverage {
    int width, height;          ///< the raster's size
    int64_t covered;            ///< texels with a triangle
    int64_t overlapping;        ///< covered texels inside more than one triangle
    int64_t padded;             ///< texels that take a neighbour's values
    int64_t triangles_outside;  ///< triangles reaching outside the tile(s) (exact)
    int64_t triangles_unusable; ///< triangles without usable UVs
} wx_texture_coverage;

/// The coverage of TextureMap `t` over `mesh` (imported with its UV channel)
/// in UDIM tile `udim` (0 for a texture without tiles). An error when the
/// raster cannot be built (the mesh lacks the channel, out of memory).
wx_result wx_texture_coverage_estimate(const wx_texture_map *t, const wx_mesh_data *mesh, int udim,
                                       wx_texture_coverage *out, wx_error *err);

#endif
