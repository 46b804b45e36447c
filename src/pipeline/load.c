// load.c: what the simulation and the gather read before they compute (load.h):
// the input cameras' maps.
#include "pipeline/load.h"
#include "core/big_alloc.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/progress.h"
#include "gather/gather.h"
#include "io/exr.h"
#include "io/maps_file.h"

wx_result wx_load_simulation_maps(const wx_scene *scene, int threads, wx_image *baked,
                                  wx_maps *maps, wx_error *err)
{
    int k = 0;
    for (int c = 0; c < scene->camera_count; ++c) {
        const wx_scene_camera *cam = &scene->cameras[c];
        if (cam->is_output) {
            continue;
        }
        if (!wx_has_path(cam->depth_path)) {
            return wx_fail(err, WX_CAUSE_MISSING_PHASE,
                           "%s: camera '%s' has no maps yet; run `weathering bake` first",
                           scene->path, cam->name);
        }
        unsigned which = WX_MAPS_DEPTH | WX_MAPS_NORMAL | WX_MAPS_IMPACT;
        if (wx_has_path(cam->dirt_path)) {
            // A dirt map that an earlier `simulate` wrote starts from the dirt it
            // started from (channel initialDirt), so running again is repeatable.
            which |= WX_MAPS_DIRT | WX_MAPS_INITIAL_DIRT;
        }
        const char *const paths[4] = { cam->depth_path, cam->normal_path, cam->impact_path,
                                       cam->dirt_path };
        const wx_image *given[4] = { NULL, NULL, NULL, NULL };
        for (int f = 0; f < 4 && baked != NULL; ++f) {
            given[f] = baked[4 * c + f].channel_count > 0 ? &baked[4 * c + f] : NULL;
        }
        wx_result r =
            wx_maps_load_given(&maps[k], which, threads, scene, cam->layers, paths, given, err);
        for (int f = 0; f < 4 && baked != NULL; ++f) {
            wx_image_free(&baked[4 * c + f]); // loaded: the peak holds one camera's twice
        }
        if (r != WX_OK) {
            wx_error_prefix(err, "camera '%s'", cam->name);
            return r;
        }
        k++;
    }
    return WX_OK;
}

// True when the EXR at `path` has a channel named `name` (header only).
static bool has_channel(const char *path, const char *name)
{
    wx_image *header = calloc(1, sizeof *header); // attributes inline: off the stack
    bool found = false;
    if (header != NULL && wx_exr_read_header(path, header, NULL) == WX_OK) {
        for (int c = 0; c < header->channel_count && !found; ++c) {
            found = strcmp(header->channel_names[c], name) == 0;
        }
    }
    free(header);
    return found;
}

wx_result wx_load_gather_maps(const wx_scene *scene, const wx_run_def *opts, wx_maps *maps,
                              wx_error *err)
{
    int k = 0;
    for (int c = 0; c < scene->camera_count; ++c) {
        const wx_scene_camera *cam = &scene->cameras[c];
        if (cam->is_output) {
            continue;
        }
        char simulated[WX_PATH_MAX];
        int n = snprintf(simulated, sizeof simulated, "%s/%s_dirt.exr", opts->out_dir, cam->name);
        if (n < 0 || n >= (int)sizeof simulated) {
            return wx_fail(err, WX_CAUSE_PATH_TOO_LONG, "%s: output path too long", opts->out_dir);
        }
        const char *dirt_path = simulated;
        unsigned which = WX_MAPS_DEPTH | WX_MAPS_NORMAL | WX_MAPS_DIRT;
        if (access(simulated, R_OK) != 0) {
            if (!wx_has_path(cam->dirt_path)) {
                return wx_fail(err, WX_CAUSE_MISSING_PHASE,
                                    "%s: camera '%s' has no dirt map (no %s); run `weathering "
                                    "simulate %s --out %s` first",
                                    scene->path, cam->name, simulated, scene->path,
                                    opts->out_dir);
            }
            dirt_path = cam->dirt_path;
            wx_note(opts->quiet,
                    "gather: no simulated dirt map %s; camera '%s' uses its scene dirt map %s",
                    simulated, cam->name, dirt_path);
        } else if (scene->substances_declared && has_channel(simulated, WX_HITS_CHANNEL)) {
            which |= WX_MAPS_SIMULATED;
        } else if (scene->substances_declared ||
                   !has_channel(simulated, WX_INITIAL_DIRT_CHANNEL)) {
            wx_note(opts->quiet,
                    "gather: %s was never simulated (it holds the initial dirt bake wrote); run "
                    "`weathering simulate` first for the particles' dirt",
                    simulated);
        } else if (!has_channel(simulated, WX_HITS_CHANNEL)) {
            wx_note(opts->quiet,
                    "gather: %s has no '%s' channel (a simulation by an earlier version): the "
                    "mask is not smoothed unless <OutputMap> gives a radius; run `weathering "
                    "simulate` again",
                    simulated, WX_HITS_CHANNEL);
        } else {
            which |= WX_MAPS_SIMULATED;
        }
        wx_result r = wx_maps_load_layers(&maps[k], which, opts->threads, scene, cam->layers,
                                          cam->depth_path,
                                         cam->normal_path, NULL, dirt_path, err);
        if (r != WX_OK) {
            wx_error_prefix(err, "camera '%s'", cam->name);
            return r;
        }
        // Only the dirt plane is read: release deposit and erosion now.
        free(maps[k].deposit);
        free(maps[k].erosion);
        maps[k].deposit = maps[k].erosion = NULL;
        k++;
    }
    return WX_OK;
}

wx_result wx_layer_scene_init(const wx_scene *scene, const wx_maps *maps, int threads,
                              wx_layer_scene *out, wx_error *err)
{
    memset(out, 0, sizeof *out);
    out->scene = *scene;
    int views = 0;
    for (int k = 0; k < scene->input_count; ++k) {
        views += wx_maps_layers(&maps[k]);
    }
    bool layered = views > scene->input_count;
    int count = scene->camera_count + views - scene->input_count;
    wx_scene_camera *cameras = layered ? calloc((size_t)count, sizeof *cameras) : NULL;
    out->maps = calloc((size_t)views + 1, sizeof *out->maps);
    wx_gather_view *gather = calloc((size_t)views + 1, sizeof *gather);
    if ((layered && cameras == NULL) || out->maps == NULL || gather == NULL) {
        free(cameras);
        free(gather);
        free(out->maps);
        out->maps = NULL;
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (layers)");
    }
    int n = 0, v = 0, k = 0;
    for (int c = 0; c < scene->camera_count; ++c) {
        const wx_scene_camera *cam = &scene->cameras[c];
        if (cam->is_output) {
            if (layered) {
                out->scene.output_index = n;
                cameras[n++] = *cam;
            }
            continue;
        }
        // A layered camera's views see no crossing buried in a solid or sealed
        // behind a pane (wx_maps_bury): nothing reaches those.
        float *buried = NULL;
        int K = wx_maps_layers(&maps[k]);
        size_t texels = (size_t)maps[k].width * (size_t)maps[k].height;
        if (K > 1 && out->buried_count < WX_MAX_INPUT_CAMERAS) {
            buried = wx_big_malloc((size_t)K * texels * sizeof *buried + 1);
            if (buried == NULL) {
                free(gather);
                wx_layer_scene_free(out);
                free(cameras);
                return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (layers)");
            }
            out->buried[out->buried_count++] = buried;
            float view[3], fw, fh;
            wx_camera_view_dir(&cam->camera, view);
            wx_camera_frame_size(&cam->camera, &fw, &fh);
            float texel = fminf(fw / (float)maps[k].width, fh / (float)maps[k].height);
            wx_maps_bury(&maps[k], view, 0.25f * texel, buried);
        }
        for (int layer = 0; layer < K; ++layer) {
            if (layered) {
                cameras[n] = *cam;
                cameras[n++].layers = 1;
                wx_maps_layer_view(&maps[k], layer, &out->maps[v]);
                if (buried != NULL) {
                    out->maps[v].depth = buried + (size_t)layer * texels;
                }
            } else {
                out->maps[v] = maps[k];
            }
            gather[v] = wx_gather_view_from_maps(&cam->camera, &out->maps[v]);
            v++;
        }
        k++;
    }
    if (layered) {
        out->scene.cameras = cameras;
        out->scene.camera_count = n;
        out->scene.input_count = v;
        out->own_cameras = true;
    }
    // Each view's share of its texels, once for the mask, every texture and
    // every substance of the frame.
    wx_result r = wx_gather_owned(gather, v, threads, &out->owned, err);
    size_t at = 0;
    for (int j = 0; r == WX_OK && out->owned != NULL && j < v; ++j) {
        if (out->maps[j].owned == NULL) {
            out->maps[j].owned = out->owned + at;
            at += (size_t)out->maps[j].width * (size_t)out->maps[j].height;
        }
    }
    free(gather);
    if (r != WX_OK) {
        wx_layer_scene_free(out);
    }
    return r;
}

void wx_layer_scene_free(wx_layer_scene *layered)
{
    if (layered->own_cameras) {
        free(layered->scene.cameras);
    }
    free(layered->maps);
    free(layered->owned);
    for (int k = 0; k < layered->buried_count; ++k) {
        free(layered->buried[k]);
    }
    memset(layered, 0, sizeof *layered);
}

void wx_gather_views_of_substance(wx_gather_view *views, const wx_maps *in_maps, int count,
                                  int substance)
{
    for (int v = 0; v < count; ++v) {
        size_t plane = (size_t)substance * (size_t)in_maps[v].width * (size_t)in_maps[v].height;
        views[v].dirt = in_maps[v].dirt != NULL ? in_maps[v].dirt + plane : NULL;
        views[v].initial = in_maps[v].initial_dirt != NULL ? in_maps[v].initial_dirt + plane : NULL;
    }
}
