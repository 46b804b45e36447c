// phases.c: the phase commands `bake`, `simulate`, `gather` (and the run of a
// scene): the scene loaded with the command line's options, the phases run in
// one process, the statistics written, and the summary printed.
#include "cli.h"

#include <stdio.h>
#include <string.h>

#include "core/dist.h"
#include "core/limits.h"
#include "core/progress.h"
#include "io/scene_xml.h"
#include "io/stats_json.h"
#include "model/scene.h"
#include "pipeline/outputs.h"
#include "pipeline/pipeline.h"
#include "pipeline/run.h"
#include "pipeline/simulate_phase.h"

// Loads the scene and fills the run options from it and the command line.
int cli_load_scene(const cli_args *args, wx_scene *scene, wx_run_def *opts)
{
    wx_error err;
    wx_result r = args->scene_text != NULL
                      ? wx_scene_load_text(args->scene_path, args->scene_text,
                                           strlen(args->scene_text), scene, &err)
                      : wx_scene_load(args->scene_path, scene, &err);
    if (r != WX_OK) {
        fprintf(stderr, "weathering: %s\n", err.message);
        return r;
    }
    *opts = wx_default_run_def(scene);
    opts->scene_text = args->scene_text;
    if (args->out_dir != NULL) {
        snprintf(opts->out_dir, sizeof opts->out_dir, "%s", args->out_dir);
    }
    if (args->seed_set) {
        opts->seed = args->seed;
    }
    if (args->threads > 0) {
        opts->threads = args->threads;
    }
    opts->quiet = args->quiet;
    opts->stats_path = args->stats_path;
    return WX_OK;
}

// --- bake, simulate, gather, run ------------------------------------------------

int cli_report(wx_result r, const wx_error *err)
{
    if (r != WX_OK) {
        fprintf(stderr, "weathering: %s\n", err->message);
    }
    return r;
}

// Where the emitters' particles ended: each one hit the model, left the
// bounding box without a hit, or is still flying without one, so the three
// shares add up to 100%; and how many are still flying, hit or not.
static void print_particles(const wx_sim_stats *st)
{
    double n = (double)st->particles_emitted;
    int64_t hit = st->particles_emitted - st->escaped_without_hit - st->alive_without_hit;
    printf("  particles  %lld emitted: %.1f%% hit the model, %.1f%% left without a hit, %.1f%% "
           "still flying without a hit; %lld hits; %lld (%.1f%%) still flying at the end\n",
           (long long)st->particles_emitted, 100.0 * (double)hit / n,
           100.0 * (double)st->escaped_without_hit / n, 100.0 * (double)st->alive_without_hit / n,
           (long long)st->collisions, (long long)st->alive, 100.0 * (double)st->alive / n);
}

// After a run, on stdout: where the particles ended, what they left (each
// substance on the surfaces at the start and at the end, and what they
// brought), and the main files written.
static void print_summary(const wx_scene *scene, const wx_run_def *opts, const wx_run_report *run,
                          const char *command_name, unsigned phases)
{
    printf("%s done in %.2f s; outputs in %s\n", command_name, run->times.total, opts->out_dir);
    const wx_sim_stats *st = &run->stats;
    if ((phases & WX_PHASE_SIMULATE) && st->particles_emitted > 0) {
        print_particles(st);
        for (int k = 0; k < st->substance_count; ++k) {
            const wx_substance_ledger *l = &st->substance[k];
            printf("  %-10s on the surfaces %.6g at the start, %.6g at the end (brought %.6g)\n",
                   st->substance_names[k], l->initial_surface, l->final_surface, l->emitted);
        }
    }
    if (!(phases & WX_PHASE_GATHER)) {
        return;
    }
    if (scene->output_index >= 0) {
        wx_output_describe(stdout, opts, scene->cameras[scene->output_index].output_file);
    }
    for (int t = 0; t < scene->texture_count; ++t) {
        const wx_texture_map *tm = &scene->textures[t];
        // One file, or one per UDIM tile.
        for (int f = 0; f < wx_texture_file_count(tm); ++f) {
            char name[WX_OUTPUT_NAME_MAX];
            if (tm->tiles == WX_TILES_UDIM) {
                wx_tile_name(tm->file, wx_texture_file_tile(tm, f), name, sizeof name);
            } else {
                snprintf(name, sizeof name, "%s", tm->file);
            }
            wx_output_describe(stdout, opts, name);
        }
    }
}

// Runs the phases in `phases` in order, in one process; a phase that is not run
// reads what an earlier command left in the output folder.
int cli_run_phases(const cli_args *args, unsigned phases)
{
    double start = wx_now_s();
    wx_run_report run;
    memset(&run, 0, sizeof run);
    wx_scene scene;
    wx_run_def opts;
    int status = cli_load_scene(args, &scene, &opts);
    if (status != WX_OK) {
        return status;
    }
    wx_error err;
    if (wx_dist_rank() > 0) {
        // Another rank of an MPI run, released by rank 0 (main.c): its share
        // of the simulation, no output.
        wx_result r = wx_simulate_follow(&scene, &opts, &err);
        wx_scene_free(&scene);
        return cli_report(r, &err);
    }
    run.times.load = wx_now_s() - start;
    wx_result r = WX_OK;
    if ((phases & WX_PHASE_GATHER) && scene.output_index < 0 && scene.texture_count == 0) {
        r = wx_fail(&err, WX_CAUSE_MISSING,
                    "%s: has no output camera (<Ortho out=\"true\">) and no <TextureMap>; `%s` "
                    "needs one",
                    scene.path, args->command);
    }
    if (r == WX_OK) {
        r = wx_run_phases(&scene, &opts, phases, &run, &err);
    }
    run.times.total = wx_now_s() - start;
    if (r == WX_OK && opts.stats_path != NULL) {
        r = wx_write_stats(opts.stats_path, &run.stats, &run.times, &run.noise, opts.threads,
                           opts.seed, &err);
    }
    if (r == WX_OK && !opts.quiet) {
        print_summary(&scene, &opts, &run, args->command, phases);
    }
    wx_noise_report_free(&run.noise);
    wx_scene_free(&scene);
    return cli_report(r, &err);
}

int command_bake(const cli_args *args)
{
    return cli_run_phases(args, WX_PHASE_BAKE);
}

int command_simulate(const cli_args *args)
{
    return cli_run_phases(args, WX_PHASE_SIMULATE);
}

int command_gather(const cli_args *args)
{
    return cli_run_phases(args, WX_PHASE_GATHER);
}
