// texture_phase.h: the <TextureMap>s of a scene (docs/design.md section 11,
// docs/texture.md): each mesh's UV layout rasterised once per run, and after
// the simulation (and after every k-th iteration with `every`) the texture
// written with one channel per mask channel and `seen`, with its previews.
#ifndef WX_TEXTURE_PHASE_H
#define WX_TEXTURE_PHASE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "gather/texture.h"
#include "model/geometry.h"
#include "model/maps.h"
#include "model/scene.h"
#include "model/stats.h"
#include "pipeline/masks_phase.h"
#include "pipeline/pipeline.h"

/// One file of a <TextureMap>: the texture, or with tiles="udim" one tile.
typedef struct wx_texture_file {
    int udim; ///< the UDIM tile (number 1001 + udim), -1 for a texture without tiles
    wx_uv_raster raster;
} wx_texture_file;

/// One <TextureMap>, ready to be sampled: what its mesh needs of the import
/// (positions, normals, indices and the UV channel, owned copies) and the
/// raster of each of its files.
typedef struct wx_texture_target {
    const wx_texture_map *def;
    wx_mesh_data mesh;
    int file_count;
    wx_texture_file *files;
    float texel; ///< a texel's world size: the mesh's area over the covered texels, square-rooted
} wx_texture_target;

/// Every <TextureMap> of a scene, in scene order.
typedef struct wx_textures {
    int count;
    wx_texture_target *items;
} wx_textures;

/// The UDIM tiles of every tiles="udim" <TextureMap> (the tiles where a texel
/// centre lies inside a triangle of its UV layout), from `geometry` imported
/// with their UV channels: the files the run writes, which the output checks
/// and the memory estimate need before any work. The others are left alone.
void wx_textures_find_tiles(wx_scene *scene, const wx_geometry *geometry);

/// Rasterises every <TextureMap> from `geometry` (imported by
/// wx_geometry_load with the UV channels they read, before the bake releases
/// its arrays), and says for each what `info` says (coverage, overlaps,
/// triangles outside the tile) unless quiet. An empty set when the scene has none.
wx_result wx_textures_prepare(const wx_scene *scene, const wx_geometry *geometry,
                              const wx_run_def *opts, wx_textures *out, wx_error *err);

/// Frees everything; the struct is zeroed.
void wx_textures_free(wx_textures *textures);

/// Writes the textures of frame `frame` from the input cameras' maps in memory
/// (in_maps: one per input camera in scene order, depth, normal and the dirt
/// planes a gather reads; `masks` the derived masks' context, texture t's
/// points in the slots wx_mask_slot_texture gives): frame 0 every texture's
/// BASE.exr and previews, frame k > 0 BASE.NNNN.exr for those whose `every`
/// divides k; with tiles="udim" each tile's BASE.TTTT.exr, its previews and
/// frames BASE.TTTT.NNNN.exr. `detail` (may be NULL) gets the compute and write times added;
/// `noise` (may be NULL), for frame 0, the figures of each texture smoothed adaptively.
wx_result wx_textures_write(const wx_scene *scene, const wx_run_def *opts,
                            const wx_textures *textures, const wx_maps *in_maps,
                            wx_mask_context *masks, int frame, wx_phase_detail *detail,
                            wx_noise_report *noise, wx_error *err);

/// Bytes per texel of a UV raster while it is held (triangle and source).
#define WX_TEXTURE_RASTER_BYTES_PER_TEXEL 8.0

/// What `info` and the memory check count for texture `t` of `scene` whose
/// smoothing runs on input cameras of `camera_texels` texels in all: bytes at
/// the peak of writing one of its files, with that file's raster.
int64_t wx_texture_bytes(const wx_scene *scene, const wx_texture_map *t, int64_t camera_texels);

#endif
