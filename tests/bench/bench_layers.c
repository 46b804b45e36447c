// bench_layers.c: what layered depth maps cost (issue 26, item 7: with 4
// layers the simulation runs at least 0.5x the speed of one layer, and the
// memory estimate still bounds the peak).
//
// (a) Speed. The shipped house (xml_scenes/building.xml: sills, a balcony with
//     a railing, an overhanging roof, glass panes) is baked here twice by its
//     three 1024-pixel input cameras, once with one layer and once with
//     layers="4" (docs/design.md section 14), through the real bake, and the
//     simulation runs on each set of maps in memory: the same drops (spread
//     over the cameras' frame, 7.5 m either side of the house's axis, 0.1 to
//     13.5 m up, none inside a solid of either collider), falling at 3 m/s
//     under the scene's gravity, wind and turbulence, bouncing or sliding as
//     its impact maps say, up to 150 collisions each; the scene's own emitter
//     is left out. 40 steps after 3 of warm-up on 2 threads; the rate is
//     particle-steps per wall-clock second, the median of 3 runs, one layer
//     and four layers alternating; the ratio is the median of the three
//     back-to-back ratios (target >= 0.5).
// (b) Memory. `weathering init` writes a scene for the house's mesh (its
//     cameras hold layers="4"; --resolution 512, 256 with WX_BENCH_QUICK=1),
//     `weathering info` prints the estimate of its peak, and `weathering run`
//     runs it in a child process whose peak resident memory wait4 reports
//     (target: estimate >= peak). The same scene with layers="1" runs too,
//     for its peak and for the two runs' simulation rates (their --stats; one
//     run each, so no target): there the drops slide down the walls for most
//     of their steps, and the emitter, not the bench, makes them.
//
// Environment: WX_BENCH_PARTICLES (1000000; 250000 with WX_BENCH_QUICK=1),
// WX_BENCH_STEPS (40), WX_BENCH_LAYERS_PX (the resolution of (b)).
// Figures go to $WX_BENCH_CSV (bench_report.h); exit status 1 only on errors.
#define _XOPEN_SOURCE   700 // realpath
#define _DEFAULT_SOURCE     // wait4
#include <fcntl.h>
#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bench_report.h"
#include "bench_run.h"
#include "io/scene_xml.h"
#include "model/maps.h"
#include "model/scene.h"
#include "pipeline/bake_phase.h"
#include "pipeline/load.h"
#include "pipeline/outputs.h"
#include "pipeline/pipeline.h"
#include "sim/collider.h"
#include "sim/particles.h"
#include "sim/simulate.h"

enum { THREADS = 2, REPS = 3, MAX_COLLISIONS = 150 };

// --- (a) speed ----------------------------------------------------------------

// The house baked with some layers: its scene, the input cameras' maps and a
// collider of them (to keep drops out of solids).
typedef struct house {
    wx_scene scene;
    bool scene_loaded;
    int count, emitters;
    wx_camera cams[WX_MAX_INPUT_CAMERAS];
    wx_maps maps[WX_MAX_INPUT_CAMERAS];
    wx_collider collider;
    bool collider_ready;
} house;

static void house_free(house *h)
{
    if (h->collider_ready) {
        wx_collider_free(&h->collider);
    }
    for (int c = 0; c < h->count; ++c) {
        wx_maps_free(&h->maps[c]);
    }
    if (h->scene_loaded) {
        h->scene.emitter_count = h->emitters;
        wx_scene_free(&h->scene);
    }
    memset(h, 0, sizeof *h);
}

static bool house_load(house *h, const char *out_dir, int layers)
{
    memset(h, 0, sizeof *h);
    wx_error err;
    if (wx_scene_load("xml_scenes/building.xml", &h->scene, &err) != WX_OK) {
        fprintf(stderr, "bench_layers: %s\n", err.message);
        return false;
    }
    h->scene_loaded = true;
    for (int c = 0; c < h->scene.camera_count; ++c) {
        if (!h->scene.cameras[c].is_output) {
            h->scene.cameras[c].layers = layers;
        }
    }
    wx_run_def opts = wx_default_run_def(&h->scene);
    snprintf(opts.out_dir, sizeof opts.out_dir, "%s", out_dir);
    opts.threads = THREADS;
    opts.quiet = true;
    if (wx_output_prepare(&h->scene, &opts, NULL, &err) != WX_OK ||
        wx_bake_scene(&h->scene, &opts, &err) != WX_OK ||
        wx_use_baked_maps(&h->scene, &opts, &err) != WX_OK ||
        wx_load_simulation_maps(&h->scene, THREADS, NULL, h->maps, &err) != WX_OK) {
        fprintf(stderr, "bench_layers: %s\n", err.message);
        return false;
    }
    for (int c = 0; c < h->scene.camera_count; ++c) {
        if (!h->scene.cameras[c].is_output) {
            h->cams[h->count++] = h->scene.cameras[c].camera;
        }
    }
    if (wx_collider_init(&h->collider, h->cams, h->maps, h->count, false, &err) != WX_OK) {
        fprintf(stderr, "bench_layers: %s\n", err.message);
        return false;
    }
    h->collider_ready = true;
    // Only the drops below fly: the same ones on both sets of maps.
    h->emitters = h->scene.emitter_count;
    h->scene.emitter_count = 0;
    return true;
}

typedef struct drops {
    long count;
    float *p, *v; ///< 3 per drop
} drops;

// `count` drops in free space for both houses' colliders.
static bool drops_make(drops *d, long count, const house *a, const house *b)
{
    d->count = count;
    d->p = malloc((size_t)count * 3 * sizeof(float));
    d->v = malloc((size_t)count * 3 * sizeof(float));
    if (d->p == NULL || d->v == NULL) {
        return false;
    }
    uint64_t state = 2026;
    for (long i = 0; i < count;) {
        float r[5];
        for (int k = 0; k < 5; ++k) {
            state = wx_mix64(state + 1);
            r[k] = (float)((state >> 40) * (1.0 / 16777216.0));
        }
        float p[3] = { -7.5f + 15 * r[0], 0.1f + 13.4f * r[1], -7.5f + 15 * r[2] };
        if (wx_collider_point_collides(&a->collider, p) ||
            wx_collider_point_collides(&b->collider, p)) {
            continue;
        }
        memcpy(&d->p[3 * i], p, sizeof p);
        d->v[3 * i] = r[3] - 0.5f;
        d->v[3 * i + 1] = -3.0f;
        d->v[3 * i + 2] = r[4] - 0.5f;
        ++i;
    }
    return true;
}

typedef struct result {
    double rate;         ///< particle-steps per second, wall clock
    double collide_frac; ///< collisions per particle-step
} result;

static bool run_once(const house *h, const drops *d, long steps, result *out)
{
    wx_sim_def cfg = wx_default_sim_def(&h->scene);
    cfg.threads = THREADS;
    cfg.maps = h->maps;
    wx_sim *sim = NULL;
    wx_error err;
    if (wx_sim_create(&h->scene, &cfg, &sim, &err) != WX_OK) {
        fprintf(stderr, "bench_layers: %s\n", err.message);
        return false;
    }
    for (long i = 0; i < d->count; ++i) {
        if (wx_sim_spawn(sim, &d->p[3 * i], &d->v[3 * i], 1.0f, 1.0, MAX_COLLISIONS, &err) !=
            WX_OK) {
            fprintf(stderr, "bench_layers: %s\n", err.message);
            wx_sim_destroy(sim);
            return false;
        }
    }
    for (int s = 0; s < 3; ++s) {
        wx_sim_step(sim, &err);
    }
    wx_sim_stats before, after;
    wx_sim_get_stats(sim, &before);
    double t0 = bench_now_s();
    for (long s = 0; s < steps; ++s) {
        wx_sim_step(sim, &err);
    }
    double t1 = bench_now_s();
    wx_sim_get_stats(sim, &after);
    double done = (double)(after.particle_steps - before.particle_steps);
    out->rate = done / (t1 - t0);
    out->collide_frac = (double)(after.collisions - before.collisions) / done;
    wx_sim_destroy(sim);
    return true;
}

static bool speed(long particles, long steps)
{
    char program[PATH_MAX], dir[PATH_MAX], out[PATH_MAX + 16];
    if (!bench_workdir("bench_layers", program, dir)) {
        return false;
    }
    house one, four;
    snprintf(out, sizeof out, "%s/l1", dir);
    double t0 = bench_now_s();
    bool ok = house_load(&one, out, 1);
    double bake_one = bench_now_s() - t0;
    snprintf(out, sizeof out, "%s/l4", dir);
    t0 = bench_now_s();
    ok = ok && house_load(&four, out, 4);
    double bake_four = bench_now_s() - t0;
    drops d = { 0 };
    ok = ok && drops_make(&d, particles, &one, &four);
    result runs[2][REPS];
    double ratio[REPS];
    for (int rep = 0; ok && rep < REPS; ++rep) {
        ok = run_once(&one, &d, steps, &runs[0][rep]) && run_once(&four, &d, steps, &runs[1][rep]);
        if (ok) {
            ratio[rep] = runs[1][rep].rate / runs[0][rep].rate;
            printf("  run %d: 1 layer %.1f M/s, 4 layers %.1f M/s (%.2fx)\n", rep + 1,
                   runs[0][rep].rate / 1e6, runs[1][rep].rate / 1e6, ratio[rep]);
            fflush(stdout);
        }
    }
    house_free(&one);
    house_free(&four);
    free(d.p);
    free(d.v);
    if (!ok) {
        return false;
    }
    double rate[2], frac[2];
    for (int l = 0; l < 2; ++l) {
        double r[REPS], f[REPS];
        for (int rep = 0; rep < REPS; ++rep) {
            r[rep] = runs[l][rep].rate;
            f[rep] = runs[l][rep].collide_frac;
        }
        rate[l] = bench_median(r, REPS);
        frac[l] = bench_median(f, REPS);
    }
    double up = bench_median(ratio, REPS);
    printf("(a) the house, 3 cameras of 1024 px, %ldk drops, %ld steps, %d threads, median of %d:\n"
           "    1 layer %.1f M steps/s (%.2f%% collisions; bake and load %.1f s)\n"
           "    4 layers %.1f M steps/s (%.2f%% collisions; bake and load %.1f s)\n"
           "    layered speed ratio %.2f (target >= 0.5: %s)\n",
           particles / 1000, steps, THREADS, REPS, rate[0] / 1e6, 100.0 * frac[0], bake_one,
           rate[1] / 1e6, 100.0 * frac[1], bake_four, up, up >= 0.5 ? "met" : "MISSED");
    for (int l = 0; l < 2; ++l) {
        bench_row("layers", "M steps/s", rate[l] / 1e6, "M/s", NULL, false,
                  "house %d layer%s 3 cams 1024 px %ldk drops %d thr", l == 0 ? 1 : 4,
                  l == 0 ? "" : "s", particles / 1000, THREADS);
        bench_row("layers", "collisions per step", 100.0 * frac[l], "%", NULL, false,
                  "house %d layer%s 3 cams 1024 px", l == 0 ? 1 : 4, l == 0 ? "" : "s");
    }
    bench_row("layers", "layered speed ratio", up, "x", ">= 0.5", up >= 0.5,
              "house 4 layers / 1 layer; median of %d paired runs", REPS);
    return true;
}

// --- (b) memory -----------------------------------------------------------------

// Runs `weathering run SCENE --out OUT --stats OUT.json` in `dir` and returns its
// peak resident memory in MiB: the run's own `peak_memory_mib` (its address
// space's high-water mark). wait4's ru_maxrss is no measure here: a child
// forked from this benchmark keeps the benchmark's own peak (part (a) ran a
// simulation in this process) as its ru_maxrss. -1 when the run fails.
static double json_number(const char *text, const char *key);
static double run_peak_mib(const char *program, const char *dir, const char *scene, const char *out)
{
    char stats[64];
    snprintf(stats, sizeof stats, "%s.json", out);
    pid_t pid = fork();
    if (pid == 0) {
        int null = open("/dev/null", O_WRONLY);
        dup2(null, STDOUT_FILENO);
        dup2(null, STDERR_FILENO);
        if (chdir(dir) != 0) {
            _exit(97);
        }
        execl(program, program, "run", scene, "--out", out, "--threads", "2", "--stats", stats,
              "-q", (char *)NULL);
        _exit(98);
    }
    int status = 0;
    if (pid < 0 || waitpid(pid, &status, 0) != pid || !WIFEXITED(status) ||
        WEXITSTATUS(status) != 0) {
        fprintf(stderr, "bench_layers: `weathering run %s` failed in %s\n", scene, dir);
        return -1.0;
    }
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/%s", dir, stats);
    char *json = ensure_read_file(path);
    double peak = json_number(json, "\"peak_memory_mib\": ");
    free(json);
    return peak;
}

// The number after `key` in `text`, or -1.
static double json_number(const char *text, const char *key)
{
    const char *at = text != NULL ? strstr(text, key) : NULL;
    return at != NULL ? atof(at + strlen(key)) : -1.0;
}

// The simulation's rate of a run (its --stats): particle-steps over the
// seconds of the steps.
static double run_rate(const char *dir, const char *out, double *steps)
{
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/%s.json", dir, out);
    char *stats = ensure_read_file(path);
    *steps = json_number(stats, "\"particle_steps\": ");
    double seconds = json_number(stats, "\"steps\": ");
    free(stats);
    return *steps > 0.0 && seconds > 0.0 ? *steps / seconds : 0.0;
}

static bool memory(int px)
{
    char program[PATH_MAX], dir[PATH_MAX];
    if (!bench_workdir("bench_layers", program, dir)) {
        return false;
    }
    // house.xml as init writes it (layers="4"), house1.xml the same with one.
    char cmd[4 * PATH_MAX];
    snprintf(cmd, sizeof cmd,
             "cp xml_scenes/meshes/building.obj xml_scenes/meshes/building.mtl '%s/meshes/' && "
             "cd '%s' && '%s' init meshes/building.obj -o house.xml --resolution %d --force "
             ">/dev/null && sed 's/layers=\"4\"/layers=\"1\"/' house.xml > house1.xml",
             dir, dir, program, px);
    if (system(cmd) != 0) {
        fprintf(stderr, "bench_layers: failed: %s\n", cmd);
        return false;
    }
    char path[PATH_MAX + 32];
    snprintf(path, sizeof path, "%s/house.xml", dir);
    char *scene = ensure_read_file(path);
    int layered = 0;
    for (const char *s = scene; s != NULL && (s = strstr(s, "layers=\"4\"")) != NULL; ++s) {
        layered++;
    }
    free(scene);
    snprintf(path, sizeof path, "%s/info.txt", dir);
    snprintf(cmd, sizeof cmd, "cd '%s' && '%s' info house.xml > info.txt", dir, program);
    char *info = system(cmd) == 0 ? ensure_read_file(path) : NULL;
    double estimate = json_number(info, "memory: about ");
    free(info);
    double t0 = bench_now_s();
    double peak = run_peak_mib(program, dir, "house.xml", "run4");
    double seconds = bench_now_s() - t0;
    double peak_one = run_peak_mib(program, dir, "house1.xml", "run1");
    if (estimate <= 0.0 || peak <= 0.0 || peak_one <= 0.0) {
        fprintf(stderr, "bench_layers: no estimate (%g) or no peak (%g, %g)\n", estimate, peak,
                peak_one);
        return false;
    }
    double steps, steps_one;
    double rate = run_rate(dir, "run4", &steps);
    double rate_one = run_rate(dir, "run1", &steps_one);
    printf("(b) `weathering init` of the house at %d px (%d cameras with layers=\"4\"), run in "
           "%.1f s:\n"
           "    estimate %.0f MiB, peak %.0f MiB (%.2fx; target estimate >= peak: %s); "
           "with layers=\"1\" the peak is %.0f MiB\n"
           "    its simulation: %.1f M steps/s over %.0f M particle-steps; with layers=\"1\" "
           "%.1f M steps/s over %.0f M (%.2fx; one run each)\n",
           px, layered, seconds, estimate, peak, estimate / peak,
           estimate >= peak ? "met" : "MISSED", peak_one, rate / 1e6, steps / 1e6, rate_one / 1e6,
           steps_one / 1e6, rate / rate_one);
    bench_row("layers", "memory estimate", estimate, "MiB", NULL, false,
              "init house %d px %d cams 4 layers (weathering info)", px, layered);
    bench_row("layers", "peak RSS", peak, "MiB", NULL, false,
              "init house %d px %d cams 4 layers (weathering run)", px, layered);
    bench_row("layers", "estimate / peak", estimate / peak, "x", ">= 1", estimate >= peak,
              "init house %d px %d cams 4 layers", px, layered);
    bench_row("layers", "peak RSS", peak_one, "MiB", NULL, false,
              "init house %d px %d cams 1 layer (weathering run)", px, layered);
    bench_row("layers", "M steps/s", rate / 1e6, "M/s", NULL, false,
              "init house %d px %d cams 4 layers (weathering run; one run)", px, layered);
    bench_row("layers", "M steps/s", rate_one / 1e6, "M/s", NULL, false,
              "init house %d px %d cams 1 layer (weathering run; one run)", px, layered);
    bench_row("layers", "layered speed ratio", rate / rate_one, "x", NULL, false,
              "init house %d px %d cams 4 layers / 1 layer (weathering run; one run each)", px,
              layered);
    return true;
}

int main(void)
{
    bool quick = bench_env_long("WX_BENCH_QUICK", 0) == 1;
    long particles = bench_env_long("WX_BENCH_PARTICLES", quick ? 250000 : 1000000);
    long steps = bench_env_long("WX_BENCH_STEPS", 40);
    int px = (int)bench_env_long("WX_BENCH_LAYERS_PX", quick ? 256 : 512);
    printf("layers: what layered depth maps cost (issue 26, item 7)\n");
    fflush(stdout);
    bool ok = speed(particles, steps);
    ok = memory(px) && ok;
    return ok ? 0 : 1;
}
