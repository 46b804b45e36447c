// texture.h: the gather's second kind of target, a mesh's UV layout
// (docs/design.md section 11, docs/texture.md).
//
// The UV raster says which triangle covers each texel of a W x H texture
// (texel (i, j) has its centre at u = (i + 1/2)/W, v = 1 - (j + 1/2)/H; a
// texel is covered when its centre lies inside a triangle, edges shared by two
// triangles going to exactly one of them) and, for the texels within `padding`
// of a covered one, which covered texel is nearest (island bleed). Each covered
// texel stands for its triangle's surface point at the texel centre, world
// position and normal interpolated.
//
// Its values are sampled, not gathered again: for every input camera the mask
// is first computed on that camera's own texels (wx_gather_compute with the
// camera as target: the same first pass and the same smoothing, in world space
// along the surface that camera records), and each texel's surface point then
// reads those planes through the first pass's visibility test. A point on
// either side of a UV seam reads the same planes at the same place, so the
// texture has no seam; a point no input camera sees is not `seen`.
#ifndef WX_TEXTURE_H
#define WX_TEXTURE_H

#include <stdbool.h>
#include <stdint.h>

#include "core/error.h"
#include "gather/gather.h"
#include "model/mesh.h"

/// A triangle whose UVs span a box of more UV tiles than this is unusable
/// (counted, never drawn): read with REPEAT it would fold onto the texture
/// that many times over. It also bounds the work a triangle costs, whatever
/// its UVs (1e30 spans 1e30 tiles).
#define WX_UV_MAX_TILES_PER_TRIANGLE 64

/// What a UV raster draws: UV channel `uv` of `mesh` (which must hold it, with
/// positions, normals and indices) read as `tiles` says (docs/texture.md, "UVs
/// outside [0,1]"): REPEAT draws every triangle at each whole-tile offset
/// whose tile it overlaps, clipped to [0,1]^2; CLIP only the [0,1]^2 tile;
/// UDIM the tile `udim` (tile number 1001 + udim, its u from udim % 10, its v
/// from udim / 10).
typedef struct wx_uv_raster_def {
    const wx_mesh_data *mesh;
    int uv;
    wx_uv_tiles tiles;
    int udim;
    int width, height;
    int padding; ///< texels of island bleed (0: none)
} wx_uv_raster_def;

/// Which triangle covers each texel, and where padding takes its values.
typedef struct wx_uv_raster {
    int width, height;
    wx_uv_tiles tiles;
    int udim;
    int32_t *triangle; ///< per texel: the covering triangle, -1 where none
    /// Per texel: the covered texel whose values it holds (itself when covered,
    /// the nearest covered one within the padding), -1 where none.
    int32_t *source;
    int64_t covered;           ///< texels with a triangle
    int64_t overlapping;       ///< covered texels inside more than one triangle (or copy)
    int64_t padded;            ///< texels that take a neighbour's values
    /// Triangles reaching outside the [0,1]^2 tile (REPEAT: they wrap; CLIP:
    /// their part outside is left out), or with UDIM outside the tiles
    /// [0,10] x [0,100] of UV (their part there is left out).
    int64_t triangles_outside;
    int64_t triangles_degenerate; ///< triangles of zero area in UV (never cover a texel)
    /// Triangles with no usable UVs, never drawn: a UV that is not a finite
    /// number or lies beyond WX_UV_FAR, (REPEAT, UDIM) more than
    /// WX_UV_MAX_TILES_PER_TRIANGLE tiles spanned, or no area in UV for a
    /// triangle that has one in 3D (Assimp
    /// gives an OBJ face without `vt` (0, 0) at every corner, and reads `vt
    /// nan nan` as 0 0).
    int64_t triangles_unusable;
} wx_uv_raster;

/// A UV farther than this from 0 (in either coordinate) makes its triangle
/// unusable in every mode: float holds no position within a tile finer than
/// 1/128 there, and a triangle reaching that far crosses the tile as a sliver
/// whose edges double precision no longer places (at 1e30 or u = 3e6 the
/// texel index passed 2^31, which used to make `info` and `run` spin).
#define WX_UV_FAR 65536.0

/// The default: REPEAT, no padding; mesh, uv and the size to be set.
wx_uv_raster_def wx_default_uv_raster_def(void);

/// Rasterises the layout `def` names into a width x height raster with
/// `padding` texels of bleed. Overlaps go to the triangle of lowest index (of
/// one triangle's copies, to the first in v then u). WX_FAIL when out of
/// memory; WX_BAD_ARGUMENT when the channel is missing.
wx_result wx_uv_raster_build(const wx_uv_raster_def *def, wx_uv_raster *out, wx_error *err);

/// Frees the planes; the struct is zeroed.
void wx_uv_raster_free(wx_uv_raster *raster);

/// The surface point of covered texel t: world position and unit normal (the
/// vertex normals interpolated at the texel centre in the copy of the
/// triangle the raster drew there; the triangle's own normal when they
/// cancel). False when t is not covered.
bool wx_uv_raster_point(const wx_mesh_data *mesh, int uv, const wx_uv_raster *raster,
                        size_t t, double position[3], float normal[3]);

/// What a UV layout covers at width x height texels a tile, read every way:
/// for the files tiles="udim" writes and for `weathering init`'s choice.
typedef struct wx_uv_survey {
    int64_t triangles;            ///< all of the mesh's
    int64_t triangles_unusable;   ///< a non-finite UV, or more than WX_UV_MAX_TILES_PER_TRIANGLE tiles
    int64_t triangles_degenerate; ///< zero area in UV
    int64_t triangles_outside_unit; ///< usable, reaching outside [0,1]^2
    int64_t triangles_outside_udim; ///< usable, reaching outside the UDIM tiles [0,10] x [0,100]
    /// Usable, of positive area, lying wholly in one UDIM tile other than 1001.
    int64_t triangles_in_other_tiles;
    double uv_min[2], uv_max[2]; ///< the usable triangles' UVs (0 when none)
    bool covers; ///< read with REPEAT, some texel centre lies inside a triangle
    /// UDIM tiles (k = u + 10 v) where a texel centre lies inside a triangle.
    int udim_count;
    uint8_t udim[WX_UDIM_TILES / 8];
} wx_uv_survey;

/// Surveys UV channel `uv` of `mesh` (positions not needed) at width x height
/// texels a tile, with the raster's own test of a texel centre inside a
/// triangle: exact, and linear in the triangles (each stops at its first
/// covered centre in a tile not yet known to be covered). WX_BAD_ARGUMENT
/// when the channel is missing.
wx_result wx_uv_survey_build(const wx_mesh_data *mesh, int uv, int width, int height,
                             wx_uv_survey *out, wx_error *err);

/// The sampling of a texture from the planes the mask computed on every input
/// camera's own texels.
typedef struct wx_texture_def {
    const wx_mesh_data *mesh;
    int uv;
    const wx_uv_raster *raster;
    const wx_gather_view *inputs; ///< input cameras: camera, size, depth and normal
    int input_count;
    /// smoothed[k * channels + c]: channel c computed on input camera k's
    /// texels (width*height of that camera).
    const float *const *smoothed;
    int channels;
    int threads;
    /// Optional (NULL: not kept): the covered texels' surface points as the
    /// sampling makes them (3 doubles and 3 floats a texel; the others are
    /// left alone), for what is evaluated at the same points (derived masks).
    double *position;
    float *normal;
} wx_texture_def;

/// Fills out[c] (width*height floats each, c < channels) and seen (the same
/// size): at a covered texel whose point some input camera sees, the mean of
/// the seeing cameras' values weighted by |N . view|^2 (a camera that sees the
/// surface head-on resolves it best) times the share of the camera's bilinear
/// taps that see the point (it fades out where it stops seeing the surface),
/// seen 1; at a covered texel no camera
/// sees, 0 and seen 0; elsewhere 0 (wx_texture_pad fills the padding).
/// `seen_texels` (may be NULL) gets the covered texels that are seen.
wx_result wx_texture_sample(const wx_texture_def *def, float *const *out, float *seen,
                            int64_t *seen_texels, wx_error *err);

/// Padding: every texel within the raster's padding of an island takes all the
/// values of its nearest covered texel, in each of the `count` planes.
void wx_texture_pad(const wx_uv_raster *raster, float *const *planes, int count);

#endif
