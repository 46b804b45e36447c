// bake_phase.c: the `bake` phase on files (bake_phase.h): the depth maps the
// visibility test needs read, the cameras rendered in memory (raster/bake.c),
// each camera's maps written as they come.
#include "pipeline/bake_phase.h"
#include "core/big_alloc.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <pthread.h>

#include "core/parallel.h"
#include "io/exr.h"
#include "core/progress.h"
#include "io/maps_file.h"
#include "io/mesh_import.h"
#include "model/naming.h"
#include "pipeline/load.h"
#include "pipeline/outputs.h"

// One map file of a baked camera.
typedef struct map_file {
    const wx_image *image;
    char path[WX_PATH_MAX];
    wx_result result;
    wx_error err;
} map_file;

// The map files of one baked camera, written together.
typedef struct file_batch {
    map_file files[4];
    int count;
    int threads;
    char camera[WX_NAME_MAX]; ///< the camera's name, for errors
} file_batch;

typedef struct bake_writer {
    wx_scene *scene;
    const wx_run_def *opts;
    wx_maps *output_maps; ///< when not NULL: the output camera's depth and normal kept
    wx_image *kept;       ///< when not NULL: the input cameras' images, 4 per scene camera
    bool prepared; ///< the output folder exists (made with the first camera's maps)
    file_batch now; ///< written before write_maps returns
    // A camera whose images the run keeps is written on a thread of its own
    // while the next camera renders (the render leaves a core idle): at most
    // one such batch at a time, joined before the next one and at the end.
    file_batch later;
    pthread_t thread;
    bool in_flight;
} bake_writer;

// Writes files [begin, end) of a batch (one per worker).
static void write_files(int64_t begin, int64_t end, int worker, void *context)
{
    (void)worker;
    file_batch *b = context;
    for (int64_t k = begin; k < end; ++k) {
        map_file *f = &b->files[k];
        // Every map but the depth (whose +inf means no surface) holds finite values.
        f->result = k > 0 ? wx_image_check_finite(f->image, f->path, &f->err) : WX_OK;
        if (f->result == WX_OK) {
            f->result = wx_exr_write(f->path, f->image, &f->err);
        }
    }
}

static void write_batch(file_batch *b)
{
    wx_parallel_for(b->threads, b->count, 1, write_files, b);
}

static void *write_batch_thread(void *context)
{
    write_batch(context);
    return NULL;
}

// The first failure of a written batch, named by its camera.
static wx_result batch_result(const file_batch *b, wx_error *err)
{
    for (int k = 0; k < b->count; ++k) {
        if (b->files[k].result != WX_OK) {
            *err = b->files[k].err;
            wx_error_prefix(err, "bake camera '%s'", b->camera);
            return b->files[k].result;
        }
    }
    return WX_OK;
}

// Waits for the batch written in the background, if any, and gives its result.
static wx_result join_later(bake_writer *w, wx_error *err)
{
    if (!w->in_flight) {
        return WX_OK;
    }
    pthread_join(w->thread, NULL);
    w->in_flight = false;
    return batch_result(&w->later, err);
}

// The output camera's depth and normal as the gather reads them (depth +inf
// where there is no surface, normals interleaved), so a run need not read its
// own files back.
static wx_result keep_output_maps(const wx_image *depth, const wx_image *normal, wx_maps *out,
                                  wx_error *err)
{
    int w = depth->width, h = depth->height;
    size_t texels = (size_t)w * (size_t)h;
    memset(out, 0, sizeof *out);
    out->depth = wx_big_malloc(texels * sizeof *out->depth);
    out->normal = wx_big_malloc(3 * texels * sizeof *out->normal);
    if (out->depth == NULL || out->normal == NULL) {
        wx_maps_free(out);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
    }
    out->width = w;
    out->height = h;
    for (size_t t = 0; t < texels; ++t) {
        float d = depth->channels[0][t];
        out->depth[t] = wx_depth_is_empty(d) ? INFINITY : d;
        for (int k = 0; k < 3; ++k) {
            out->normal[3 * t + (size_t)k] = normal->channels[k][t];
        }
    }
    return WX_OK;
}

// wx_bake_maps_fn: names the camera's files, stamps the headers, writes them in
// parallel (in the background when the run keeps the images), and points the
// camera at them.
static wx_result write_maps(int camera, wx_image *maps, int count, void *user, wx_error *err)
{
    bake_writer *w = user;
    wx_scene_camera *sc = &w->scene->cameras[camera];
    if (!w->prepared) {
        wx_result r = wx_output_prepare(w->scene, w->opts, NULL, err);
        if (r != WX_OK) {
            return r;
        }
        w->prepared = true;
    }
    // Kept images are the run's from here on, and the bake allocates the next
    // camera's anew: they can be written while the next camera renders.
    bool keep = !sc->is_output && w->kept != NULL;
    wx_result r = keep ? join_later(w, err) : WX_OK;
    if (r != WX_OK) {
        return r;
    }
    file_batch *b = keep ? &w->later : &w->now;
    b->count = count;
    b->threads = w->opts->threads;
    snprintf(b->camera, sizeof b->camera, "%s", sc->name);
    for (int k = 0; k < count; ++k) {
        map_file *f = &b->files[k];
        char name[sizeof sc->name + 32];
        wx_map_file_name(sc->name, k, name, sizeof name);
        r = wx_output_path(w->scene, w->opts, name, f->path, err);
        if (r != WX_OK) {
            wx_error_prefix(err, "bake camera '%s'", sc->name);
            return r;
        }
        wx_image_set_m44f(&maps[k], "WTCMatrix", sc->camera.wtc);
        wx_image_set_m44f(&maps[k], "CTWMatrix", sc->camera.ctw);
        wx_image_set_string(&maps[k], "cameraName", sc->name);
        maps[k].zip_level = 1; // the pipeline's own intermediates: the fastest zlib
        f->result = WX_OK;
        if (keep) {
            // Taken over, not copied: the bake allocates the next camera's anew.
            w->kept[4 * camera + k] = maps[k];
            memset(&maps[k], 0, sizeof maps[k]);
            f->image = &w->kept[4 * camera + k];
        } else {
            f->image = &maps[k];
        }
    }
    if (keep && pthread_create(&w->thread, NULL, write_batch_thread, b) == 0) {
        w->in_flight = true;
    } else {
        write_batch(b); // not kept, or no thread to be had: written here
        r = batch_result(b, err);
    }
    if (r == WX_OK && sc->is_output && w->output_maps != NULL) {
        r = keep_output_maps(&maps[0], &maps[1], w->output_maps, err);
    }
    if (r != WX_OK) {
        return r;
    }
    char **dest[4] = { &sc->depth_path, &sc->normal_path, &sc->impact_path, &sc->dirt_path };
    for (int k = 0; k < count; ++k) {
        if (!wx_scene_set_path(dest[k], b->files[k].path)) {
            return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
        }
    }
    sc->maps_in_output = true; // ours: later phases may replace them
    return WX_OK;
}

// The depth maps of the input cameras the scene gives as files, when the
// initial-dirt visibility test needs them (some surface starts with dirt and
// there is more than one input camera); *given stays NULL otherwise.
static wx_result read_given_depths(const wx_scene *scene, const wx_geometry *geometry,
                                   wx_maps **given, wx_error *err)
{
    *given = NULL;
    if (!geometry->has_dirt || scene->input_count < 2) {
        return WX_OK;
    }
    wx_maps *maps = calloc((size_t)scene->camera_count, sizeof *maps);
    if (maps == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
    }
    *given = maps;
    for (int c = 0; c < scene->camera_count; ++c) {
        const wx_scene_camera *sc = &scene->cameras[c];
        if (sc->is_output || (sc->has_view && !wx_has_path(sc->depth_path))) {
            continue; // the output camera has no dirt; a baked camera renders its own
        }
        wx_result r = wx_maps_load(&maps[c], WX_MAPS_DEPTH, 1, sc->depth_path, NULL, NULL, NULL,
                                   err);
        if (r != WX_OK) {
            return r;
        }
    }
    return WX_OK;
}

wx_result wx_geometry_load(const wx_scene *scene, bool quiet, wx_geometry *out, wx_error *err)
{
    memset(out, 0, sizeof *out);
    for (int c = 0; c < scene->camera_count && scene->mesh_count == 0; ++c) {
        const wx_scene_camera *sc = &scene->cameras[c];
        if (sc->has_view && !wx_has_path(sc->depth_path)) {
            return wx_fail(err, WX_CAUSE_MISSING,
                           "%s:%d: camera '%s' is given by <View> without map files, and the "
                           "scene has no <Geometry> meshes to bake them from",
                           scene->path, sc->line, sc->name);
        }
    }
    out->meshes = calloc(scene->mesh_count > 0 ? (size_t)scene->mesh_count : 1,
                         sizeof *out->meshes);
    if (out->meshes == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (meshes)");
    }
    wx_result r = WX_OK;
    double t0 = wx_now_s();
    for (int i = 0; i < scene->mesh_count && r == WX_OK; ++i) {
        const wx_mesh *mesh = &scene->meshes[i];
        wx_geometry_mesh *g = &out->meshes[i];
        out->count = i + 1;
        struct stat st;
        if (stat(mesh->path, &st) == 0) {
            out->file_bytes += (int64_t)st.st_size;
        }
        // The UV channels this mesh's <TextureMap>s read (docs/design.md section 11).
        unsigned uv_channels = 0u;
        int texture_line = 0;
        for (int t = 0; t < scene->texture_count; ++t) {
            if (scene->textures[t].mesh == i) {
                uv_channels |= 1u << scene->textures[t].uv;
                texture_line = texture_line > 0 ? texture_line : scene->textures[t].line;
            }
        }
        r = wx_mesh_import_uvs(mesh->path, uv_channels, &g->data, err);
        if (r != WX_OK && uv_channels != 0u && err->cause == WX_CAUSE_NO_UVS) {
            wx_error_prefix(err, "%s:%d: <TextureMap> (line %d) needs texture coordinates",
                            scene->path, mesh->line, texture_line);
            break;
        }
        if (r != WX_OK) {
            wx_error_prefix(err, "%s:%d", scene->path, mesh->line);
            break;
        }
        if (g->data.triangle_count == 0) {
            wx_warn(quiet, "%s:%d: mesh '%s' has no triangles", scene->path, mesh->line,
                    wx_mesh_display_name(scene, mesh));
        }
        if (g->data.parts_turned > 0) {
            wx_note(quiet,
                    "%s:%d: mesh '%s': %lld closed part%s with normals pointing inwards "
                    "(flipped on export?) turned outwards, as renderers show it",
                    scene->path, mesh->line, wx_mesh_display_name(scene, mesh),
                    (long long)g->data.parts_turned, g->data.parts_turned == 1 ? "" : "s");
        }
        if (g->data.parts_wound_both_ways > 0) {
            wx_warn(quiet,
                    "%s:%d: mesh '%s': %lld part%s with faces wound both ways (some inside "
                    "out): the cameras may read a solid's side as a thin sheet and let "
                    "particles through; make the winding consistent in the modeller "
                    "(Blender: Mesh > Normals > Recalculate Outside)",
                    scene->path, mesh->line, wx_mesh_display_name(scene, mesh),
                    (long long)g->data.parts_wound_both_ways,
                    g->data.parts_wound_both_ways == 1 ? "" : "s");
        }
        int materials = g->data.material_count;
        g->surface = calloc(materials > 0 ? (size_t)materials : 1, sizeof *g->surface);
        if (g->surface == NULL) {
            r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (meshes)");
            break;
        }
        r = wx_geometry_match(scene, i, g, &out->has_dirt, err);
        out->triangles += g->data.triangle_count;
        out->vertices += g->data.vertex_count;
    }
    out->import_s = wx_now_s() - t0;
    if (r != WX_OK) {
        wx_geometry_free(out);
    }
    return r;
}

wx_result wx_bake_geometry_into(const wx_scene *scene, const wx_run_def *opts,
                                wx_geometry *geometry, wx_bake_maps_fn *on_maps, void *user,
                                wx_bake_stats *stats, wx_error *err)
{
    wx_maps *given = NULL;
    wx_result r = WX_OK;
    if (wx_scene_needs_bake(scene)) {
        r = read_given_depths(scene, geometry, &given, err);
    }
    if (r == WX_OK) {
        wx_bake_def def = wx_default_bake_def();
        def.scene = scene;
        def.geometry = geometry;
        def.given_depth = given;
        def.threads = opts->threads;
        def.quiet = opts->quiet;
        def.on_maps = on_maps;
        def.user = user;
        r = wx_bake_render(&def, stats, err);
    }
    for (int c = 0; given != NULL && c < scene->camera_count; ++c) {
        wx_maps_free(&given[c]);
    }
    free(given);
    return r;
}

wx_result wx_bake_geometry(wx_scene *scene, const wx_run_def *opts, wx_geometry *geometry,
                           wx_maps *output_maps, wx_image *kept, wx_bake_stats *stats,
                           wx_error *err)
{
    bake_writer *writer = calloc(1, sizeof *writer); // four paths: off the stack
    if (writer == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
    }
    writer->scene = scene;
    writer->opts = opts;
    writer->output_maps = output_maps;
    writer->kept = kept;
    wx_result r = wx_bake_geometry_into(scene, opts, geometry, write_maps, writer, stats, err);
    // Joined whatever the bake's result. Its camera came before any camera the
    // bake failed in: errors are told in the cameras' order, whatever the timing.
    wx_error late;
    wx_result written = join_later(writer, &late);
    if (written != WX_OK) {
        *err = late;
        r = written;
    }
    free(writer);
    return r;
}

wx_result wx_bake_scene_stats(wx_scene *scene, const wx_run_def *opts, wx_bake_stats *stats,
                              wx_error *err)
{
    wx_geometry geometry;
    memset(&geometry, 0, sizeof geometry);
    wx_result r = WX_OK;
    if (wx_scene_needs_bake(scene)) {
        r = wx_geometry_load(scene, opts->quiet, &geometry, err);
    }
    if (r == WX_OK) {
        r = wx_bake_geometry(scene, opts, &geometry, NULL, NULL, stats, err);
    }
    wx_geometry_free(&geometry);
    return r;
}

wx_result wx_bake_scene(wx_scene *scene, const wx_run_def *opts, wx_error *err)
{
    return wx_bake_scene_stats(scene, opts, NULL, err);
}

int wx_geometry_warn_blind(const wx_scene *scene, const wx_geometry *geometry, const char *what,
                           bool quiet)
{
    char cameras[512] = "", flat[512] = "";
    int blind = 0, last = -1;
    for (int c = 0; c < scene->camera_count; ++c) {
        const wx_scene_camera *sc = &scene->cameras[c];
        if (sc->is_output || !sc->has_view || wx_has_path(sc->depth_path)) {
            continue; // not baked: its maps say what it sees
        }
        double texels = 0.0;
        for (int m = 0; m < geometry->count && texels < 1.0; ++m) {
            texels += wx_geometry_texels_seen(&geometry->meshes[m].data, &sc->camera);
        }
        if (texels < 1.0) {
            if (last >= 0) {
                char name[WX_NAME_MAX + 4];
                snprintf(name, sizeof name, "'%s'", scene->cameras[last].name);
                wx_list_append(cameras, sizeof cameras, name);
            }
            last = c;
            blind++;
        }
    }
    if (blind == 0) {
        return 0;
    }
    char tail[WX_NAME_MAX + 16];
    snprintf(tail, sizeof tail, "%s'%s'", blind > 1 ? " and " : "", scene->cameras[last].name);
    snprintf(cameras + strlen(cameras), sizeof cameras - strlen(cameras), "%s", tail);
    static const char axes[3] = { 'x', 'y', 'z' };
    for (int m = 0; m < geometry->count && m < scene->mesh_count; ++m) {
        const wx_mesh_data *d = &geometry->meshes[m].data;
        for (int k = 0; k < 3 && d->triangle_count > 0; ++k) {
            if (d->bounds_max[k] - d->bounds_min[k] == 0.0) {
                size_t n = strlen(flat);
                snprintf(flat + n, sizeof flat - n,
                         "%smesh '%s' has no thickness along %c (every vertex at %c = %g)",
                         n > 0 ? "; " : ": ", wx_mesh_display_name(scene, &scene->meshes[m]),
                         axes[k] - 32, axes[k], d->bounds_min[k]);
                break;
            }
        }
    }
    wx_warn(quiet,
            "%s: camera%s %s record%s no surface: the meshes cover less than a texel of %s "
            "frame%s (edge-on)%s; particles pass wherever a camera that frames them records no "
            "surface, so nothing will be hit in %s frame%s and the maps and masks stay zero "
            "(give the model some thickness; docs/physics.md)",
            what, blind > 1 ? "s" : "", cameras, blind > 1 ? "" : "s",
            blind > 1 ? "their" : "its", blind > 1 ? "s" : "", flat,
            blind > 1 ? "their" : "its", blind > 1 ? "s" : "");
    return blind;
}
