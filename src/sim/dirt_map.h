// dirt_map.h: the dirt on the surface seen by one input camera, and the
// exchange of dirt between particles and surface (thesis 3.5, 4.8.4.3,
// docs/design.md section 4).
//
// Surface dirt is kept in double precision during the simulation so that the
// ledger (initial surface + emitted = final surface + in flight + escaped)
// holds to rounding of doubles; the written map is float32 (a relative rounding
// of at most 2^-24 per texel).
#ifndef WX_DIRT_MAP_H
#define WX_DIRT_MAP_H

#include <stdint.h>

#include "model/camera.h"
#include "core/error.h"

/// One texel: its dirt and its exchange rates, already scaled by the collider's
/// deposit D and erosion E and clamped to [0, 1].
typedef struct wx_dirt_texel {
    double dirt;
    float deposit; ///< clamp(D * kd, 0, 1)
    float erosion; ///< clamp(E * ke, 0, 1)
    /// The share of the texel's dirt one contact meets: |N . view| of its
    /// surface (in [1e-3, 1]; 1 without normals). The texel holds the dirt of
    /// texel area / |N . view| of surface, and a particle's contact meets the
    /// dirt of a head-on texel's area of it, so erosion takes
    /// erosion * contact * dirt (docs/physics.md, "Dirt exchange").
    float contact;
    /// The particles that exchanged here, each counted by the share of itself
    /// it spent here (its weight, wx_particles.weight: a particle counts once
    /// over all its hits): what the gather's adaptive smoothing counts as its
    /// independent samples (docs/mask.md).
    float hits;
} wx_dirt_texel;

/// The substances of a map (docs/design.md section 9): texel t's substance s is
/// texels[t * substances + s]; `hits` is counted in substance 0's entry only.
/// With one substance the layout is version 1's.
typedef struct wx_dirt_map {
    int width;
    int height;
    int substances;        ///< 1..WX_MAX_SUBSTANCES
    wx_dirt_texel *texels; ///< W*H*substances, row 0 at the top
    const float *depth;    ///< W*H (borrowed): streaks skip texels without surface
} wx_dirt_map;

/// Builds the map from the planes of `substances` substances, each plane
/// W*H floats one after the other (plane s at s*W*H; any of the three may be
/// NULL: zeros), and the collider's D and E. `depth` (borrowed, may be NULL)
/// marks the texels with a surface (finite depth). `normal` (3*W*H, may be
/// NULL: every contact 1) and `view` (the camera's unit axis, either sense)
/// give each texel's contact, |N . view|. Fails with WX_FAIL when out of
/// memory.
wx_result wx_dirt_map_init(wx_dirt_map *map, int width, int height, int substances,
                           const float *dirt, const float *deposit, const float *erosion,
                           float D, float E, const float *depth, const float *normal,
                           const float view[3], wx_error *err);

/// Frees the texels; the struct is zeroed.
void wx_dirt_map_free(wx_dirt_map *map);

/// Sum of substance s over every texel, in texel order.
double wx_dirt_map_total(const wx_dirt_map *map, int s);

/// One impact at `texel`, for every substance s with load[s]: dep =
/// deposit*p, ero = erosion*s, then p += ero - dep, s += dep - ero (thesis
/// 4.8.4.3, as pinned in docs/design.md section 4). The particle spends the
/// share f of its weight (*weight, in [0, 1]) that the texel's strongest
/// exchange rate gives (f = the largest deposit or erosion rate over the
/// substances): the texel's hits grow by f * weight, and weight shrinks by as
/// much.
void wx_dirt_map_exchange(wx_dirt_map *map, uint32_t texel, double *load, float *weight);

/// A slide that follows a slide: the same exchange spread evenly over the
/// surface texels of the Bresenham line from `from` to `to`, without `from` (it
/// took its share at the previous hit): each of the n texels exchanges with
/// dep_k = deposit_k*p/n and ero_k = erosion_k*s_k/n, p being the load on
/// arrival, for every substance, and takes f_k * weight / n of the particle's
/// weight. With no surface texel on the line, a plain exchange at `to`.
void wx_dirt_map_exchange_line(wx_dirt_map *map, uint32_t from, uint32_t to, double *load,
                               float *weight);

/// Deposits all of every substance's load at `texel` (absorbed and settled
/// particles), and the rest of the particle's weight.
void wx_dirt_map_deposit_all(wx_dirt_map *map, uint32_t texel, double *load, float *weight);

#endif
