// simulate_phase.c: the `simulate` phase on files (simulate_phase.h): the maps
// in, the simulation (sim/simulate.c) on them, the dirt maps out.
#include "pipeline/simulate_phase.h"
#include "core/big_alloc.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/dist.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "io/exr.h"
#include "io/maps_file.h"
#include "model/naming.h"
#include "pipeline/gather_phase.h"
#include "pipeline/load.h"
#include "pipeline/masks_phase.h"
#include "pipeline/outputs.h"
#include "pipeline/texture_phase.h"

// The planes the gather reads from the simulation's state for input camera k,
// into the caller's planes of its W*H texels: per substance s the amount
// (dirt[s]) and the amount without the particles (initial[s]: the baseline,
// or the planes the simulation started from when the scene has no rules), and
// the hits. Rows in parallel on `threads`: the same values for any count.
typedef struct planes_job {
    const wx_dirt_map *map;
    const double *baseline;
    const float *start; ///< the starting amounts (S planes), or NULL
    float *const *dirt, *const *initial;
    float *hits;
} planes_job;

static void planes_rows(int64_t begin, int64_t end, int worker, void *context)
{
    (void)worker;
    const planes_job *job = context;
    const wx_dirt_map *map = job->map;
    const size_t n = (size_t)map->width * (size_t)map->height, S = (size_t)map->substances;
    for (size_t t = (size_t)begin * (size_t)map->width; t < (size_t)end * (size_t)map->width;
         ++t) {
        const wx_dirt_texel *x = &map->texels[t * S];
        for (size_t s = 0; s < S; ++s) {
            job->dirt[s][t] = (float)x[s].dirt;
            job->initial[s][t] = job->baseline != NULL ? (float)job->baseline[t * S + s]
                                 : job->start != NULL  ? job->start[s * n + t]
                                                       : 0.0f;
        }
        job->hits[t] = x[0].hits;
    }
}

static void gather_planes(const wx_sim *sim, const wx_maps *m, int k, float *const *dirt,
                          float *const *initial, float *hits, int threads)
{
    const wx_dirt_map *map = wx_sim_dirt_map(sim, k);
    planes_job job = { .map = map,
                       .baseline = wx_sim_baseline(sim, k),
                       .start = m->dirt,
                       .dirt = dirt,
                       .initial = initial,
                       .hits = hits };
    wx_parallel_for(threads, map->height, 16, planes_rows, &job);
}

// The planes of gather_planes of input camera c's every layer in one block
// each (dirt and initial: S planes per layer, layer after layer, model/maps.h),
// for a frame's gather; the caller frees them.
static wx_result gather_plane_blocks(const wx_sim *sim, const wx_maps *m, int c, int threads,
                                     float **dirt, float **initial, float **hits, wx_error *err)
{
    int first;
    int layers = wx_sim_camera_views(sim, c, &first);
    const wx_dirt_map *map = wx_sim_dirt_map(sim, first);
    size_t n = (size_t)map->width * (size_t)map->height;
    int S = map->substances;
    size_t L = (size_t)layers;
    *dirt = wx_big_malloc(L * n * (size_t)S * sizeof **dirt + 1);
    *initial = wx_big_malloc(L * n * (size_t)S * sizeof **initial + 1);
    *hits = wx_big_malloc(L * n * sizeof **hits + 1);
    if (*dirt == NULL || *initial == NULL || *hits == NULL) {
        free(*dirt);
        free(*initial);
        free(*hits);
        *dirt = *initial = *hits = NULL;
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (dirt maps)");
    }
    for (int k = 0; k < layers; ++k) {
        wx_maps layer;
        wx_maps_layer_view(m, k, &layer);
        float *dirt_planes[WX_MAX_SUBSTANCES], *initial_planes[WX_MAX_SUBSTANCES];
        for (int s = 0; s < S; ++s) {
            dirt_planes[s] = *dirt + ((size_t)k * (size_t)S + (size_t)s) * n;
            initial_planes[s] = *initial + ((size_t)k * (size_t)S + (size_t)s) * n;
        }
        gather_planes(sim, &layer, first + k, dirt_planes, initial_planes, *hits + (size_t)k * n,
                      threads);
    }
    return WX_OK;
}

// Writes the dirt map of input camera `k` (scene camera `cam`) in the scene's
// layout (model/maps.h, wx_dirt_channels): per substance the simulated amount,
// deposit, erosion; the amounts without the particles, which a later
// `simulate` starts from; the hits, which the gather's smoothing reads; and the
// bake's surface and area records it carries on. Layer j >= 1 repeats them
// as "layerJ." channels (docs/design.md section 14).
static wx_result write_one(const wx_scene *scene, const wx_run_def *opts, const wx_sim *sim,
                           const wx_maps *maps, int k, const wx_scene_camera *cam,
                           wx_image *image, wx_error *err)
{
    int first;
    int layers = wx_sim_camera_views(sim, k, &first);
    const wx_dirt_map *map = wx_sim_dirt_map(sim, first);
    char name[300];
    snprintf(name, sizeof name, "%s_dirt.exr", cam->name);
    char path[WX_PATH_MAX];
    wx_result r = wx_output_path(scene, opts, name, path, err);
    if (r != WX_OK) {
        return r;
    }
    char names[WX_IMAGE_MAX_CHANNELS][WX_NAME_MAX];
    const char *channels[WX_IMAGE_MAX_CHANNELS];
    int count = wx_dirt_channels(scene, true, names);
    for (int j = 1; j < layers; ++j) {
        for (int c = 0; c < count; ++c) {
            wx_layer_channel(names[j * count + c], j, names[c]);
        }
    }
    for (int c = 0; c < count * layers; ++c) {
        channels[c] = names[c];
    }
    r = wx_image_alloc(image, map->width, map->height, count * layers, channels, err);
    if (r != WX_OK) {
        wx_image_free(image);
        return r;
    }
    size_t n = (size_t)map->width * (size_t)map->height;
    int S = map->substances;
    for (int j = 0; j < layers; ++j) {
        wx_maps layer;
        wx_maps_layer_view(maps, j, &layer);
        float *const *ch = image->channels + (size_t)j * (size_t)count;
        // The simulated planes straight into the image's channels.
        float *dirt[WX_MAX_SUBSTANCES], *initial[WX_MAX_SUBSTANCES];
        for (int s = 0; s < S; ++s) {
            dirt[s] = ch[3 * s];
            initial[s] = ch[3 * S + s];
        }
        gather_planes(sim, &layer, first + j, dirt, initial, ch[4 * S], opts->threads);
        for (int s = 0; s < S; ++s) {
            size_t plane = (size_t)s * n;
            if (layer.deposit != NULL) {
                memcpy(ch[3 * s + 1], layer.deposit + plane, n * sizeof(float));
            }
            if (layer.erosion != NULL) {
                memcpy(ch[3 * s + 2], layer.erosion + plane, n * sizeof(float));
            }
        }
        int next = 4 * S + 1;
        if (next < count && strcmp(names[next], WX_SURFACE_CHANNEL) == 0) {
            if (layer.surface != NULL) {
                memcpy(ch[next], layer.surface, n * sizeof(float));
            }
            next++;
        }
        if (next < count && strcmp(names[next], WX_AREA_CHANNEL) == 0 && layer.area != NULL) {
            memcpy(ch[next], layer.area, n * sizeof(float));
        }
    }
    // The input dirt map's header travels with it (kept when the map was read).
    for (int a = 0; a < maps->dirt_attr_count && image->attr_count < WX_IMAGE_MAX_ATTRS; ++a) {
        image->attrs[image->attr_count++] = maps->dirt_attrs[a];
    }
    if (wx_image_find_attr(image, "WTCMatrix") == NULL) {
        wx_image_set_m44f(image, "WTCMatrix", cam->camera.wtc);
    }
    if (wx_image_find_attr(image, "CTWMatrix") == NULL) {
        wx_image_set_m44f(image, "CTWMatrix", cam->camera.ctw);
    }
    if (wx_image_find_attr(image, "cameraName") == NULL) {
        wx_image_set_string(image, "cameraName", cam->name);
    }
    image->threads = opts->threads; // compresses chunks in parallel: same bytes
    image->zip_level = 1;           // the pipeline's own intermediate: the fastest zlib
    r = wx_image_check_finite(image, path, err); // a double beyond FLT_MAX became +inf
    if (r == WX_OK) {
        r = wx_exr_write(path, image, err);
    }
    wx_image_free(image);
    return r;
}

// The input maps a gather reads from the simulation's state now, one per input
// camera: `maps`' depth and normal borrowed, the dirt, initial and hits planes
// made (gather_plane_blocks). free_simulation_views releases them.
static wx_result simulation_views(const wx_scene *scene, const wx_run_def *opts, const wx_sim *sim,
                                  const wx_maps *maps, wx_maps **out, wx_error *err)
{
    int n = scene->input_count;
    wx_maps *view = calloc((size_t)n + 1, sizeof *view);
    *out = view;
    if (view == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (frame)");
    }
    wx_result r = WX_OK;
    for (int c = 0; c < n && r == WX_OK; ++c) {
        view[c].width = maps[c].width;
        view[c].height = maps[c].height;
        view[c].substances = maps[c].substances;
        view[c].layers = maps[c].layers;
        // Layered cameras' normals point out of the solid, as the dirt maps'
        // loader (wx_maps_load_layers) says of the maps it reads: a frame's
        // ownership and its masks' collider then are the final gather's.
        view[c].outward = maps[c].outward;
        view[c].depth = maps[c].depth;
        view[c].normal = maps[c].normal;
        r = gather_plane_blocks(sim, &maps[c], c, opts->threads, &view[c].dirt,
                                &view[c].initial_dirt, &view[c].hits, err);
    }
    return r;
}

static void free_simulation_views(const wx_scene *scene, wx_maps *view)
{
    for (int c = 0; view != NULL && c < scene->input_count; ++c) {
        free(view[c].dirt);
        free(view[c].initial_dirt);
        free(view[c].hits);
    }
    free(view);
}

// Frame `frame` of the mask's image sequence from the simulation's state now:
// the input maps' depth and normal borrowed, the dirt planes made for it.
static wx_result write_frame(const wx_scene *scene, const wx_run_def *opts, const wx_sim *sim,
                             const wx_maps *maps, const wx_maps *out_maps,
                             const wx_textures *textures, wx_mask_context *masks, int frame,
                             wx_error *err)
{
    wx_maps *view = NULL;
    wx_result r = simulation_views(scene, opts, sim, maps, &view, err);
    if (r == WX_OK) {
        r = wx_gather_frame(scene, opts, view, out_maps, textures, masks, frame, NULL, NULL, err);
    }
    free_simulation_views(scene, view);
    return r;
}

wx_result wx_gather_simulation(const wx_scene *scene, const wx_run_def *opts, const wx_sim *sim,
                               const wx_maps *maps, wx_error *err)
{
    wx_maps *view = NULL;
    wx_result r = simulation_views(scene, opts, sim, maps, &view, err);
    if (r == WX_OK) {
        r = wx_gather_maps(scene, opts, view, NULL, NULL, NULL, NULL, NULL, err);
    }
    free_simulation_views(scene, view);
    return r;
}

wx_result wx_write_dirt_maps(const wx_scene *scene, const wx_run_def *opts, const wx_sim *sim,
                             const wx_maps *maps, wx_error *err)
{
    // Images carry their attributes inline (tens of kilobytes): not on the stack.
    wx_image *image = calloc(1, sizeof *image);
    if (image == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (dirt maps)");
    }
    wx_result r = WX_OK;
    int k = 0;
    for (int c = 0; c < scene->camera_count && r == WX_OK; ++c) {
        if (!scene->cameras[c].is_output) {
            r = write_one(scene, opts, sim, &maps[k], k, &scene->cameras[c], image, err);
            k++;
        }
    }
    free(image);
    return r;
}

// The run's simulation on `maps`, spread over the ranks of an MPI run (all of
// them create it alike: wx_simulate_follow).
static wx_result create_simulation(const wx_scene *scene, const wx_run_def *opts,
                                   const wx_maps *maps, const wx_mask_context *masks, wx_sim **sim,
                                   wx_error *err)
{
    wx_sim_def config = wx_default_sim_def(scene);
    // The derived masks' collider, when the run built one: the same geometry.
    config.shared_collider = masks != NULL && masks->ready ? &masks->collider : NULL;
    config.seed = opts->seed;
    // The ranks on one machine step at the same time: they share its threads
    // (rank 0 has them all again for what it does alone: bake, frames, gather).
    int share = opts->threads / wx_dist_local_size();
    config.threads = share > 1 ? share : 1;
    config.maps = maps;
    config.distributed = true;
    return wx_sim_create(scene, &config, sim, err);
}

static int64_t total_steps(const wx_scene *scene)
{
    int64_t iterations = scene->iterations > 1 ? scene->iterations : 1;
    return scene->steps * iterations;
}

wx_result wx_simulate_maps(const wx_scene *scene, const wx_run_def *opts, wx_maps *maps,
                           const wx_maps *out_maps, const wx_textures *textures,
                           wx_mask_context *masks, wx_sim_stats *stats, wx_phase_detail *detail,
                           wx_error *err)
{
    wx_phase_detail local;
    detail = detail != NULL ? detail : &local;
    double t0 = wx_now_s();
    wx_sim *sim = NULL;
    wx_result r = create_simulation(scene, opts, maps, masks, &sim, err);
    double t1 = wx_now_s();
    detail->setup = t1 - t0;
    if (r != WX_OK) {
        return r;
    }
    // Frames of the mask's image sequence (docs/design.md section 10) need the
    // output camera's maps: those a run kept, or read here.
    const wx_scene_camera *out = scene->output_index >= 0 ? &scene->cameras[scene->output_index]
                                                          : NULL;
    int every = out != NULL ? out->every : 0;
    wx_maps read_out;
    memset(&read_out, 0, sizeof read_out);
    if (every > 0 && out_maps == NULL) {
        r = wx_maps_load(&read_out, WX_MAPS_DEPTH | WX_MAPS_NORMAL, opts->threads,
                         out->depth_path, out->normal_path, NULL, NULL, err);
        if (r != WX_OK) {
            wx_error_prefix(err, "output camera '%s'", out->name);
        }
        out_maps = &read_out;
    }
    double frames_s = 0.0;
    int64_t total = total_steps(scene);
    wx_progress progress;
    wx_progress_begin(&progress, "simulate", total, opts->quiet);
    for (int64_t s = 0; s < total && r == WX_OK; ++s) {
        r = wx_sim_step(sim, err);
        wx_progress_update(&progress, s + 1);
        int64_t done = wx_sim_iterations_done(sim);
        if (r == WX_OK && (s + 1) % scene->steps == 0 && done > 0 &&
            wx_frame_wanted(scene, (int)done)) {
            double f0 = wx_now_s();
            r = write_frame(scene, opts, sim, maps, out_maps, textures, masks, (int)done, err);
            frames_s += wx_now_s() - f0;
        }
    }
    wx_progress_end(&progress);
    wx_maps_free(&read_out);
    double t2 = wx_now_s();
    detail->compute = t2 - t1 - frames_s;
    if (r == WX_OK) {
        r = wx_write_dirt_maps(scene, opts, sim, maps, err);
    }
    detail->write = wx_now_s() - t2 + frames_s;
    if (stats != NULL) {
        wx_sim_get_stats(sim, stats);
    }
    // What the gather reads, as the written maps hold it (float): the dirt, the
    // amounts without the particles and the hits; the planes only the
    // simulation needed released.
    for (int c = 0; c < scene->input_count && r == WX_OK; ++c) {
        wx_maps *m = &maps[c];
        float *dirt = NULL, *initial = NULL, *hits = NULL;
        r = gather_plane_blocks(sim, m, c, opts->threads, &dirt, &initial, &hits, err);
        if (r != WX_OK) {
            break;
        }
        free(m->dirt);
        free(m->initial_dirt);
        free(m->hits);
        m->dirt = dirt;
        m->initial_dirt = initial;
        m->hits = hits;
        free(m->impact);
        free(m->deposit);
        free(m->erosion);
        m->impact = m->deposit = m->erosion = NULL;
    }
    wx_sim_destroy(sim);
    return r;
}

wx_result wx_simulate_scene(const wx_scene *scene, const wx_run_def *opts,
                            wx_sim_stats *stats, wx_error *err)
{
    wx_maps *maps = calloc((size_t)scene->input_count + 1, sizeof *maps);
    if (maps == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (maps)");
    }
    wx_result r = wx_load_simulation_maps(scene, opts->threads, NULL, maps, err);
    if (r == WX_OK) {
        r = wx_simulate_maps(scene, opts, maps, NULL, NULL, NULL, stats, NULL, err);
    }
    for (int c = 0; c < scene->input_count; ++c) {
        wx_maps_free(&maps[c]);
    }
    free(maps);
    return r;
}

wx_result wx_simulate_follow(wx_scene *scene, const wx_run_def *opts, wx_error *err)
{
    wx_maps *maps = calloc((size_t)scene->input_count + 1, sizeof *maps);
    if (maps == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (maps)");
    }
    // Rank 0 has baked what the scene does not give into the output folder
    // (or an earlier `bake` had): the maps its own simulation reads.
    wx_result r = wx_use_baked_maps(scene, opts, err);
    if (r == WX_OK) {
        r = wx_load_simulation_maps(scene, opts->threads, NULL, maps, err);
    }
    wx_sim *sim = NULL;
    if (r == WX_OK) {
        r = create_simulation(scene, opts, maps, NULL, &sim, err);
    }
    int64_t total = total_steps(scene);
    for (int64_t s = 0; s < total && r == WX_OK; ++s) {
        r = wx_sim_step(sim, err);
    }
    wx_sim_destroy(sim);
    for (int c = 0; c < scene->input_count; ++c) {
        wx_maps_free(&maps[c]);
    }
    free(maps);
    return r;
}
