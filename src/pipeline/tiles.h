// tiles.h: a scene cut into tiles (docs/tiles.md): what a tile's run writes
// (only the surface points the tile owns), the tile scenes `weathering tiles`
// writes (cameras cropped to the tile and its halo, on the whole scene's texel
// grid) with their Slurm job scripts, and `weathering merge`, which joins the
// tiles' masks and TextureMaps.
#ifndef WX_TILES_H
#define WX_TILES_H

#include <stdbool.h>
#include <stddef.h>

#include "core/error.h"
#include "model/camera.h"
#include "model/image.h"
#include "model/scene.h"
#include "pipeline/pipeline.h"

/// A camera mask seen from `camera` (depth: its W x H depth map, layer 0):
/// zeroes every channel of every pixel whose surface point (or, for a
/// background pixel, the point on the camera's plane) the scene's tile does not
/// own. Nothing happens without a <Tile>.
void wx_tile_restrict_camera(const wx_scene *scene, const wx_camera *camera, const float *depth,
                             wx_image *image);

/// A TextureMap: zeroes every channel of every texel whose surface point
/// (position, 3 doubles a texel; valid where covered[i]) the tile does not own.
/// Texels without a point keep their values (0). Nothing happens without a <Tile>.
void wx_tile_restrict_points(const wx_scene *scene, const double *position, const float *seen,
                             wx_image *image);

/// The window of `view` (its matrices `cam`) over its texel columns [i0, i1)
/// and rows [j0, j1) (row 0 at the top; they may reach beyond its frame): the
/// same texels, its eye moved sideways by whole texels. A tile's cameras are
/// such windows, and so is the whole output camera over the tiles' masks.
void wx_view_window(const wx_view *view, const wx_camera *cam, int i0, int i1, int j0, int j1,
                    wx_view *out);

/// DIR/NAME into `out` (cap bytes); false when it does not fit.
bool wx_tiles_join(char *out, size_t cap, const char *dir, const char *name);

/// What `weathering tiles` is asked for.
typedef struct wx_tiles_def {
    const char *scene_path;
    int nx, nz;  ///< tiles along x and z, >= 1
    double halo; ///< world units, >= 0
    const char *out_dir;
    bool slurm;          ///< also write tiles.sbatch, merge.sbatch and submit.sh
    const char *program; ///< the weathering program the job scripts run
    bool quiet;
} wx_tiles_def;

/// Writes tile_IX_IZ.xml for every tile (and the Slurm scripts) into out_dir.
wx_result wx_tiles_write(const wx_tiles_def *def, wx_error *err);

/// What `weathering merge` is asked for.
typedef struct wx_merge_def {
    const char *dir;     ///< the folder with tile_IX_IZ.xml and tile_IX_IZ/
    const char *out_dir; ///< default DIR/merged
    int threads;
    bool quiet;
} wx_merge_def;

/// Joins the tiles' masks and TextureMaps (every final file and frame) into
/// out_dir, with the previews of the final files.
wx_result wx_merge_tiles(const wx_merge_def *def, wx_error *err);

#endif
