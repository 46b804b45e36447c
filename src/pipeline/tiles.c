// tiles.c: a scene cut into tiles (tiles.h): what a tile's run writes (only
// the surface points its <Tile> owns, so that the tiles' files add up to the
// whole scene's), and the tile scenes with their Slurm job scripts.
#define _XOPEN_SOURCE 700 // realpath
#include "pipeline/tiles.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "core/atomic_file.h"
#include "io/scene_xml.h"
#include "model/maps.h"
#include "pipeline/outputs.h"

static void zero_texel(wx_image *image, size_t i)
{
    for (int c = 0; c < image->channel_count; ++c) {
        image->channels[c][i] = 0.0f;
    }
}

void wx_tile_restrict_camera(const wx_scene *scene, const wx_camera *camera, const float *depth,
                             wx_image *image)
{
    const wx_tile_def *tile = &scene->tile;
    if (!tile->present) {
        return;
    }
    const int w = image->width, h = image->height;
    for (int j = 0; j < h; ++j) {
        for (int i = 0; i < w; ++i) {
            size_t t = (size_t)j * (size_t)w + (size_t)i;
            float uvd[3], p[3];
            wx_map_texel_center(w, h, i, j, &uvd[0], &uvd[1]);
            // A background pixel belongs to the tile under its point on the
            // camera's plane, so that every pixel has exactly one owner.
            uvd[2] = depth != NULL && !wx_depth_is_empty(depth[t]) ? depth[t] : 0.0f;
            wx_camera_map_to_world(camera, uvd, p);
            if (!wx_tile_owns(tile, p[0], p[2])) {
                zero_texel(image, t);
            }
        }
    }
}

void wx_tile_restrict_points(const wx_scene *scene, const double *position, const float *seen,
                             wx_image *image)
{
    const wx_tile_def *tile = &scene->tile;
    if (!tile->present || position == NULL) {
        return;
    }
    const size_t n = (size_t)image->width * (size_t)image->height;
    for (size_t t = 0; t < n; ++t) {
        if (seen[t] > 0.0f && !wx_tile_owns(tile, position[3 * t], position[3 * t + 2])) {
            zero_texel(image, t);
        }
    }
}

// ---------------------------------------------------------------------------
// `weathering tiles`: the tile scenes

// The tile's bounds along axis a (0: x, 1: z) of an n-tile cut of [lo, hi]:
// the outer tiles are unbounded outward, so that every point has one owner.
static void tile_bounds(double lo, double hi, int n, int k, double *min, double *max)
{
    double step = (hi - lo) / n;
    *min = k == 0 ? -INFINITY : lo + step * k;
    *max = k == n - 1 ? INFINITY : lo + step * (k + 1);
}

void wx_view_window(const wx_view *view, const wx_camera *cam, int i0, int i1, int j0, int j1,
                    wx_view *out)
{
    const double W = view->width_px, H = view->height_px;
    // The window's centre on the eye plane; the view direction and up stay.
    float centre[3] = { (float)((i0 + i1) / (2.0 * W)), (float)(1.0 - (j0 + j1) / (2.0 * H)),
                        0.0f };
    float eye[3];
    wx_camera_map_to_world(cam, centre, eye);
    *out = *view;
    for (int a = 0; a < 3; ++a) {
        out->eye[a] = eye[a];
        out->target[a] = eye[a] + (view->target[a] - view->eye[a]);
    }
    out->width_px = i1 - i0;
    out->height_px = j1 - j0;
    out->width_ws = (float)(view->width_ws * (double)out->width_px / W);
    out->height_ws = (float)(view->height_ws * (double)out->height_px / H);
}

bool wx_tiles_join(char *out, size_t cap, const char *dir, const char *name)
{
    int n = snprintf(out, cap, "%s/%s", dir, name);
    return n > 0 && (size_t)n < cap;
}

// Input camera `view` cropped, on its own texel grid, to what it sees of the
// box [lo, hi] (the tile and its halo within the bounding box). False when
// it sees none of it.
static bool crop_view(const wx_view *view, const double lo[3], const double hi[3], wx_view *out)
{
    wx_camera cam;
    wx_error err;
    if (wx_camera_from_view(view, &cam, &err) != WX_OK) {
        return false;
    }
    const double W = view->width_px, H = view->height_px;
    double i_lo = INFINITY, i_hi = -INFINITY, j_lo = INFINITY, j_hi = -INFINITY;
    for (int c = 0; c < 8; ++c) {
        float p[3] = { (float)((c & 1) ? hi[0] : lo[0]), (float)((c & 2) ? hi[1] : lo[1]),
                       (float)((c & 4) ? hi[2] : lo[2]) };
        float uvd[3];
        wx_camera_world_to_map(&cam, p, uvd);
        double i = uvd[0] * W, j = (1.0 - uvd[1]) * H;
        i_lo = fmin(i_lo, i);
        i_hi = fmax(i_hi, i);
        j_lo = fmin(j_lo, j);
        j_hi = fmax(j_hi, j);
    }
    int i0 = (int)fmax(0.0, floor(i_lo)), i1 = (int)fmin(W, ceil(i_hi));
    int j0 = (int)fmax(0.0, floor(j_lo)), j1 = (int)fmin(H, ceil(j_hi));
    if (i1 <= i0 || j1 <= j0) {
        return false;
    }
    wx_view_window(view, &cam, i0, i1, j0, j1, out);
    return true;
}

static wx_result write_text(const char *dir, const char *name, const char *text, wx_error *err)
{
    char path[WX_PATH_MAX];
    if (!wx_tiles_join(path, sizeof path, dir, name)) {
        return wx_fail(err, WX_CAUSE_PATH_TOO_LONG, "%s: output folder path too long", dir);
    }
    return wx_write_file_atomic(path, text, strlen(text), err);
}

// tiles.sbatch (the job array), merge.sbatch and submit.sh, which submits both
// with the merge after the array (afterok).
static wx_result write_slurm(const wx_tiles_def *def, const char *dir, const char *name,
                             const char *shot, wx_error *err)
{
    char text[4 * WX_PATH_MAX + 2048];
    snprintf(text, sizeof text,
             "#!/bin/sh\n"
             "# The tiles of %s as a Slurm job array, one task per tile (written by\n"
             "# `weathering tiles`). Submit with ./submit.sh, which runs the merge after it.\n"
             "#SBATCH --job-name=%s-tiles\n"
             "#SBATCH --array=0-%d\n"
             "#SBATCH --chdir=%s\n"
             "#SBATCH --output=logs/tile_%%a.log\n"
             "set -eu\n"
             "task=${SLURM_ARRAY_TASK_ID:?run this script with sbatch (a job array)}\n"
             "ix=$((task %% %d))\n"
             "iz=$((task / %d))\n"
             "# As many threads as the task was given cores (sbatch --cpus-per-task), else all.\n"
             "exec '%s' run \"tile_${ix}_${iz}.xml\" --out \"tile_${ix}_${iz}\" "
             "--stats \"tile_${ix}_${iz}.json\" -q ${SLURM_CPUS_PER_TASK:+--threads "
             "\"$SLURM_CPUS_PER_TASK\"}\n",
             def->scene_path, name, def->nx * def->nz - 1, dir, def->nx, def->nx, def->program);
    wx_result r = write_text(dir, "tiles.sbatch", text, err);
    if (r == WX_OK) {
        snprintf(text, sizeof text,
                 "#!/bin/sh\n"
                 "# Joins the tiles' masks and TextureMaps once every tile is done.\n"
                 "#SBATCH --job-name=%s-merge\n"
                 "#SBATCH --chdir=%s\n"
                 "#SBATCH --output=logs/merge.log\n"
                 "set -eu\n"
                 "exec '%s' merge . --out merged -q\n",
                 name, dir, def->program);
        r = write_text(dir, "merge.sbatch", text, err);
    }
    if (r == WX_OK) {
        snprintf(text, sizeof text,
                 "#!/bin/sh\n"
                 "# Submits the tiles' job array and the merge that waits for it (afterok).\n"
                 "# ./submit.sh TASKS submits only those tasks (sbatch --array=TASKS, task\n"
                 "# IX + %d * IZ); the output camera sees tasks: %s. Merge joins the tile\n"
                 "# scenes in this folder: move the others' tile_IX_IZ.xml away first.\n"
                 "set -eu\n"
                 "cd '%s'\n"
                 "mkdir -p logs\n"
                 "tiles=$(sbatch --parsable ${1:+--array=\"$1\"} tiles.sbatch)\n"
                 "merge=$(sbatch --parsable --dependency=afterok:${tiles%%%%;*} merge.sbatch)\n"
                 "echo \"tiles: job ${tiles%%%%;*}; merge: job ${merge%%%%;*}\"\n",
                 def->nx, shot, dir);
        r = write_text(dir, "submit.sh", text, err);
        char path[WX_PATH_MAX];
        if (r == WX_OK && wx_tiles_join(path, sizeof path, dir, "submit.sh")) {
            chmod(path, 0755);
        }
    }
    return r;
}

// Writes tile IX IZ's scene; *cameras_out: its input cameras; *shot: whether
// the output camera sees the tile itself (not only its halo).
static wx_result write_tile(const wx_tiles_def *def, const wx_scene *scene, const char *dir, int ix,
                            int iz, int *cameras_out, bool *shot, wx_error *err)
{
    const double half = 0.5 * (double)scene->bbox_size;
    double lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
        lo[a] = (double)scene->bbox_center[a] - half;
        hi[a] = (double)scene->bbox_center[a] + half;
    }
    wx_tile_def tile = { .present = true, .halo = def->halo };
    tile_bounds(lo[0], hi[0], def->nx, ix, &tile.min[0], &tile.max[0]);
    tile_bounds(lo[2], hi[2], def->nz, iz, &tile.min[1], &tile.max[1]);
    // What the cameras must see: the tile and its halo, within the bounds.
    double box_lo[3] = { fmax(lo[0], tile.min[0] - def->halo), lo[1],
                         fmax(lo[2], tile.min[1] - def->halo) };
    double box_hi[3] = { fmin(hi[0], tile.max[0] + def->halo), hi[1],
                         fmin(hi[2], tile.max[1] + def->halo) };
    const char **names = calloc((size_t)scene->camera_count + 1, sizeof *names);
    wx_view *views = calloc((size_t)scene->camera_count + 1, sizeof *views);
    if (names == NULL || views == NULL) {
        free(names);
        free(views);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "tiles: out of memory");
    }
    int count = 0;
    for (int c = 0; c < scene->camera_count; ++c) {
        const wx_scene_camera *sc = &scene->cameras[c];
        if (!sc->is_output && crop_view(&sc->view, box_lo, box_hi, &views[count])) {
            names[count++] = sc->name;
        }
    }
    // The output camera over the tile and its halo too: the gather smooths
    // across the tile's border as the whole run does, the tile writes only its
    // own pixels, and merge places the crops on the whole camera's pixel grid.
    wx_view output_view;
    bool crop_output = false;
    *shot = false;
    if (scene->output_index >= 0) {
        const wx_scene_camera *out = &scene->cameras[scene->output_index];
        crop_output = out->has_view && out->depth_path == NULL &&
                      crop_view(&out->view, box_lo, box_hi, &output_view);
        const double own_lo[3] = { fmax(lo[0], tile.min[0]), lo[1], fmax(lo[2], tile.min[1]) };
        const double own_hi[3] = { fmin(hi[0], tile.max[0]), hi[1], fmin(hi[2], tile.max[1]) };
        wx_view unused;
        // An output camera given by map files is not cropped: it sees them all.
        *shot = !(out->has_view && out->depth_path == NULL) ||
                (crop_output && crop_view(&out->view, own_lo, own_hi, &unused));
    }
    char name[64], file[80];
    snprintf(name, sizeof name, "tile_%d_%d", ix, iz);
    snprintf(file, sizeof file, "%s.xml", name);
    wx_result r = WX_OK;
    if (count == 0) {
        r = wx_fail(err, WX_CAUSE_BAD_SCENE,
                    "%s: no input camera sees tile %d %d: use fewer tiles, or cameras that "
                    "cover the <BoundingBox>",
                    scene->path, ix, iz);
    }
    wx_tile_scene_edit edit = { .name = name,
                                .tile = tile,
                                .to_dir = dir,
                                .view_count = count,
                                .view_names = names,
                                .views = views,
                                .output_view = crop_output ? &output_view : NULL };
    char *text = NULL;
    size_t size = 0;
    if (r == WX_OK) {
        r = wx_scene_tile_text(def->scene_path, &edit, &text, &size, err);
    }
    // The tile scene must read back as a scene (it names the same files).
    char path[WX_PATH_MAX];
    if (r == WX_OK && !wx_tiles_join(path, sizeof path, dir, file)) {
        r = wx_fail(err, WX_CAUSE_PATH_TOO_LONG, "%s: output folder path too long", dir);
    }
    if (r == WX_OK) {
        wx_scene check;
        memset(&check, 0, sizeof check);
        r = wx_scene_load_text(path, text, size, &check, err);
        wx_scene_free(&check);
        if (r != WX_OK) {
            wx_error_prefix(err, "tiles: the tile scene made of %s does not read back",
                            scene->path);
            r = WX_FAIL;
        }
    }
    if (r == WX_OK) {
        // Never over the scene it was cut from.
        char a[WX_PATH_MAX], b[WX_PATH_MAX];
        if (realpath(def->scene_path, a) != NULL && realpath(path, b) != NULL &&
            strcmp(a, b) == 0) {
            r = wx_fail(err, WX_CAUSE_OUTPUT_CONFLICT,
                        "%s: the tile scene %s would replace the scene itself: use another --out",
                        def->scene_path, path);
        } else {
            r = wx_write_file_atomic(path, text, size, err);
        }
    }
    *cameras_out = count;
    free(text);
    free(names);
    free(views);
    return r;
}

wx_result wx_tiles_write(const wx_tiles_def *def, wx_error *err)
{
    wx_scene scene;
    memset(&scene, 0, sizeof scene);
    wx_result r = wx_scene_load(def->scene_path, &scene, err);
    if (r != WX_OK) {
        return r;
    }
    if (scene.tile.present) {
        r = wx_fail(err, WX_CAUSE_BAD_SCENE,
                    "%s:%d: the scene is already a tile (<Tile>): cut the whole scene", scene.path,
                    scene.tile.line);
    }
    for (int c = 0; c < scene.camera_count && r == WX_OK; ++c) {
        const wx_scene_camera *sc = &scene.cameras[c];
        if (!sc->is_output && (!sc->has_view || sc->depth_path != NULL)) {
            r = wx_fail(err, WX_CAUSE_BAD_SCENE,
                        "%s:%d: camera '%s': a tile crops its input cameras, so each must be "
                        "given by <View> without map files",
                        scene.path, sc->line, sc->name);
        }
    }
    char dir[WX_PATH_MAX], created[WX_PATH_MAX];
    if (r == WX_OK) {
        r = wx_make_folders(def->out_dir, created, err);
    }
    if (r == WX_OK && realpath(def->out_dir, dir) == NULL) {
        r = wx_fail(err, WX_CAUSE_IO, "%s: the folder cannot be resolved", def->out_dir);
    }
    // The tiles a shot needs: those the output camera sees, as the job
    // array's task numbers ("5,6,9,10"; docs/scale-out.md).
    const size_t shot_cap = (size_t)def->nx * (size_t)def->nz * 8 + 1;
    char *shot = r == WX_OK ? calloc(shot_cap, 1) : NULL;
    if (r == WX_OK && shot == NULL) {
        r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "tiles: out of memory");
    }
    int cameras = 0, most = 0, least = INT32_MAX, shots = 0;
    size_t used = 0;
    for (int iz = 0; iz < def->nz && r == WX_OK; ++iz) {
        for (int ix = 0; ix < def->nx && r == WX_OK; ++ix) {
            bool seen = false;
            r = write_tile(def, &scene, dir, ix, iz, &cameras, &seen, err);
            most = cameras > most ? cameras : most;
            least = cameras < least ? cameras : least;
            if (seen) {
                used += (size_t)snprintf(shot + used, shot_cap - used, "%s%d", shots ? "," : "",
                                         ix + def->nx * iz);
                ++shots;
            }
        }
    }
    if (r == WX_OK && def->slurm) {
        // The list in submit.sh's comment, unless it is long.
        const char *listed = shot;
        if (scene.output_index < 0) {
            listed = "none (the scene has no output camera)";
        } else if (shots == def->nx * def->nz) {
            listed = "all";
        } else if (shots == 0) {
            listed = "none";
        } else if (used > 1024) {
            listed = "many: `weathering tiles` printed them";
        }
        r = write_slurm(def, dir, scene.name, listed, err);
    }
    if (r == WX_OK && !def->quiet) {
        fprintf(stderr,
                "tiles: %d x %d tiles of %s (halo %g) in %s: tile_IX_IZ.xml, %d to %d input "
                "cameras each%s\n",
                def->nx, def->nz, scene.path, def->halo, dir, least, most,
                def->slurm ? "; tiles.sbatch, merge.sbatch and submit.sh for Slurm" : "");
        if (scene.output_index >= 0 && shots < def->nx * def->nz) {
            fprintf(stderr,
                    "tiles: the output camera '%s' sees %d of the %d tiles (tasks %s: tile IX + "
                    "%d * IZ)%s\n",
                    scene.cameras[scene.output_index].name, shots, def->nx * def->nz,
                    shots ? shot : "none", def->nx,
                    def->slurm && shots ? "; ./submit.sh with that list runs just them" : "");
        }
    }
    free(shot);
    wx_scene_free(&scene);
    return r;
}
