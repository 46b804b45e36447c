// simulate_phase.c: the `simulate` phase on files (simulate_phase.h): the maps
// in, the simulation (sim/simulate.c) on them, the dirt maps out.
#include "pipeline/simulate_phase.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/progress.h"
#include "io/exr.h"
#include "io/maps_file.h"
#include "pipeline/load.h"
#include "pipeline/outputs.h"

// Writes the dirt map of input camera `k` (scene camera `cam`).
static wx_result write_one(const wx_scene *scene, const wx_run_def *opts, const wx_sim *sim,
                           const wx_maps *maps, int k, const wx_scene_camera *cam,
                           wx_image *image, wx_error *err)
{
    const wx_dirt_map *map = wx_sim_dirt_map(sim, k);
    char name[300];
    snprintf(name, sizeof name, "%s_dirt.exr", cam->name);
    char path[WX_PATH_MAX];
    wx_result r = wx_output_path(scene, opts, name, path, err);
    if (r != WX_OK) {
        return r;
    }
    // R G B keep the dirt map layout (R now the simulated dirt); initialDirt is
    // the dirt the simulation started from, which a later `simulate` reads;
    // hits counts the impacts at each texel, which the gather's smoothing reads.
    static const char *const channels[5] = { "R", "G", "B", WX_INITIAL_DIRT_CHANNEL,
                                             WX_HITS_CHANNEL };
    r = wx_image_alloc(image, map->width, map->height, 5, channels, err);
    if (r != WX_OK) {
        return r;
    }
    size_t texels = (size_t)map->width * (size_t)map->height;
    for (size_t t = 0; t < texels; ++t) {
        image->channels[0][t] = (float)map->texels[t].dirt;
        image->channels[1][t] = maps->deposit != NULL ? maps->deposit[t] : 0.0f;
        image->channels[2][t] = maps->erosion != NULL ? maps->erosion[t] : 0.0f;
        image->channels[3][t] = maps->dirt != NULL ? maps->dirt[t] : 0.0f;
        image->channels[4][t] = map->texels[t].hits;
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
    r = wx_exr_write(path, image, err);
    wx_image_free(image);
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

wx_result wx_simulate_maps(const wx_scene *scene, const wx_run_def *opts, wx_maps *maps,
                           wx_sim_stats *stats, wx_phase_detail *detail, wx_error *err)
{
    wx_phase_detail local;
    detail = detail != NULL ? detail : &local;
    double t0 = wx_now_s();
    wx_sim_def config = wx_default_sim_def(scene);
    config.seed = opts->seed;
    config.threads = opts->threads;
    config.maps = maps;
    wx_sim *sim = NULL;
    wx_result r = wx_sim_create(scene, &config, &sim, err);
    double t1 = wx_now_s();
    detail->setup = t1 - t0;
    if (r != WX_OK) {
        return r;
    }
    wx_progress progress;
    wx_progress_begin(&progress, "simulate", scene->steps, opts->quiet);
    for (int64_t s = 0; s < scene->steps && r == WX_OK; ++s) {
        r = wx_sim_step(sim, err);
        wx_progress_update(&progress, s + 1);
    }
    wx_progress_end(&progress);
    double t2 = wx_now_s();
    detail->compute = t2 - t1;
    if (r == WX_OK) {
        r = wx_write_dirt_maps(scene, opts, sim, maps, err);
    }
    detail->write = wx_now_s() - t2;
    if (stats != NULL) {
        wx_sim_get_stats(sim, stats);
    }
    // What the gather reads, as the written maps hold it (float): the dirt, the
    // dirt the simulation started from and the hits; the planes only the
    // simulation needed released.
    for (int c = 0; c < wx_sim_input_count(sim) && r == WX_OK; ++c) {
        wx_maps *m = &maps[c];
        size_t texels = (size_t)m->width * (size_t)m->height;
        float *initial = m->dirt != NULL ? m->dirt : calloc(texels, sizeof *initial);
        float *final = malloc(texels * sizeof *final);
        float *hits = malloc(texels * sizeof *hits);
        free(m->initial_dirt);
        free(m->hits);
        m->initial_dirt = initial;
        m->dirt = final;
        m->hits = hits;
        if (initial == NULL || final == NULL || hits == NULL) {
            r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (dirt maps)");
            break;
        }
        const wx_dirt_map *dirt = wx_sim_dirt_map(sim, c);
        for (size_t t = 0; t < texels; ++t) {
            final[t] = (float)dirt->texels[t].dirt;
            hits[t] = dirt->texels[t].hits;
        }
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
    wx_result r = wx_load_simulation_maps(scene, opts->threads, maps, err);
    if (r == WX_OK) {
        r = wx_simulate_maps(scene, opts, maps, stats, NULL, err);
    }
    for (int c = 0; c < scene->input_count; ++c) {
        wx_maps_free(&maps[c]);
    }
    free(maps);
    return r;
}
