// merge.c: `weathering merge DIR` (tiles.h): the tiles' masks and TextureMaps,
// every final file and frame, joined into one. Each tile wrote only the points
// it owns and zero elsewhere, so the join is the sum of the tiles' files: each
// texel takes the one tile's value that is not zero.
#define _XOPEN_SOURCE 700 // realpath
#include "pipeline/tiles.h"

#include <dirent.h>
#include <inttypes.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/exr.h"
#include "io/maps_file.h"
#include "io/png_preview.h"
#include "io/scene_xml.h"
#include "gather/gather.h"
#include "model/naming.h"
#include "pipeline/outputs.h"

typedef struct tile_ref {
    int ix, iz;
    char scene[WX_PATH_MAX];  ///< DIR/tile_IX_IZ.xml
    char folder[WX_PATH_MAX]; ///< DIR/tile_IX_IZ
} tile_ref;

static int compare_tiles(const void *a, const void *b)
{
    const tile_ref *x = a, *y = b;
    return x->iz != y->iz ? (x->iz > y->iz) - (x->iz < y->iz) : (x->ix > y->ix) - (x->ix < y->ix);
}

// The tile scenes of DIR (tile_IX_IZ.xml exactly), sorted by IZ then IX.
static wx_result find_tiles(const char *dir, tile_ref **out, int *count, wx_error *err)
{
    *out = NULL;
    *count = 0;
    DIR *d = opendir(dir);
    if (d == NULL) {
        return wx_fail(err, WX_CAUSE_FILE_MISSING, "%s: not a folder that can be read", dir);
    }
    tile_ref *tiles = NULL;
    int n = 0, cap = 0;
    wx_result r = WX_OK;
    for (struct dirent *e = readdir(d); e != NULL && r == WX_OK; e = readdir(d)) {
        int ix = -1, iz = -1;
        char again[64];
        if (sscanf(e->d_name, "tile_%d_%d.xml", &ix, &iz) != 2 || ix < 0 || iz < 0) {
            continue;
        }
        snprintf(again, sizeof again, "tile_%d_%d.xml", ix, iz);
        if (strcmp(again, e->d_name) != 0) {
            continue;
        }
        if (n == cap) {
            cap = cap > 0 ? 2 * cap : 16;
            tile_ref *grown = realloc(tiles, (size_t)cap * sizeof *tiles);
            if (grown == NULL) {
                r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "merge: out of memory");
                break;
            }
            tiles = grown;
        }
        tile_ref *t = &tiles[n++];
        t->ix = ix;
        t->iz = iz;
        int a = snprintf(t->scene, sizeof t->scene, "%s/%s", dir, e->d_name);
        int b = snprintf(t->folder, sizeof t->folder, "%s/tile_%d_%d", dir, ix, iz);
        if (a <= 0 || a >= (int)sizeof t->scene || b <= 0 || b >= (int)sizeof t->folder) {
            r = wx_fail(err, WX_CAUSE_PATH_TOO_LONG, "%s: folder path too long", dir);
        }
    }
    closedir(d);
    if (r == WX_OK && n == 0) {
        r = wx_fail(err, WX_CAUSE_FILE_MISSING,
                    "%s: no tile scenes (tile_IX_IZ.xml, as `weathering tiles` writes them)", dir);
    }
    if (r != WX_OK) {
        free(tiles);
        return r;
    }
    qsort(tiles, (size_t)n, sizeof *tiles, compare_tiles);
    *out = tiles;
    *count = n;
    return WX_OK;
}

// How `name` relates to output file `file` (BASE.exr): -1 not one of its
// files, else the number of ".DIGITS" groups between BASE and ".exr" (a frame
// BASE.NNNN.exr or a UDIM tile BASE.TTTT.exr has one, a tile's frame two).
static int digit_groups(const char *name, const char *file)
{
    size_t base = wx_output_base_length(file);
    size_t len = strlen(name);
    if (strncmp(name, file, base) != 0 || len < base + 4 || strcmp(name + len - 4, ".exr") != 0) {
        return -1;
    }
    int groups = 0;
    for (size_t k = base; k < len - 4;) {
        if (name[k] != '.' || k + 1 >= len - 4) {
            return -1;
        }
        size_t digits = 0;
        for (++k; k < len - 4 && name[k] >= '0' && name[k] <= '9'; ++k) {
            digits++;
        }
        if (digits == 0) {
            return -1;
        }
        groups++;
    }
    return groups;
}

// What kind of output of `scene` the file `name` is: 0 not one, 1 a final
// file (it has previews), 2 a frame. *mask says whether it is the mask's.
static int classify(const wx_scene *scene, const char *name, bool *mask)
{
    *mask = false;
    if (scene->output_index >= 0) {
        int g = digit_groups(name, scene->cameras[scene->output_index].output_file);
        if (g == 0 || g == 1) {
            *mask = true;
            return g == 0 ? 1 : 2;
        }
    }
    for (int t = 0; t < scene->texture_count; ++t) {
        const wx_texture_map *def = &scene->textures[t];
        int finals = def->tiles == WX_TILES_UDIM ? 1 : 0;
        int g = digit_groups(name, def->file);
        if (g == finals) {
            return 1;
        }
        if (g == finals + 1) {
            return 2;
        }
    }
    return 0;
}

// Where each tile's mask lies on the whole output camera's pixel grid: the
// tiles' output cameras are crops of it (tiles.c), so tile k's first pixel
// falls on pixel (x[k], y[k]) of the first tile's camera; the canvas is their
// union, `view` the whole camera over it.
typedef struct mask_layout {
    int *x, *y;
    int width, height;
    wx_view view;
    wx_camera camera;
} mask_layout;

static wx_result layout_masks(const wx_scene *scenes, int count, mask_layout *out, wx_error *err)
{
    memset(out, 0, sizeof *out);
    out->x = calloc((size_t)count, sizeof *out->x);
    out->y = calloc((size_t)count, sizeof *out->y);
    if (out->x == NULL || out->y == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "merge: out of memory");
    }
    const wx_scene_camera *ref = &scenes[0].cameras[scenes[0].output_index];
    const int W0 = ref->output_width, H0 = ref->output_height;
    int x0 = INT32_MAX, y0 = INT32_MAX, x1 = INT32_MIN, y1 = INT32_MIN;
    for (int k = 0; k < count; ++k) {
        const wx_scene_camera *c = &scenes[k].cameras[scenes[k].output_index];
        float uvd[3] = { 0.5f / (float)c->output_width, 1.0f - 0.5f / (float)c->output_height,
                         0.0f };
        float p[3];
        wx_camera_map_to_world(&c->camera, uvd, p);
        wx_camera_world_to_map(&ref->camera, p, uvd);
        out->x[k] = (int)floor((double)uvd[0] * W0);
        out->y[k] = (int)floor((1.0 - (double)uvd[1]) * H0);
        x0 = out->x[k] < x0 ? out->x[k] : x0;
        y0 = out->y[k] < y0 ? out->y[k] : y0;
        x1 = out->x[k] + c->output_width > x1 ? out->x[k] + c->output_width : x1;
        y1 = out->y[k] + c->output_height > y1 ? out->y[k] + c->output_height : y1;
    }
    out->width = x1 - x0;
    out->height = y1 - y0;
    for (int k = 0; k < count; ++k) {
        out->x[k] -= x0;
        out->y[k] -= y0;
    }
    // The camera over the union: the first tile's, moved by whole pixels.
    wx_view_window(&ref->view, &ref->camera, x0, x1, y0, y1, &out->view);
    wx_result r = wx_camera_from_view(&out->view, &out->camera, err);
    out->camera.width = out->width;
    out->camera.height = out->height;
    return r;
}

static void free_layout(mask_layout *layout)
{
    free(layout->x);
    free(layout->y);
}

// The sum of every tile's file `name`: they must agree in channels, and in
// size unless `layout` places them (the masks) on its canvas.
static wx_result sum_tiles(const tile_ref *tiles, int count, const char *name,
                           const mask_layout *layout, wx_image *sum, wx_error *err)
{
    wx_result r = WX_OK;
    for (int k = 0; k < count && r == WX_OK; ++k) {
        char path[WX_PATH_MAX];
        if (!wx_tiles_join(path, sizeof path, tiles[k].folder, name)) {
            return wx_fail(err, WX_CAUSE_PATH_TOO_LONG, "%s: folder path too long",
                           tiles[k].folder);
        }
        wx_image img;
        memset(&img, 0, sizeof img);
        r = wx_exr_read_all(path, &img, err);
        if (r != WX_OK) {
            wx_error_prefix(err, "merge: tile %d %d", tiles[k].ix, tiles[k].iz);
            break;
        }
        const int W = layout != NULL ? layout->width : img.width;
        const int H = layout != NULL ? layout->height : img.height;
        const int ox = layout != NULL ? layout->x[k] : 0, oy = layout != NULL ? layout->y[k] : 0;
        if (k == 0) {
            const char *names[WX_IMAGE_MAX_CHANNELS];
            for (int c = 0; c < img.channel_count; ++c) {
                names[c] = img.channel_names[c];
            }
            r = wx_image_alloc(sum, W, H, img.channel_count, names, err);
            for (int a = 0; r == WX_OK && a < img.attr_count; ++a) {
                sum->attrs[a] = img.attrs[a];
            }
            sum->attr_count = img.attr_count;
        }
        bool same = r == WX_OK && img.channel_count == sum->channel_count && ox + img.width <= W &&
                    oy + img.height <= H && (layout != NULL || (img.width == W && img.height == H));
        for (int c = 0; same && c < img.channel_count; ++c) {
            same = strcmp(img.channel_names[c], sum->channel_names[c]) == 0;
        }
        if (r == WX_OK && !same) {
            r = wx_fail(err, WX_CAUSE_MAP_SIZE,
                        "%s: its size or channels differ from the first tile's (%s/%s)", path,
                        tiles[0].folder, name);
        }
        for (int c = 0; r == WX_OK && c < img.channel_count; ++c) {
            for (int j = 0; j < img.height; ++j) {
                float *to = sum->channels[c] + (size_t)(oy + j) * (size_t)W + (size_t)ox;
                const float *from = img.channels[c] + (size_t)j * (size_t)img.width;
                for (int i = 0; i < img.width; ++i) {
                    to[i] += from[i];
                }
            }
        }
        wx_image_free(&img);
    }
    return r;
}

// The previews of a final file, as a run writes them; `surface` gives the
// transparent texels (NULL: opaque).
static wx_result write_previews(const wx_scene *scene, const char *out_dir, const char *name,
                                const wx_image *image, const float *surface, wx_error *err)
{
    char previews[WX_MAX_PREVIEWS][WX_OUTPUT_NAME_MAX];
    int count = wx_preview_names(scene, name, previews);
    wx_result r = WX_OK;
    for (int c = 0; c < count && c < image->channel_count && r == WX_OK; ++c) {
        char path[WX_PATH_MAX];
        if (!wx_tiles_join(path, sizeof path, out_dir, previews[c])) {
            return wx_fail(err, WX_CAUSE_PATH_TOO_LONG, "%s: folder path too long", out_dir);
        }
        r = wx_preview_write_png(path, image->channels[c], surface, image->width, image->height,
                                 err);
    }
    return r;
}

// The transparent texels of a merged preview: for the mask, the background of
// the tiles' output depth maps placed as their masks are; for a texture, the
// texels no tile wrote: neither seen nor holding a value (covered texels no
// camera sees included, which a run's preview shows black).
static float *preview_surface(const wx_scene *scenes, const tile_ref *tiles, int count,
                              const mask_layout *layout, const wx_image *image, int threads)
{
    const size_t n = (size_t)image->width * (size_t)image->height;
    if (layout != NULL) {
        float *surface = malloc(n * sizeof *surface);
        for (size_t i = 0; surface != NULL && i < n; ++i) {
            surface[i] = INFINITY;
        }
        for (int k = 0; surface != NULL && k < count; ++k) {
            const wx_scene_camera *out = &scenes[k].cameras[scenes[k].output_index];
            char path[WX_PATH_MAX], name[WX_OUTPUT_NAME_MAX];
            bool fits;
            if (out->depth_path != NULL) {
                int len = snprintf(path, sizeof path, "%s", out->depth_path);
                fits = len > 0 && (size_t)len < sizeof path;
            } else {
                wx_map_file_name(out->name, WX_MAP_DEPTH, name, sizeof name);
                fits = wx_tiles_join(path, sizeof path, tiles[k].folder, name);
            }
            wx_maps maps;
            memset(&maps, 0, sizeof maps);
            wx_error err;
            if (fits &&
                wx_maps_load(&maps, WX_MAPS_DEPTH, threads, path, NULL, NULL, NULL, &err) ==
                    WX_OK &&
                layout->x[k] + maps.width <= image->width &&
                layout->y[k] + maps.height <= image->height) {
                for (int j = 0; j < maps.height; ++j) {
                    memcpy(surface + (size_t)(layout->y[k] + j) * (size_t)image->width +
                               (size_t)layout->x[k],
                           maps.depth + (size_t)j * (size_t)maps.width,
                           (size_t)maps.width * sizeof *surface);
                }
            }
            wx_maps_free(&maps);
        }
        return surface;
    }
    const float *seen = NULL;
    for (int c = 0; c < image->channel_count; ++c) {
        if (strcmp(image->channel_names[c], "seen") == 0) {
            seen = image->channels[c];
        }
    }
    float *surface = malloc(n * sizeof *surface);
    for (size_t i = 0; surface != NULL && i < n; ++i) {
        bool any = seen != NULL && seen[i] > 0.0f;
        for (int c = 0; c < image->channel_count && !any; ++c) {
            any = image->channels[c][i] != 0.0f;
        }
        surface[i] = any ? 1.0f : INFINITY;
    }
    return surface;
}

// "tile_particles" of a tile's --stats file, or -1 when it has none.
static long long tile_particles(const tile_ref *t)
{
    char path[WX_PATH_MAX + 8];
    snprintf(path, sizeof path, "%s.json", t->folder);
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        return -1;
    }
    char text[8192];
    size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = '\0';
    const char *key = strstr(text, "\"tile_particles\":");
    long long v = -1;
    if (key == NULL || sscanf(key + strlen("\"tile_particles\":"), "%lld", &v) != 1) {
        return -1;
    }
    return v;
}

wx_result wx_merge_tiles(const wx_merge_def *def, wx_error *err)
{
    tile_ref *tiles = NULL;
    int count = 0;
    wx_result r = find_tiles(def->dir, &tiles, &count, err);
    if (r != WX_OK) {
        return r;
    }
    // The first tile's scene names the outputs; every tile must be a tile
    // scene, and must have run.
    wx_scene *scenes = calloc((size_t)count, sizeof *scenes);
    if (scenes == NULL) {
        free(tiles);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "merge: out of memory");
    }
    for (int k = 0; k < count && r == WX_OK; ++k) {
        r = wx_scene_load(tiles[k].scene, &scenes[k], err);
        if (r == WX_OK && !scenes[k].tile.present) {
            r = wx_fail(err, WX_CAUSE_BAD_SCENE, "%s: not a tile scene (it has no <Tile>)",
                        tiles[k].scene);
        }
        if (r == WX_OK && (scenes[k].output_index < 0) != (scenes[0].output_index < 0)) {
            r = wx_fail(err, WX_CAUSE_BAD_SCENE, "%s: its output camera differs from %s's",
                        tiles[k].scene, tiles[0].scene);
        }
    }
    const wx_scene *scene = &scenes[0];
    mask_layout layout;
    memset(&layout, 0, sizeof layout);
    if (r == WX_OK && scene->output_index >= 0) {
        r = layout_masks(scenes, count, &layout, err);
    }
    for (int k = 0; k < count && r == WX_OK; ++k) {
        DIR *d = opendir(tiles[k].folder);
        if (d == NULL) {
            r = wx_fail(err, WX_CAUSE_FILE_MISSING,
                        "%s: no output folder for %s: run the tile first (weathering run %s "
                        "--out %s)",
                        tiles[k].folder, tiles[k].scene, tiles[k].scene, tiles[k].folder);
        } else {
            closedir(d);
        }
    }
    char out_dir[WX_PATH_MAX], created[WX_PATH_MAX];
    if (def->out_dir != NULL) {
        snprintf(out_dir, sizeof out_dir, "%s", def->out_dir);
    } else {
        snprintf(out_dir, sizeof out_dir, "%s/merged", def->dir);
    }
    if (r == WX_OK) {
        r = wx_make_folders(out_dir, created, err);
    }
    // Never into a tile's own folder: its files are the merge's inputs.
    char real_out[WX_PATH_MAX], real_tile[WX_PATH_MAX];
    if (r == WX_OK && realpath(out_dir, real_out) != NULL) {
        for (int k = 0; k < count && r == WX_OK; ++k) {
            if (realpath(tiles[k].folder, real_tile) != NULL && strcmp(real_out, real_tile) == 0) {
                r = wx_fail(err, WX_CAUSE_OUTPUT_CONFLICT,
                            "%s: the merge would write over tile %d %d's own files: use another "
                            "--out",
                            out_dir, tiles[k].ix, tiles[k].iz);
            }
        }
    }
    // Every output of the first tile's folder that is a mask's or a texture's.
    DIR *d = r == WX_OK ? opendir(tiles[0].folder) : NULL;
    int files = 0;
    for (struct dirent *e = d != NULL ? readdir(d) : NULL; e != NULL && r == WX_OK;
         e = readdir(d)) {
        bool mask = false;
        int kind = classify(scene, e->d_name, &mask);
        if (kind == 0) {
            continue;
        }
        wx_image sum;
        memset(&sum, 0, sizeof sum);
        r = sum_tiles(tiles, count, e->d_name, mask ? &layout : NULL, &sum, err);
        // A mask's header: the whole output camera over the tiles' union.
        if (r == WX_OK && mask) {
            const wx_scene_camera *out = &scene->cameras[scene->output_index];
            float m[16];
            wx_mask_world_to_camera(&layout.camera, m);
            wx_image_set_m44f(&sum, "worldToCamera", m);
            wx_mask_world_to_ndc(&layout.camera, m);
            wx_image_set_m44f(&sum, "worldToNDC", m);
            wx_image_set_m44f(&sum, "WTCMatrix", layout.camera.wtc);
            wx_image_set_m44f(&sum, "CTWMatrix", layout.camera.ctw);
            wx_image_set_string(&sum, "cameraName", out->name);
        }
        char path[WX_PATH_MAX];
        if (r == WX_OK && !wx_tiles_join(path, sizeof path, out_dir, e->d_name)) {
            r = wx_fail(err, WX_CAUSE_PATH_TOO_LONG, "%s: output folder path too long", out_dir);
        }
        if (r == WX_OK) {
            sum.threads = def->threads;
            r = wx_exr_write(path, &sum, err);
        }
        if (r == WX_OK && kind == 1) {
            float *surface =
                preview_surface(scenes, tiles, count, mask ? &layout : NULL, &sum, def->threads);
            r = write_previews(scene, out_dir, e->d_name, &sum, surface, err);
            free(surface);
        }
        wx_image_free(&sum);
        files += r == WX_OK;
    }
    if (d != NULL) {
        closedir(d);
    }
    if (r == WX_OK && !def->quiet) {
        long long particles = 0;
        for (int k = 0; k < count && particles >= 0; ++k) {
            long long p = tile_particles(&tiles[k]);
            particles = p >= 0 ? particles + p : -1;
        }
        fprintf(stderr, "merge: %d tiles of %s joined into %s: %d files", count, def->dir, out_dir,
                files);
        if (particles >= 0) {
            fprintf(stderr, "; %lld particles, each counted in the one tile it starts in",
                    particles);
        }
        fprintf(stderr, "\n");
    }
    for (int k = 0; k < count; ++k) {
        wx_scene_free(&scenes[k]);
    }
    free(scenes);
    free_layout(&layout);
    free(tiles);
    return r;
}
