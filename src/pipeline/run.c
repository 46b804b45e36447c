// run.c: the phases of a run in one process (run.h): the checks first, then
// bake, simulate and gather, each input file read once.
#include "pipeline/run.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/big_alloc.h"
#include "core/dist.h"
#include "core/progress.h"
#include "model/geometry.h"
#include "pipeline/bake_phase.h"
#include "pipeline/gather_phase.h"
#include "pipeline/load.h"
#include "pipeline/masks_phase.h"
#include "pipeline/memory.h"
#include "pipeline/outputs.h"
#include "pipeline/simulate_phase.h"
#include "pipeline/texture_phase.h"
#include "sim/noise.h"

// Marks the maps of the cameras bake renders as the output folder's own (bake
// is about to write them there); true when there is any.
static bool mark_baked_cameras(wx_scene *scene)
{
    bool any = wx_scene_needs_bake(scene);
    for (int c = 0; c < scene->camera_count; ++c) {
        wx_scene_camera *cam = &scene->cameras[c];
        cam->maps_in_output =
            cam->maps_in_output || (cam->has_view && !wx_has_path(cam->depth_path));
    }
    return any;
}

static void free_maps(wx_maps *maps, int count)
{
    if (maps != NULL) {
        for (int c = 0; c < count; ++c) {
            wx_maps_free(&maps[c]);
        }
        free(maps);
    }
}

// The meshes' area-weighted sample a Noise mask's remap is built from, lent
// to the scene (scene->surface_sample) for the run.
static wx_result sample_surfaces(wx_scene *scene, const wx_geometry *geometry, double **out,
                                 wx_error *err)
{
    const wx_mesh_data **meshes = calloc((size_t)geometry->count + 1, sizeof *meshes);
    *out = malloc(3 * (size_t)WX_NOISE_SAMPLE_POINTS * sizeof **out);
    if (meshes == NULL || *out == NULL) {
        free(meshes);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (noise sample)");
    }
    for (int m = 0; m < geometry->count; ++m) {
        meshes[m] = &geometry->meshes[m].data;
    }
    size_t n = wx_noise_sample_meshes(meshes, geometry->count, WX_NOISE_SAMPLE_POINTS, *out);
    free(meshes);
    scene->surface_sample = n > 0 ? *out : NULL;
    scene->surface_sample_count = (int64_t)n;
    return WX_OK;
}

wx_result wx_run_phases(wx_scene *scene, const wx_run_def *opts, unsigned phases,
                        wx_run_report *report, wx_error *err)
{
    double start = wx_now_s();
    memset(&report->noise, 0, sizeof report->noise);
    wx_geometry geometry;
    memset(&geometry, 0, sizeof geometry);
    wx_maps *maps = NULL;
    wx_mask_context masks;
    memset(&masks, 0, sizeof masks);
    wx_maps output_maps;
    memset(&output_maps, 0, sizeof output_maps);
    wx_image *baked = NULL; // the input cameras' images, kept from the bake for the simulation
    char created[WX_PATH_MAX] = "";
    wx_result r = WX_OK;
    bool bake = (phases & WX_PHASE_BAKE) && mark_baked_cameras(scene);
    if (!(phases & WX_PHASE_BAKE)) {
        r = wx_use_baked_maps(scene, opts, err);
    }
    // Everything that can be refused, before any folder or file is made.
    // TextureMaps read their meshes' UV layouts: imported with the bake's, or
    // for them alone when nothing is baked.
    bool textures_needed = scene->texture_count > 0 && (phases & (WX_PHASE_SIMULATE | WX_PHASE_GATHER));
    // Height's default range is the geometry's bounds (docs/design.md section 12).
    bool bounds_needed = false;
    for (int m = 0; m < scene->mask_count; ++m) {
        const wx_mask_def *md = &scene->masks[m];
        bounds_needed |= md->kind == WX_MASK_HEIGHT && !(md->has_min && md->has_max);
    }
    bounds_needed = bounds_needed && scene->mesh_count > 0 && (phases & WX_PHASE_GATHER);
    // A Noise mask's remap is built from the meshes' surfaces when the scene
    // has meshes (docs/masks.md): whatever phases run, the same table.
    bool noise_needed = false;
    for (int m = 0; m < scene->mask_count; ++m) {
        noise_needed |= scene->masks[m].kind == WX_MASK_NOISE;
    }
    noise_needed =
        noise_needed && scene->mesh_count > 0 && (phases & (WX_PHASE_SIMULATE | WX_PHASE_GATHER));
    if (r == WX_OK && (bake || textures_needed || bounds_needed || noise_needed)) {
        r = wx_geometry_load(scene, opts->quiet, &geometry, err);
    }
    double *surface_sample = NULL;
    if (r == WX_OK && noise_needed) {
        r = sample_surfaces(scene, &geometry, &surface_sample, err);
    }
    // The UDIM tiles the UVs cover name the files a tiles="udim" texture
    // writes: the output checks and the memory estimate below need them.
    if (r == WX_OK && textures_needed) {
        wx_textures_find_tiles(scene, &geometry);
    }
    for (int m = 0; r == WX_OK && m < geometry.count; ++m) {
        const wx_mesh_data *d = &geometry.meshes[m].data;
        if (d->triangle_count == 0) {
            continue;
        }
        for (int k = 0; k < 3; ++k) {
            scene->bounds_min[k] = scene->has_bounds ? fmin(scene->bounds_min[k], d->bounds_min[k])
                                                     : d->bounds_min[k];
            scene->bounds_max[k] = scene->has_bounds ? fmax(scene->bounds_max[k], d->bounds_max[k])
                                                     : d->bounds_max[k];
        }
        scene->has_bounds = true;
    }
    if (r == WX_OK && (phases & WX_PHASE_GATHER)) {
        r = wx_gather_check(scene, err);
    }
    if (r == WX_OK) {
        r = wx_memory_check(scene, phases, geometry.count > 0 ? &geometry : NULL, err);
    }
    if (r == WX_OK) {
        r = wx_check_outputs(scene, opts, phases, err);
    }
    if (r == WX_OK) {
        r = wx_output_prepare(scene, opts, created, err);
    }
    if (r == WX_OK) {
        r = wx_output_write_scene(scene, opts, err);
    }
    wx_textures textures;
    memset(&textures, 0, sizeof textures);
    if (r == WX_OK && textures_needed) {
        r = wx_textures_prepare(scene, &geometry, opts, &textures, err);
    }
    report->times.load += wx_now_s() - start;

    if (r == WX_OK && (phases & WX_PHASE_BAKE)) {
        double t0 = wx_now_s();
        if (bake && (phases & WX_PHASE_SIMULATE)) {
            baked = calloc(4 * (size_t)scene->camera_count, sizeof *baked);
            if (baked == NULL) {
                r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (maps)");
            }
        }
        if (bake && r == WX_OK) {
            // The output camera's maps stay in memory for the gather below,
            // and the input cameras' for the simulation: not read back.
            r = wx_bake_geometry(scene, opts, &geometry,
                                 (phases & WX_PHASE_GATHER) ? &output_maps : NULL, baked, NULL,
                                 err);
        } else if (phases == WX_PHASE_BAKE) {
            wx_note(opts->quiet, "%s: every camera has its maps; nothing to bake", scene->path);
        }
        report->times.bake = wx_now_s() - t0;
    }
    wx_geometry_free(&geometry);
    if ((phases & WX_PHASE_BAKE) && (phases & (WX_PHASE_SIMULATE | WX_PHASE_GATHER))) {
        // What the renderer and the meshes freed stays resident in the heap
        // unless given back: the phases after it would sit on it (a command
        // that only bakes ends here).
        wx_release_freed_memory();
    }
    if (r == WX_OK && (phases & WX_PHASE_SIMULATE)) {
        // An MPI run's other ranks join the simulation now that the maps are
        // baked (wx_simulate_follow; nothing with one process).
        wx_dist_release(WX_DIST_JOIN);
    }
    if (r == WX_OK && (phases & WX_PHASE_SIMULATE)) {
        double t0 = wx_now_s();
        maps = calloc((size_t)scene->input_count + 1, sizeof *maps);
        r = maps != NULL ? wx_load_simulation_maps(scene, opts->threads, baked, maps, err)
                         : wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (maps)");
        double t1 = wx_now_s();
        // A run that gathers builds the derived masks' collider now: the
        // simulation steps through it too (with the maps' impact) instead of
        // building its own. One that gathers frames keeps the context's
        // masks over them and the final gather: computed once.
        if (r == WX_OK && (phases & WX_PHASE_GATHER)) {
            r = wx_mask_context_init(scene, maps, wx_masks_worth_keeping(scene), &masks, err);
        }
        if (r == WX_OK) {
            r = wx_simulate_maps(scene, opts, maps,
                                 output_maps.depth != NULL ? &output_maps : NULL, &textures,
                                 masks.ready ? &masks : NULL, &report->stats,
                                 &report->times.simulate_detail, err);
        }
        report->times.simulate_detail.read = t1 - t0;
        const wx_sim_stats *st = &report->stats;
        if (r == WX_OK && scene->emitter_count > 0 && st->collisions == 0) {
            wx_warn(opts->quiet,
                    "%s: no particle hit a surface (%lld emitted, %lld escaped the bounding "
                    "box, %lld still flying): the dirt maps and the mask hold only the "
                    "initial dirt; see \"Fitting a scene to a model\" in docs/user-guide.md",
                    scene->path, (long long)st->particles_emitted, (long long)st->escaped,
                    (long long)st->alive);
        } else if (r == WX_OK && 2 * st->escaped_without_hit > st->particles_emitted) {
            wx_warn(opts->quiet,
                    "%s: %.0f%% of the particles (%lld of %lld) left the bounding box without "
                    "hitting anything: aim the emitters at the model (a <BoxEmitter> above or "
                    "beside it wastes none; see \"Fitting a scene to a model\" in "
                    "docs/user-guide.md)",
                    scene->path, 100.0 * (double)st->escaped_without_hit / (double)st->particles_emitted,
                    (long long)st->escaped_without_hit, (long long)st->particles_emitted);
        }
        // Particles still flying at the end carry their load in flight, not
        // onto the surfaces: a run that stops too early looks too clean.
        if (r == WX_OK && st->particles_emitted > 0 && 20 * st->alive > st->particles_emitted) {
            wx_warn(opts->quiet,
                    "%s: %.0f%% of the particles (%lld of %lld) are still flying when the "
                    "simulation ends, %lld of them before any hit: what they carry is in "
                    "flight, not on the surfaces; give the simulation more steps or end the "
                    "emitters earlier",
                    scene->path, 100.0 * (double)st->alive / (double)st->particles_emitted,
                    (long long)st->alive, (long long)st->particles_emitted,
                    (long long)st->alive_without_hit);
        }
        report->times.simulate = wx_now_s() - t0;
    }
    if (r == WX_OK && (phases & WX_PHASE_GATHER)) {
        double t0 = wx_now_s();
        if (maps != NULL) {
            r = wx_gather_maps(scene, opts, maps, output_maps.depth != NULL ? &output_maps : NULL,
                               &textures, masks.ready ? &masks : NULL, &report->times.gather_detail,
                               &report->noise, err);
        } else {
            wx_maps *in = calloc((size_t)scene->input_count + 1, sizeof *in);
            r = in != NULL ? wx_load_gather_maps(scene, opts, in, err)
                           : wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (maps)");
            double t1 = wx_now_s();
            if (r == WX_OK) {
                r = wx_gather_maps(scene, opts, in, output_maps.depth != NULL ? &output_maps : NULL,
                                   &textures, NULL, &report->times.gather_detail, &report->noise,
                                   err);
            }
            report->times.gather_detail.read += t1 - t0;
            free_maps(in, scene->input_count);
        }
        report->times.gather = wx_now_s() - t0;
    }
    wx_mask_context_free(&masks); // before the maps it borrows
    scene->surface_sample = NULL;
    scene->surface_sample_count = 0;
    free(surface_sample);
    for (int k = 0; baked != NULL && k < 4 * scene->camera_count; ++k) {
        wx_image_free(&baked[k]); // what an early failure left unread
    }
    free(baked);
    free_maps(maps, scene->input_count);
    wx_maps_free(&output_maps);
    wx_textures_free(&textures);
    if (r != WX_OK) {
        wx_output_remove_scene(scene, opts, created);
        wx_output_remove_empty(opts->out_dir, created); // a failed run leaves no empty folder
    }
    return r;
}
