// main.c: weathering-viewer, the live view of a simulation (thesis 4.8.5,
// docs/design.md sections 1 and 6; docs/viewer.md is the user's guide).
//
//   weathering-viewer SCENE.xml [--out DIR] [--threads N] [--size WxH]
//                     [--screenshot FILE.png] [--frames N] [--steps-per-frame K]
//                     [--substance NAME] [--mask NAME] [-v]
//
// The scene is read (and baked, by `weathering bake` in a child process) before
// any window opens, so bad input is reported with exit status 2 even without a
// display. The simulation is the library's, stepped at the scene's fixed time
// step: interactively as many steps per frame as real time asks for, within a
// time budget so the window stays responsive; with --frames, a fixed number per
// frame so that a screenshot is reproducible.
#include <errno.h>
#include <inttypes.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bake_child.h"
#include "core/usage.h"
#include "draw.h"
#include "overlay.h"
#include "screenshot.h"
#include "view.h"
#include "world.h"
#include "core/limits.h"
#include "sim/simulate.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

enum {
    DEFAULT_WIDTH = 1024,
    DEFAULT_HEIGHT = 640,
    HIT_CAPACITY = 16384,
    MAX_TOGGLE_CAMERAS = 9,
};

static const double STEP_BUDGET_S = 0.025; ///< wall-clock stepping per frame, at most
static const double MIN_SPEED = 1.0 / 16.0, MAX_SPEED = 256.0;

typedef struct timing {
    int frames;
    int64_t steps;
    double sim_s, upload_s, draw_s, total_s;
    int64_t max_particles;
    int64_t drawn_particles; ///< summed over frames: particles drawn (nearest per pixel)
    int64_t drawn_samples;   ///< summed over frames: depth samples drawn
} timing;

typedef struct app {
    vw_settings settings;
    char exe_dir[WX_PATH_MAX];
    bool verbose;
    const char *screenshot; ///< --screenshot, or NULL
    int frames;             ///< --frames: run this many frames and exit (0 = until closed)
    int steps_per_frame;    ///< with --frames
    bool gather_at_end;     ///< --gather: gather after the last of --frames
    const char *substance;  ///< --substance: shown first, or NULL (the first)
    const char *mask;       ///< --mask: the derived mask shown first, or NULL (none)
    int mask_request;       ///< M: a mask to compute after the frame that says so, or -1
    int width, height;

    vw_world *world;        ///< the running scene
    vw_world *pending;      ///< a reloaded scene whose maps are being baked
    vw_bake_child bake;

    GLFWwindow *window;
    vw_draw draw;
    vw_overlay overlay;
    vw_orbit orbit;
    bool *camera_visible;   ///< per scene camera of the running world
    vw_show show;

    bool playing;
    bool help;
    double speed;           ///< simulated seconds per wall-clock second
    double step_debt;       ///< steps owed to real time
    double last_frame_s;

    bool rotating, panning;
    double cursor_x, cursor_y;

    double rate_t0;         ///< steps and frames per second, over about half a second
    int64_t rate_steps;
    int rate_frames;
    double steps_per_s, frames_per_s;
    double title_s;

    char message[WX_ERROR_MAX + 64];
    bool message_is_error;
    timing timing;
} app;

static const char *const KEY_HELP[] = {
    "mouse: left drag orbit, right or middle drag pan, scroll zoom",
    "space    play / pause (at the end: start again)",
    "N        one step",
    "R        reload the scene file",
    "G        gather: save the dirt maps and the mask",
    "H        hit points on / off",
    "1-9      camera 1-9 on / off (scene order)",
    "D        depth samples on / off",
    "L        layers of the depth samples and hits: all, 0, 1, ..., the deepest, all",
    "P        particles on / off",
    "S        next substance: what particles and deposits show",
    "M        next derived mask on the depth samples (<Masks>; off, 1, 2, ..., off)",
    "+ / -    simulation speed x2 / /2",
    "Backspace  start the simulation again",
    "Home     frame the cameras again",
    "F1       this help",
    "Esc, Q   quit",
};
enum { KEY_HELP_COUNT = sizeof KEY_HELP / sizeof KEY_HELP[0] };

static const char *const COLOUR_HELP[] = {
    "colours: input cameras blue, green, magenta, yellow, cyan, orange, ...;",
    "  output camera white; depth samples in their camera's colour,",
    "  deeper layers darker (layer 1 at 70%, 2 at 50%, ...);",
    "  particles pale blue (clean) to brown (carrying dirt), or to the",
    "  colour of the substance shown (S); with <Substances>, depth samples",
    "  tinted towards it where it lies on their surface;",
    "  with a mask (M): depth samples dark violet (0) through crimson and",
    "  orange to pale yellow (1); curvature blue concave, grey flat, red convex;",
    "  hits red absorbed, pale yellow bounced, pale green slid;",
    "  emitters pink; bounding box grey",
};
enum { COLOUR_HELP_COUNT = sizeof COLOUR_HELP / sizeof COLOUR_HELP[0] };

// --- messages ----------------------------------------------------------------------

static void print_usage(FILE *out)
{
    fprintf(out,
            "usage: weathering-viewer SCENE.xml [options]\n"
            "\n"
            "Shows the weathering simulation of a scene live: cameras, depth samples,\n"
            "emitters, particles and hit points. Press F1 in the window for the keys.\n"
            "\n"
            "options:\n"
            "  --out DIR             output folder (default: out/<scene name>/)\n"
            "  --threads N           simulation threads (default: all cores)\n"
            "  --size WxH            window size (default: %dx%d)\n"
            "  --screenshot FILE.png save the framebuffer after the last frame and exit\n"
            "  --frames N            run N frames and exit (default with --screenshot: 1)\n"
            "  --steps-per-frame K   simulation steps per frame with --frames (default 1)\n"
            "  --gather              with --frames: save the dirt maps and the mask at the end\n"
            "  --substance NAME      show this substance first (default: the first)\n"
            "  --mask NAME           show this derived mask (<Masks>) on the depth samples\n"
            "                        (default: none; M cycles through them)\n"
            "  -v, --verbose         timing at exit on stderr\n"
            "  -h, --help            this help\n"
            "\n"
            "exit status: 0 success, 2 bad usage or bad input, 1 other failure\n"
            "documentation: docs/viewer.md\n",
            DEFAULT_WIDTH, DEFAULT_HEIGHT);
}

static void print_key_help(void)
{
    printf("weathering-viewer keys:\n");
    for (int k = 0; k < KEY_HELP_COUNT; ++k) {
        printf("  %s\n", KEY_HELP[k]);
    }
    for (int k = 0; k < COLOUR_HELP_COUNT; ++k) {
        printf("%s\n", COLOUR_HELP[k]);
    }
    fflush(stdout);
}

static void update_title(app *a);

// A message for the user: stderr for errors, stdout otherwise, and the overlay.
static void report(app *a, bool is_error, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void report(app *a, bool is_error, const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    vsnprintf(a->message, sizeof a->message, fmt, args);
    va_end(args);
    a->message_is_error = is_error;
    FILE *out = is_error ? stderr : stdout;
    fprintf(out, "weathering-viewer: %s\n", a->message);
    fflush(out);
    update_title(a);
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

// What the shown mask's colours mean; `seconds` it took to compute (< 0: it
// was known), said only interactively (a run of --frames gives the same
// pixels every time).
static void report_mask(app *a, double seconds)
{
    const vw_world *w = a->world;
    int m = w->mask;
    if (m < 0) {
        report(a, false, "mask off: depth samples in their cameras' colours%s",
               vw_world_shows_deposits(w) ? ", tinted by the substance shown" : "");
        return;
    }
    char took[64] = "";
    if (seconds >= 0.0 && a->frames == 0) {
        snprintf(took, sizeof took, " (computed in %.1f s)", seconds);
    }
    const wx_mask_def *md = &w->scene.masks[m];
    if (md->kind == WX_MASK_CURVATURE) {
        report(a, false,
               "mask %s %d/%d (curvature) on the depth samples: blue concave, grey flat, red "
               "convex, full colour at |curvature| %.3g per unit (99th percentile)%s",
               md->name, m + 1, w->scene.mask_count, (double)w->mask_scale[m], took);
    } else {
        report(a, false,
               "mask %s %d/%d (%s) on the depth samples: dark violet 0 to pale yellow 1%s",
               md->name, m + 1, w->scene.mask_count, vw_world_mask_kind_name(w, m), took);
    }
}

// Says that mask m is being computed: rays per sample, how many samples.
static void report_computing(app *a, const char *prefix, int m)
{
    const vw_world *w = a->world;
    const wx_mask_def *md = &w->scene.masks[m];
    char rays[64] = "";
    if (wx_mask_rays(md) > 0) {
        snprintf(rays, sizeof rays, ", %d ray%s a sample", wx_mask_rays(md),
                 wx_mask_rays(md) == 1 ? "" : "s");
    }
    report(a, false, "%scomputing mask %s (%s%s) at %d depth samples ...", prefix, md->name,
           vw_world_mask_kind_name(w, m), rays, w->point_count);
}

// Computes the mask M asked for (after the frame that said so) and shows it.
static void compute_requested_mask(app *a)
{
    int m = a->mask_request;
    a->mask_request = -1;
    if (m < 0 || m >= vw_world_mask_count(a->world)) {
        return;
    }
    wx_error err;
    double t0 = now_s();
    if (vw_world_show_mask(a->world, m, &err) != WX_OK) {
        report(a, true, "mask %s: %s", a->world->scene.masks[m].name, err.message);
        return;
    }
    report_mask(a, now_s() - t0);
    a->last_frame_s = glfwGetTime(); // the time it took is not owed to the simulation
    a->step_debt = 0.0;
}

// --- arguments ------------------------------------------------------------------------

static int usage_error(const char *fmt, const char *detail)
{
    return wx_usage_error("weathering-viewer", fmt, detail);
}

static bool parse_int(const char *text, int lo, int hi, int *out)
{
    uint64_t v = 0;
    if (!wx_parse_whole(text, (uint64_t)lo, (uint64_t)hi, &v)) {
        return false;
    }
    *out = (int)v;
    return true;
}

// Returns -1 to go on, else an exit status.
static int parse_args(int argc, char **argv, app *a)
{
    a->width = DEFAULT_WIDTH;
    a->height = DEFAULT_HEIGHT;
    a->steps_per_frame = 1;
    a->settings.hit_capacity = HIT_CAPACITY;
    for (int i = 1; i < argc; ++i) {
        const char *arg = argv[i];
        const char *value = i + 1 < argc ? argv[i + 1] : NULL;
        bool takes_value = strcmp(arg, "--out") == 0 || strcmp(arg, "--threads") == 0 ||
                           strcmp(arg, "--size") == 0 || strcmp(arg, "--screenshot") == 0 ||
                           strcmp(arg, "--frames") == 0 || strcmp(arg, "--steps-per-frame") == 0 ||
                           strcmp(arg, "--substance") == 0 || strcmp(arg, "--mask") == 0;
        if (takes_value && value == NULL) {
            return usage_error("%s needs a value", arg);
        }
        if (strcmp(arg, "-h") == 0 || strcmp(arg, "--help") == 0) {
            print_usage(stdout);
            return 0;
        } else if (strcmp(arg, "--gather") == 0) {
            a->gather_at_end = true;
        } else if (strcmp(arg, "-v") == 0 || strcmp(arg, "--verbose") == 0) {
            a->verbose = true;
        } else if (strcmp(arg, "--out") == 0) {
            if (value[0] == '\0') {
                return usage_error("%s needs a folder name", arg);
            }
            a->settings.out_dir = value;
        } else if (strcmp(arg, "--threads") == 0) {
            if (!parse_int(value, 1, 1024, &a->settings.threads)) {
                return usage_error("--threads takes a whole number from 1 to 1024, not '%s'",
                                   value);
            }
        } else if (strcmp(arg, "--size") == 0) {
            char w[16] = "", h[16] = "";
            const char *x = strchr(value, 'x');
            if (x == NULL || x - value >= (ptrdiff_t)sizeof w || strlen(x + 1) >= sizeof h) {
                return usage_error("--size takes WIDTHxHEIGHT, not '%s'", value);
            }
            memcpy(w, value, (size_t)(x - value));
            snprintf(h, sizeof h, "%s", x + 1);
            if (!parse_int(w, 64, 16384, &a->width) || !parse_int(h, 64, 16384, &a->height)) {
                return usage_error("--size takes WIDTHxHEIGHT (64 to 16384 each), not '%s'", value);
            }
        } else if (strcmp(arg, "--screenshot") == 0) {
            if (value[0] == '\0') {
                return usage_error("%s needs a file name", arg);
            }
            a->screenshot = value;
        } else if (strcmp(arg, "--substance") == 0) {
            if (value[0] == '\0') {
                return usage_error("%s needs a substance name", arg);
            }
            a->substance = value;
        } else if (strcmp(arg, "--mask") == 0) {
            if (value[0] == '\0') {
                return usage_error("%s needs a mask name", arg);
            }
            a->mask = value;
        } else if (strcmp(arg, "--frames") == 0) {
            if (!parse_int(value, 1, 100000000, &a->frames)) {
                return usage_error("--frames takes a whole number from 1, not '%s'", value);
            }
        } else if (strcmp(arg, "--steps-per-frame") == 0) {
            if (!parse_int(value, 0, 1000000, &a->steps_per_frame)) {
                return usage_error("--steps-per-frame takes a whole number from 0, not '%s'",
                                   value);
            }
        } else if (arg[0] == '-' && arg[1] != '\0') {
            return usage_error("unknown option '%s'", arg);
        } else if (a->settings.scene_path == NULL) {
            a->settings.scene_path = arg;
        } else {
            return usage_error("unexpected argument '%s'", arg);
        }
        i += takes_value ? 1 : 0;
    }
    if (a->settings.scene_path == NULL) {
        print_usage(stderr);
        return WX_BAD_INPUT;
    }
    if (a->screenshot != NULL && a->frames == 0) {
        a->frames = 1;
    }
    if (a->gather_at_end && a->frames == 0) {
        return usage_error("%s needs --frames N", "--gather");
    }
    return -1;
}

// --- the world ---------------------------------------------------------------------------

static bool reset_camera_visibility(app *a)
{
    int n = a->world->scene.camera_count;
    bool *visible = realloc(a->camera_visible, (size_t)(n > 0 ? n : 1) * sizeof *visible);
    if (visible == NULL) {
        return false;
    }
    for (int c = 0; c < n; ++c) {
        visible[c] = true;
    }
    a->camera_visible = visible;
    a->show.cameras = visible;
    return true;
}

static void reset_rates(app *a)
{
    a->rate_t0 = glfwGetTime();
    a->rate_steps = 0;
    a->rate_frames = 0;
    a->step_debt = 0.0;
}

// Makes a completed world the running one (reload).
static void adopt_world(app *a, vw_world *world)
{
    int old_cameras = a->world->scene.camera_count;
    vw_world_keep_substance(world, vw_world_substance_name(a->world));
    // The mask shown (or about to be) is shown again by name, computed anew
    // for the new maps after the next frame.
    int old_mask = a->mask_request >= 0 ? a->mask_request : a->world->mask;
    int mask = old_mask >= 0 ? vw_world_find_mask(world, a->world->scene.masks[old_mask].name) : -1;
    a->mask_request = mask;
    vw_world_free(a->world);
    free(a->world);
    a->world = world;
    wx_error err;
    if (vw_draw_set_world(&a->draw, world, &err) != WX_OK) {
        report(a, true, "%s", err.message);
    }
    if (world->scene.camera_count != old_cameras && !reset_camera_visibility(a)) {
        report(a, true, "out of memory");
    }
    if (a->show.layer >= world->max_layers) {
        a->show.layer = -1; // the new scene has fewer layers: show them all
    }
    reset_rates(a);
    a->playing = true;
    if (mask >= 0) {
        char prefix[WX_PATH_MAX + 32];
        snprintf(prefix, sizeof prefix, "reloaded %s; ", world->scene.path);
        report_computing(a, prefix, mask);
    } else {
        report(a, false, "reloaded %s", world->scene.path);
    }
}

static void finish_reload(app *a, vw_world *world)
{
    wx_error err;
    if (vw_world_finish(world, &a->settings, &err) != WX_OK) {
        report(a, true, "reload failed, the last good scene keeps running: %s", err.message);
        vw_world_free(world);
        free(world);
        return;
    }
    adopt_world(a, world);
}

static void cancel_pending(app *a)
{
    if (a->pending != NULL) {
        vw_bake_cancel(&a->bake);
        vw_world_free(a->pending);
        free(a->pending);
        a->pending = NULL;
    }
}

static void reload(app *a)
{
    cancel_pending(a);
    vw_world *world = calloc(1, sizeof *world);
    if (world == NULL) {
        report(a, true, "reload failed: out of memory");
        return;
    }
    wx_error err;
    if (vw_world_parse(world, &a->settings, &err) != WX_OK) {
        report(a, true, "reload failed, the last good scene keeps running: %s", err.message);
        free(world);
        return;
    }
    if (!vw_world_needs_bake(world, a->world)) {
        finish_reload(a, world);
        return;
    }
    if (vw_bake_start(&a->bake, a->exe_dir, world->scene.path, world->opts.out_dir, &err) !=
        WX_OK) {
        report(a, true, "reload failed: %s", err.message);
        vw_world_free(world);
        free(world);
        return;
    }
    a->pending = world;
    report(a, false, "baking the maps of %s in %s ...", world->scene.path, world->opts.out_dir);
}

static void poll_pending(app *a)
{
    int status = 0;
    if (a->pending == NULL || !vw_bake_poll(&a->bake, false, &status)) {
        return;
    }
    vw_world *world = a->pending;
    a->pending = NULL;
    if (status != 0) {
        report(a, true, "reload failed: `weathering bake` exited with status %d%s%s", status,
               a->bake.last_line[0] ? ": " : "", a->bake.last_line);
        vw_world_free(world);
        free(world);
        return;
    }
    finish_reload(a, world);
}

// Runs the first load to completion; returns an exit status, or -1 on success.
static int load_first_world(app *a)
{
    a->world = calloc(1, sizeof *a->world);
    if (a->world == NULL) {
        fprintf(stderr, "weathering-viewer: out of memory\n");
        return WX_FAIL;
    }
    wx_error err;
    wx_result r = vw_world_parse(a->world, &a->settings, &err);
    if (r != WX_OK) {
        fprintf(stderr, "weathering-viewer: %s\n", err.message);
        return r;
    }
    int substance = a->substance != NULL ? vw_world_find_substance(a->world, a->substance) : 0;
    if (substance < 0) {
        const wx_scene *scene = &a->world->scene;
        fprintf(stderr, "weathering-viewer: --substance %s: %s has no such substance (it has",
                a->substance, scene->path);
        for (int s = 0; s < scene->substance_count; ++s) {
            fprintf(stderr, "%s %s", s > 0 ? "," : "", scene->substances[s]);
        }
        fprintf(stderr, ")\n");
        return WX_BAD_INPUT;
    }
    int mask = a->mask != NULL ? vw_world_find_mask(a->world, a->mask) : -1;
    if (a->mask != NULL && mask < 0) {
        const wx_scene *scene = &a->world->scene;
        fprintf(stderr, "weathering-viewer: --mask %s: %s has no such mask (%s", a->mask,
                scene->path, scene->mask_count > 0 ? "it has" : "it has no <Masks>");
        for (int m = 0; m < scene->mask_count; ++m) {
            fprintf(stderr, "%s %s", m > 0 ? "," : "", scene->masks[m].name);
        }
        fprintf(stderr, ")\n");
        return WX_BAD_INPUT;
    }
    if (vw_world_needs_bake(a->world, NULL)) {
        fprintf(stderr, "weathering-viewer: baking the maps of %s into %s\n",
                a->world->scene.path, a->world->opts.out_dir);
        r = vw_bake_start(&a->bake, a->exe_dir, a->world->scene.path, a->world->opts.out_dir,
                          &err);
        if (r != WX_OK) {
            fprintf(stderr, "weathering-viewer: %s\n", err.message);
            return r;
        }
        int status = 0;
        vw_bake_poll(&a->bake, true, &status);
        if (status != 0) {
            fprintf(stderr, "weathering-viewer: `weathering bake %s` failed (exit status %d)\n",
                    a->world->scene.path, status);
            return status == WX_BAD_INPUT ? WX_BAD_INPUT : WX_FAIL;
        }
    }
    r = vw_world_finish(a->world, &a->settings, &err);
    if (r != WX_OK) {
        fprintf(stderr, "weathering-viewer: %s\n", err.message);
        return r;
    }
    vw_world_show_substance(a->world, substance);
    if (mask >= 0) {
        report_computing(a, "", mask);
        double t0 = now_s();
        r = vw_world_show_mask(a->world, mask, &err);
        if (r != WX_OK) {
            fprintf(stderr, "weathering-viewer: mask %s: %s\n", a->mask, err.message);
            return r;
        }
        report_mask(a, now_s() - t0);
    }
    return -1;
}

// --- simulation ------------------------------------------------------------------------------

// One step, unless the simulation has run the scene's steps.
static bool step_once(app *a)
{
    wx_error err;
    if (vw_world_finished(a->world)) {
        return false;
    }
    if (wx_sim_step(a->world->sim, &err) != WX_OK) {
        a->playing = false;
        report(a, true, "simulation stopped: %s", err.message);
        return false;
    }
    a->rate_steps++;
    a->timing.steps++;
    return true;
}

static bool restart(app *a)
{
    wx_error err;
    if (vw_world_restart(a->world, &a->settings, &err) != WX_OK) {
        report(a, true, "cannot start again: %s", err.message);
        return false;
    }
    reset_rates(a);
    a->playing = true;
    return true;
}

// Steps the simulation for this frame: a fixed count with --frames, else what
// real time asks for at the chosen speed, within STEP_BUDGET_S.
static void advance(app *a, double now)
{
    double wall_dt = now - a->last_frame_s;
    a->last_frame_s = now;
    if (!a->playing) {
        a->step_debt = 0.0;
        return;
    }
    if (a->frames > 0) {
        for (int k = 0; k < a->steps_per_frame && step_once(a); ++k) {
        }
    } else {
        wall_dt = wall_dt < 0.25 ? wall_dt : 0.25;
        a->step_debt += wall_dt * a->speed / a->world->scene.time_step;
        double deadline = now + STEP_BUDGET_S;
        while (a->step_debt >= 1.0 && step_once(a)) {
            a->step_debt -= 1.0;
            if (glfwGetTime() > deadline) {
                break;
            }
        }
        // What did not fit in the budget is dropped: slower than real time, but
        // the window stays responsive.
        a->step_debt = a->step_debt < 1.0 ? a->step_debt : 1.0;
    }
    if (a->playing && vw_world_finished(a->world)) {
        a->playing = false;
        report(a, false,
               "simulation finished after %" PRId64 " steps; G saves the mask, space starts "
               "again",
               wx_sim_step_count(a->world->sim));
    }
}

static wx_result gather(app *a)
{
    if (a->window != NULL) {
        glfwSetWindowTitle(a->window, "weathering-viewer: gathering ...");
    }
    char saved[WX_PATH_MAX];
    wx_error err;
    double t0 = glfwGetTime();
    wx_result r = vw_world_gather(a->world, saved, &err);
    if (r != WX_OK) {
        report(a, true, "gather failed: %s", err.message);
        return r;
    }
    double t = glfwGetTime() - t0;
    if (a->world->scene.output_index < 0) {
        report(a, false, "saved the dirt maps in %s (no output camera, so no mask) at t = %.3f s",
               saved, wx_sim_time(a->world->sim));
    } else {
        report(a, false, "saved the mask %s at t = %.3f s (%.1f s)", saved,
               wx_sim_time(a->world->sim), t);
    }
    return WX_OK;
}

// --- window and input ------------------------------------------------------------------------

static void status_line(const app *a, bool live, char *out, size_t cap)
{
    const vw_world *w = a->world;
    wx_particle_view view;
    wx_sim_particles(w->sim, &view);
    const char *state = vw_world_finished(w) ? "finished" : a->playing ? "playing" : "paused";
    int n = snprintf(out, cap, "%s  t %.3f s  step %" PRId64 "/%" PRId64, w->scene.name,
                     wx_sim_time(w->sim), wx_sim_step_count(w->sim), vw_world_total_steps(w));
    if (w->scene.iterations > 1 && n > 0 && (size_t)n < cap) {
        int64_t done = wx_sim_iterations_done(w->sim);
        n += snprintf(out + n, cap - (size_t)n, "  iteration %" PRId64 "/%d",
                      done < w->scene.iterations ? done + 1 : done, w->scene.iterations);
    }
    if (n > 0 && (size_t)n < cap) {
        n += snprintf(out + n, cap - (size_t)n, "  %" PRId64 " particles  %s", view.count, state);
    }
    // The substance shown, in scenes that declare theirs (without, it is dirt).
    if (w->scene.substances_declared && n > 0 && (size_t)n < cap) {
        n += snprintf(out + n, cap - (size_t)n, "  substance %s %d/%d",
                      vw_world_substance_name(w), w->substance + 1,
                      vw_world_substance_count(w));
    }
    // The layer shown, in scenes with a layered camera (L).
    if (w->max_layers > 1 && n > 0 && (size_t)n < cap) {
        if (a->show.layer < 0) {
            n += snprintf(out + n, cap - (size_t)n, "  all %d layers", w->max_layers);
        } else {
            n += snprintf(out + n, cap - (size_t)n, "  layer %d only (0-%d)", a->show.layer,
                          w->max_layers - 1);
        }
    }
    if (w->mask >= 0 && n > 0 && (size_t)n < cap) {
        n += snprintf(out + n, cap - (size_t)n, "  mask %s %d/%d (%s)",
                      w->scene.masks[w->mask].name, w->mask + 1, w->scene.mask_count,
                      vw_world_mask_kind_name(w, w->mask));
    }
    if (live && n > 0 && (size_t)n < cap) {
        snprintf(out + n, cap - (size_t)n, " x%g  %.0f steps/s  %.0f fps", a->speed,
                 a->steps_per_s, a->frames_per_s);
    }
}

static void update_title(app *a)
{
    if (a->window == NULL) {
        return;
    }
    char status[512], title[1200];
    status_line(a, a->frames == 0, status, sizeof status);
    snprintf(title, sizeof title, "weathering-viewer: %s%s%.600s", status,
             a->message[0] ? "  |  " : "", a->message);
    glfwSetWindowTitle(a->window, title);
}

static void toggle_camera(app *a, int c)
{
    if (c >= a->world->scene.camera_count) {
        return;
    }
    a->camera_visible[c] = !a->camera_visible[c];
    const wx_scene_camera *cam = &a->world->scene.cameras[c];
    report(a, false, "camera %d '%s' %s", c + 1, cam->name, a->camera_visible[c] ? "on" : "off");
}

// L: the next layer shown (every layer's samples, then each layer's alone).
static void next_layer(app *a)
{
    const vw_world *w = a->world;
    if (w->max_layers <= 1) {
        report(a, false, "every camera has one layer: nothing to cycle (layers=\"K\" on an "
                         "<Ortho> bakes more)");
        return;
    }
    a->show.layer = vw_world_next_layer(w, a->show.layer);
    if (a->show.layer < 0) {
        report(a, false, "depth samples and hits of all %d layers (deeper ones darker)",
               w->max_layers);
        return;
    }
    int samples = 0, cameras = 0;
    for (int c = 0; c < w->scene.camera_count; ++c) {
        samples += vw_world_layer_points(w, c, a->show.layer).count;
        cameras += a->show.layer < vw_world_camera_layers(w, c);
    }
    report(a, false, "layer %d of 0-%d only: %d depth samples of %d camera%s%s", a->show.layer,
           w->max_layers - 1, samples, cameras, cameras == 1 ? "" : "s",
           a->show.layer == 0 ? " (the first surface each ray meets)" : "");
}

static void next_substance(app *a)
{
    vw_world *w = a->world;
    int count = vw_world_substance_count(w);
    if (count == 1) {
        report(a, false, "the scene has one substance, %s", vw_world_substance_name(w));
        return;
    }
    vw_world_next_substance(w);
    report(a, false,
           "showing substance %d/%d, %s: on particles (full colour at load %g) and deposits",
           w->substance + 1, count, vw_world_substance_name(w), (double)w->load_scale);
}

// M: the next derived mask on the depth samples (off after the last); one not
// computed yet is computed after the next frame, which says so.
static void next_mask(app *a)
{
    vw_world *w = a->world;
    if (vw_world_mask_count(w) == 0) {
        report(a, false, "the scene has no <Masks>");
        return;
    }
    int m = vw_world_next_mask(w);
    if (!vw_world_mask_ready(w, m)) {
        a->mask_request = m;
        report_computing(a, "", m);
        return;
    }
    wx_error err;
    if (vw_world_show_mask(w, m, &err) != WX_OK) { // known: nothing to compute
        report(a, true, "%s", err.message);
        return;
    }
    report_mask(a, -1.0);
}

static void on_key(GLFWwindow *window, int key, int scancode, int action, int mods)
{
    (void)scancode;
    (void)mods;
    app *a = glfwGetWindowUserPointer(window);
    if (action != GLFW_PRESS && !(action == GLFW_REPEAT && key == GLFW_KEY_N)) {
        return;
    }
    switch (key) {
    case GLFW_KEY_ESCAPE:
    case GLFW_KEY_Q: glfwSetWindowShouldClose(window, GLFW_TRUE); break;
    case GLFW_KEY_SPACE:
        if (vw_world_finished(a->world)) {
            restart(a);
        } else {
            a->playing = !a->playing;
        }
        update_title(a);
        break;
    case GLFW_KEY_N:
        a->playing = false;
        step_once(a);
        update_title(a);
        break;
    case GLFW_KEY_R: reload(a); break;
    case GLFW_KEY_G: gather(a); break; // reported in the overlay either way
    case GLFW_KEY_H:
        a->show.hits = !a->show.hits;
        report(a, false, "hit points %s", a->show.hits ? "on" : "off");
        break;
    case GLFW_KEY_D:
        a->show.depth_samples = !a->show.depth_samples;
        report(a, false, "depth samples %s", a->show.depth_samples ? "on" : "off");
        break;
    case GLFW_KEY_P:
        a->show.particles = !a->show.particles;
        report(a, false, "particles %s", a->show.particles ? "on" : "off");
        break;
    case GLFW_KEY_S: next_substance(a); break;
    case GLFW_KEY_L: next_layer(a); break;
    case GLFW_KEY_M:
        if (a->mask_request < 0) {
            next_mask(a);
        }
        break;
    case GLFW_KEY_EQUAL:
    case GLFW_KEY_KP_ADD:
        a->speed = a->speed * 2.0 < MAX_SPEED ? a->speed * 2.0 : MAX_SPEED;
        report(a, false, "speed x%g (simulated seconds per second)", a->speed);
        break;
    case GLFW_KEY_MINUS:
    case GLFW_KEY_KP_SUBTRACT:
        a->speed = a->speed * 0.5 > MIN_SPEED ? a->speed * 0.5 : MIN_SPEED;
        report(a, false, "speed x%g (simulated seconds per second)", a->speed);
        break;
    case GLFW_KEY_BACKSPACE:
        if (restart(a)) {
            report(a, false, "started again");
        }
        break;
    case GLFW_KEY_HOME: {
        int w = 1, h = 1;
        glfwGetFramebufferSize(window, &w, &h);
        vw_orbit_frame(&a->orbit, a->world->frame_lo, a->world->frame_hi,
                       (float)w / (float)(h > 0 ? h : 1));
        break;
    }
    case GLFW_KEY_F1:
        a->help = !a->help;
        if (a->help) {
            print_key_help();
        }
        break;
    default:
        if (key >= GLFW_KEY_1 && key <= GLFW_KEY_9) {
            toggle_camera(a, key - GLFW_KEY_1);
        } else if (key >= GLFW_KEY_KP_1 && key <= GLFW_KEY_KP_9) {
            toggle_camera(a, key - GLFW_KEY_KP_1);
        }
        break;
    }
}

static void on_mouse_button(GLFWwindow *window, int button, int action, int mods)
{
    (void)mods;
    app *a = glfwGetWindowUserPointer(window);
    bool down = action == GLFW_PRESS;
    if (button == GLFW_MOUSE_BUTTON_LEFT) {
        a->rotating = down;
    } else if (button == GLFW_MOUSE_BUTTON_RIGHT || button == GLFW_MOUSE_BUTTON_MIDDLE) {
        a->panning = down;
    }
    glfwGetCursorPos(window, &a->cursor_x, &a->cursor_y);
}

static void on_cursor(GLFWwindow *window, double x, double y)
{
    app *a = glfwGetWindowUserPointer(window);
    float dx = (float)(x - a->cursor_x), dy = (float)(y - a->cursor_y);
    a->cursor_x = x;
    a->cursor_y = y;
    if (a->rotating) {
        vw_orbit_rotate(&a->orbit, dx, dy);
    } else if (a->panning) {
        int w = 1, h = 1;
        glfwGetWindowSize(window, &w, &h);
        vw_orbit_pan(&a->orbit, dx, dy, (float)h);
    }
}

static void on_scroll(GLFWwindow *window, double dx, double dy)
{
    (void)dx;
    app *a = glfwGetWindowUserPointer(window);
    vw_orbit_zoom(&a->orbit, (float)dy);
}

static char glfw_message[512];

static void on_glfw_error(int code, const char *description)
{
    snprintf(glfw_message, sizeof glfw_message, "%s (GLFW error 0x%x)", description, code);
}

static int open_window(app *a)
{
    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit()) {
        fprintf(stderr,
                "weathering-viewer: cannot open a window: %s; is there a display? (tests run "
                "under `xvfb-run -a`)\n",
                glfw_message);
        return WX_FAIL;
    }
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_DEPTH_BITS, 24);
    glfwWindowHint(GLFW_SAMPLES, 0);
    if (a->frames > 0) {
        glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
    }
    a->window = glfwCreateWindow(a->width, a->height, "weathering-viewer", NULL, NULL);
    if (a->window == NULL) {
        fprintf(stderr, "weathering-viewer: cannot create an OpenGL 3.3 core window: %s\n",
                glfw_message);
        return WX_FAIL;
    }
    glfwMakeContextCurrent(a->window);
    glfwSwapInterval(a->frames > 0 ? 0 : 1);
    glfwSetWindowUserPointer(a->window, a);
    glfwSetKeyCallback(a->window, on_key);
    glfwSetMouseButtonCallback(a->window, on_mouse_button);
    glfwSetCursorPosCallback(a->window, on_cursor);
    glfwSetScrollCallback(a->window, on_scroll);
    if (a->verbose) {
        fprintf(stderr, "weathering-viewer: %s, %s\n", (const char *)glGetString(GL_RENDERER),
                (const char *)glGetString(GL_VERSION));
    }
    return -1;
}

// --- the overlay ----------------------------------------------------------------------------

// Lines of at most `cols` characters: writes each chunk of `text` at (x, *y).
static void wrapped_text(vw_overlay *o, float x, float *y, int cols, const float rgba[4],
                         const char *text)
{
    char line[256];
    float cell_h = (float)(VW_CELL_H * o->scale);
    size_t len = strlen(text), at = 0;
    cols = cols < (int)sizeof line - 1 ? cols : (int)sizeof line - 1;
    cols = cols > 8 ? cols : 8;
    while (at < len) {
        size_t take = len - at < (size_t)cols ? len - at : (size_t)cols;
        memcpy(line, text + at, take);
        line[take] = '\0';
        vw_overlay_text(o, x, *y, rgba, line);
        *y += cell_h;
        at += take;
    }
}

static void draw_overlay(app *a, int fb_w, int fb_h)
{
    vw_overlay *o = &a->overlay;
    int scale = fb_h >= 1000 ? 2 : 1;
    vw_overlay_begin(o, scale);
    float cw = (float)(VW_CELL_W * scale), ch = (float)(VW_CELL_H * scale), pad = 6.0f;
    int cols = (int)(((float)fb_w - 4.0f * pad) / cw);
    static const float white[4] = { 1.0f, 1.0f, 1.0f, 1.0f };
    static const float grey[4] = { 0.75f, 0.78f, 0.82f, 1.0f };
    static const float red[4] = { 1.0f, 0.45f, 0.4f, 1.0f };
    static const float green[4] = { 0.6f, 1.0f, 0.7f, 1.0f };
    static const float shade[4] = { 0.0f, 0.0f, 0.0f, 0.6f };

    char status[512];
    status_line(a, a->frames == 0, status, sizeof status);
    const char *hint = a->help ? "" : "  (F1 help)";
    size_t msg_len = strlen(a->message);
    int msg_lines = msg_len == 0 ? 0 : (int)((msg_len + (size_t)cols - 1) / (size_t)cols);
    int status_lines = (int)((strlen(status) + strlen(hint) + (size_t)cols - 1) / (size_t)cols);
    int help_lines = a->help ? KEY_HELP_COUNT + COLOUR_HELP_COUNT + 1 : 0;
    int lines = status_lines + msg_lines + help_lines;
    int widest = 0;
    for (int k = 0; k < KEY_HELP_COUNT && a->help; ++k) {
        widest = widest > (int)strlen(KEY_HELP[k]) ? widest : (int)strlen(KEY_HELP[k]);
    }
    for (int k = 0; k < COLOUR_HELP_COUNT && a->help; ++k) {
        widest = widest > (int)strlen(COLOUR_HELP[k]) ? widest : (int)strlen(COLOUR_HELP[k]);
    }
    int text_cols = (int)(strlen(status) + strlen(hint));
    text_cols = text_cols > (int)msg_len ? text_cols : (int)msg_len;
    text_cols = text_cols > widest ? text_cols : widest;
    text_cols = text_cols < cols ? text_cols : cols;
    vw_overlay_box(o, pad, pad, (float)text_cols * cw + 2.0f * pad, (float)lines * ch + 2.0f * pad,
                   shade);
    float x = 2.0f * pad, y = 2.0f * pad;
    char first[600];
    snprintf(first, sizeof first, "%s%s", status, hint);
    wrapped_text(o, x, &y, cols, white, first);
    if (msg_len > 0) {
        wrapped_text(o, x, &y, cols, a->message_is_error ? red : green, a->message);
    }
    if (a->help) {
        y += ch;
        for (int k = 0; k < KEY_HELP_COUNT; ++k) {
            wrapped_text(o, x, &y, cols, white, KEY_HELP[k]);
        }
        for (int k = 0; k < COLOUR_HELP_COUNT; ++k) {
            wrapped_text(o, x, &y, cols, grey, COLOUR_HELP[k]);
        }
    }
    vw_overlay_end(o, fb_w, fb_h);
}

// --- the frame loop -------------------------------------------------------------------------

static void update_rates(app *a, double now)
{
    a->rate_frames++;
    double elapsed = now - a->rate_t0;
    if (elapsed >= 0.5) {
        a->steps_per_s = (double)a->rate_steps / elapsed;
        a->frames_per_s = (double)a->rate_frames / elapsed;
        a->rate_t0 = now;
        a->rate_steps = 0;
        a->rate_frames = 0;
    }
    if (now - a->title_s >= 0.25) {
        a->title_s = now;
        update_title(a);
    }
}

static void print_timing(const app *a)
{
    const timing *t = &a->timing;
    if (t->frames == 0) {
        return;
    }
    double f = (double)t->frames;
    fprintf(stderr,
            "weathering-viewer: %d frames in %.3f s: %.1f fps; per frame %.2f ms simulating "
            "(%.2f steps), %.2f ms uploading, %.2f ms drawing and swapping; %" PRId64
            " live particles at most; on average %.0f particles and %.0f depth samples drawn "
            "(the nearest in each pixel)\n",
            t->frames, t->total_s, f / t->total_s, 1e3 * t->sim_s / f, (double)t->steps / f,
            1e3 * t->upload_s / f, 1e3 * t->draw_s / f, t->max_particles,
            (double)t->drawn_particles / f, (double)t->drawn_samples / f);
}

static int run(app *a)
{
    wx_error err;
    int fb_w = 1, fb_h = 1;
    glfwGetFramebufferSize(a->window, &fb_w, &fb_h);
    vw_orbit_frame(&a->orbit, a->world->frame_lo, a->world->frame_hi,
                   (float)fb_w / (float)(fb_h > 0 ? fb_h : 1));
    a->last_frame_s = glfwGetTime();
    reset_rates(a);
    double start = glfwGetTime();
    for (int frame = 0; !glfwWindowShouldClose(a->window); ++frame) {
        if (a->frames == 0 && !a->playing && a->pending == NULL) {
            glfwWaitEventsTimeout(0.25); // nothing moves: redraw on input only
        } else {
            glfwPollEvents();
        }
        poll_pending(a);
        double t0 = glfwGetTime();
        advance(a, t0);
        double t1 = glfwGetTime();
        glfwGetFramebufferSize(a->window, &fb_w, &fb_h);
        float mvp[16];
        vw_orbit_matrix(&a->orbit, (float)fb_w / (float)(fb_h > 0 ? fb_h : 1), mvp);
        if (vw_draw_update(&a->draw, a->world, &a->show, mvp, fb_w, fb_h, &err) != WX_OK) {
            fprintf(stderr, "weathering-viewer: %s\n", err.message);
            return WX_FAIL;
        }
        double t2 = glfwGetTime();
        glViewport(0, 0, fb_w, fb_h);
        vw_draw_frame(&a->draw, a->world, &a->show, mvp);
        draw_overlay(a, fb_w, fb_h);
        bool last = a->frames > 0 && frame + 1 >= a->frames;
        if (last && a->screenshot != NULL) {
            if (vw_screenshot_write(a->screenshot, fb_w, fb_h, &err) != WX_OK) {
                fprintf(stderr, "weathering-viewer: %s\n", err.message);
                return WX_FAIL;
            }
            printf("weathering-viewer: wrote %s (%dx%d)\n", a->screenshot, fb_w, fb_h);
        }
        glfwSwapBuffers(a->window);
        double t3 = glfwGetTime();
        wx_particle_view view;
        wx_sim_particles(a->world->sim, &view);
        a->timing.frames++;
        a->timing.sim_s += t1 - t0;
        a->timing.upload_s += t2 - t1;
        a->timing.draw_s += t3 - t2;
        a->timing.max_particles =
            view.count > a->timing.max_particles ? view.count : a->timing.max_particles;
        a->timing.drawn_particles += a->draw.particle_count;
        a->timing.drawn_samples += a->show.depth_samples ? a->draw.depth_count : 0;
        update_rates(a, t3);
        if (last) {
            break;
        }
        if (a->mask_request >= 0) {
            compute_requested_mask(a); // the frame just shown says it is coming
        }
    }
    a->timing.total_s = glfwGetTime() - start;
    if (a->gather_at_end) {
        wx_result r = gather(a);
        if (r != WX_OK) {
            return r;
        }
    }
    GLenum gl_err = glGetError();
    if (gl_err != GL_NO_ERROR) {
        fprintf(stderr, "weathering-viewer: GL error 0x%x\n", gl_err);
        return WX_FAIL;
    }
    return 0;
}

int main(int argc, char **argv)
{
    static app a; // large; zero-initialised
    a.speed = 1.0;
    a.mask_request = -1;
    a.show.layer = -1;
    a.show.depth_samples = true;
    a.show.particles = true;
    a.show.hits = true;
    int status = parse_args(argc, argv, &a);
    if (status >= 0) {
        return status;
    }
    if (!vw_executable_dir(argv[0], a.exe_dir)) {
        snprintf(a.exe_dir, sizeof a.exe_dir, ".");
    }
    status = load_first_world(&a);
    if (status < 0) {
        status = open_window(&a);
    }
    if (status < 0) {
        wx_error err;
        wx_result r = vw_draw_init(&a.draw, HIT_CAPACITY, &err);
        if (r == WX_OK) {
            r = vw_overlay_init(&a.overlay, &err);
        }
        if (r != WX_OK) {
            fprintf(stderr, "weathering-viewer: %s\n", err.message);
            status = r;
        } else if (!reset_camera_visibility(&a)) {
            fprintf(stderr, "weathering-viewer: out of memory\n");
            status = WX_FAIL;
        } else if (vw_draw_set_world(&a.draw, a.world, &err) != WX_OK) {
            fprintf(stderr, "weathering-viewer: %s\n", err.message);
            status = WX_FAIL;
        }
    }
    if (status < 0) {
        a.playing = true;
        if (a.frames == 0) {
            printf("weathering-viewer: %s; press F1 in the window for help\n",
                   a.world->scene.path);
            fflush(stdout);
        }
        status = run(&a);
        if (a.verbose) {
            print_timing(&a);
        }
    }
    cancel_pending(&a);
    if (a.window != NULL) {
        vw_overlay_free(&a.overlay);
        vw_draw_free(&a.draw);
        glfwDestroyWindow(a.window);
    }
    glfwTerminate();
    if (a.world != NULL) {
        vw_world_free(a.world);
        free(a.world);
    }
    free(a.camera_visible);
    return status;
}
