// world_load.c: a world's loading (world.h): the scene parsed, its maps read,
// its simulation created (again, on restart), and everything freed.
#include "world_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/maps_file.h"
#include "io/scene_xml.h"
#include "pipeline/outputs.h"
#include "pipeline/pipeline.h"
#include "sim/simulate.h"

// --- parsing ------------------------------------------------------------------------

wx_result vw_world_parse(vw_world *world, const vw_settings *settings, wx_error *err)
{
    memset(world, 0, sizeof *world);
    wx_result r = wx_scene_load(settings->scene_path, &world->scene, err);
    if (r != WX_OK) {
        return r;
    }
    world->opts = wx_default_run_def(&world->scene);
    if (settings->out_dir != NULL) {
        int n = snprintf(world->opts.out_dir, sizeof world->opts.out_dir, "%s",
                         settings->out_dir);
        if (n < 0 || n >= (int)sizeof world->opts.out_dir) {
            wx_scene_free(&world->scene);
            return wx_fail(err, WX_CAUSE_PATH_TOO_LONG, "--out %s: path too long",
                           settings->out_dir);
        }
    }
    if (settings->threads > 0) {
        world->opts.threads = settings->threads;
    }
    world->opts.quiet = true; // the viewer reports in its own words
    world->mask = -1;
    return WX_OK;
}

// --- maps and simulation ------------------------------------------------------------

static wx_result load_maps(vw_world *world, wx_error *err)
{
    const wx_scene *scene = &world->scene;
    int n = scene->camera_count;
    world->maps = calloc((size_t)n, sizeof *world->maps);
    world->camera_maps = calloc((size_t)n, sizeof *world->camera_maps);
    world->input_camera = calloc((size_t)n, sizeof *world->input_camera);
    world->first_view = calloc((size_t)n, sizeof *world->first_view);
    if (world->maps == NULL || world->camera_maps == NULL || world->input_camera == NULL ||
        world->first_view == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (maps)");
    }
    // The simulation's views: each input camera's layers, camera by camera.
    int inputs = 0, views = 0;
    world->max_layers = 1;
    for (int c = 0; c < n; ++c) {
        const wx_scene_camera *cam = &scene->cameras[c];
        world->first_view[c] = -1;
        if (!cam->is_output) {
            int layers = cam->layers > 1 ? cam->layers : 1;
            world->input_camera[inputs] = c;
            world->camera_maps[c] = inputs++;
            world->first_view[c] = views;
            views += layers;
            world->max_layers = layers > world->max_layers ? layers : world->max_layers;
        }
    }
    for (int c = 0, outputs = 0; c < n; ++c) {
        if (scene->cameras[c].is_output) {
            world->camera_maps[c] = inputs + outputs++;
        }
    }
    for (int c = 0; c < n; ++c) {
        const wx_scene_camera *cam = &scene->cameras[c];
        if (!wx_has_path(cam->depth_path)) {
            return wx_fail(err, WX_CAUSE_MISSING_PHASE,
                           "%s: camera '%s' has no maps; run `weathering bake %s` first",
                           scene->path, cam->name, scene->path);
        }
        unsigned which = WX_MAPS_DEPTH | WX_MAPS_NORMAL;
        if (!cam->is_output) {
            which |= WX_MAPS_IMPACT;
            if (wx_has_path(cam->dirt_path)) {
                // After G the file holds simulated dirt; start from its initialDirt.
                which |= WX_MAPS_DIRT | WX_MAPS_INITIAL_DIRT;
            }
        }
        // Every layer of an input camera (docs/design.md section 14); the
        // output camera has one.
        int layers = !cam->is_output && cam->layers > 1 ? cam->layers : 1;
        wx_result r = wx_maps_load_layers(&world->maps[world->camera_maps[c]], which, 1,
                                          &world->scene, layers, cam->depth_path,
                                          cam->normal_path, cam->impact_path, cam->dirt_path,
                                          err);
        if (r != WX_OK) {
            wx_error_prefix(err, "camera '%s'", cam->name);
            return r;
        }
    }
    return WX_OK;
}

static wx_result create_sim(vw_world *world, const vw_settings *settings, wx_error *err)
{
    wx_sim_def config = wx_default_sim_def(&world->scene);
    config.seed = world->opts.seed;
    config.threads = settings->threads;
    config.hit_capacity = settings->hit_capacity;
    config.maps = world->maps;
    wx_result r = wx_sim_create(&world->scene, &config, &world->sim, err);
    // The depth samples name their views as load_maps counted them: the
    // simulation must count the same.
    for (int c = 0; r == WX_OK && c < world->scene.camera_count; ++c) {
        int first = -1;
        if (world->first_view[c] >= 0 &&
            (wx_sim_camera_views(world->sim, world->camera_maps[c], &first) !=
                 vw_world_camera_layers(world, c) ||
             first != world->first_view[c])) {
            wx_sim_destroy(world->sim);
            world->sim = NULL;
            r = wx_fail(err, WX_CAUSE_BAD_ARGUMENT,
                        "camera '%s': the simulation's views of its layers are not the viewer's",
                        world->scene.cameras[c].name);
        }
    }
    return r;
}

wx_result vw_world_finish(vw_world *world, const vw_settings *settings, wx_error *err)
{
    wx_result r = wx_use_baked_maps(&world->scene, &world->opts, err);
    if (r == WX_OK) {
        r = load_maps(world, err);
    }
    if (r == WX_OK) {
        r = vw_world_build_geometry(world, err);
    }
    if (r == WX_OK) {
        r = create_sim(world, settings, err);
    }
    if (r == WX_OK) {
        vw_world_show_substance(world, 0);
    }
    return r;
}

wx_result vw_world_restart(vw_world *world, const vw_settings *settings, wx_error *err)
{
    wx_sim *old = world->sim; // kept running should the new one fail
    wx_result r = create_sim(world, settings, err);
    if (r != WX_OK) {
        world->sim = old;
        return r;
    }
    wx_sim_destroy(old);
    return WX_OK;
}

int64_t vw_world_total_steps(const vw_world *world)
{
    return world->scene.steps * (int64_t)(world->scene.iterations > 1 ? world->scene.iterations : 1);
}

bool vw_world_finished(const vw_world *world)
{
    return world->sim != NULL && wx_sim_step_count(world->sim) >= vw_world_total_steps(world);
}

void vw_world_free(vw_world *world)
{
    wx_sim_destroy(world->sim);
    if (world->maps != NULL) {
        for (int c = 0; c < world->scene.camera_count; ++c) {
            wx_maps_free(&world->maps[c]);
        }
    }
    free(world->maps);
    free(world->camera_maps);
    free(world->input_camera);
    free(world->first_view);
    free(world->lines);
    free(world->points);
    free(world->samples);
    free(world->camera_lines);
    free(world->camera_points);
    free(world->layer_points);
    for (int m = 0; m < WX_MAX_MASKS; ++m) {
        free(world->mask_values[m]);
    }
    if (world->mask_context != NULL) {
        wx_mask_context_free(world->mask_context);
        free(world->mask_context);
    }
    wx_scene_free(&world->scene);
    memset(world, 0, sizeof *world);
}
