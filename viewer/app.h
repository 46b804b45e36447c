// app.h: the state of weathering-viewer, the program (main.c), and what its
// files share: the command line (args.c), the worlds loaded and reloaded
// (reload.c), the simulation stepped (simulation.c), the input (keys.c), the
// window (window.c) and the messages to the user (messages.c).
#ifndef VW_APP_H
#define VW_APP_H

#include <stdbool.h>
#include <stdint.h>

#include "bake_child.h"
#include "core/limits.h"
#include "draw.h"
#include "overlay.h"
#include "view.h"
#include "world.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

enum {
    DEFAULT_WIDTH = 1024,
    DEFAULT_HEIGHT = 640,
    HIT_CAPACITY = 16384,
    MAX_TOGGLE_CAMERAS = 9,
};

typedef struct vw_timing {
    int frames;
    int64_t steps;
    double sim_s, upload_s, draw_s, total_s;
    int64_t max_particles;
    int64_t drawn_particles; ///< summed over frames: particles drawn (nearest per pixel)
    int64_t drawn_samples;   ///< summed over frames: depth samples drawn
} vw_timing;

typedef struct vw_app {
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
    vw_timing timing;
} vw_app;

// --- args.c ----------------------------------------------------------------------------

/// Reads the command line into `a`; returns -1 to go on, else an exit status.
int vw_app_parse_args(int argc, char **argv, vw_app *a);

// --- messages.c ------------------------------------------------------------------------

/// Prints the keys and the colours' meanings on stdout (F1).
void vw_app_print_key_help(void);

/// A message for the user: stderr for errors, stdout otherwise, and the overlay.
void vw_app_report(vw_app *a, bool is_error, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/// The window's title: the status line and the last message.
void vw_app_update_title(vw_app *a);

/// What the shown mask's colours mean; `seconds` it took to compute (< 0: it
/// was known), said only interactively (a run of --frames gives the same
/// pixels every time).
void vw_app_report_mask(vw_app *a, double seconds);

/// Says that mask m is being computed: rays per sample, how many samples.
void vw_app_report_computing(vw_app *a, const char *prefix, int m);

/// The overlay over a framebuffer of fb_w x fb_h: the status line, the last
/// message and, with F1, the help.
void vw_app_draw_overlay(vw_app *a, int fb_w, int fb_h);

// --- reload.c --------------------------------------------------------------------------

/// Every camera of the running world shown; false when out of memory.
bool vw_app_reset_camera_visibility(vw_app *a);

/// Runs the first load to completion; returns an exit status, or -1 on success.
int vw_app_load_first_world(vw_app *a);

/// R: reads the scene file again; bakes in the background when its maps must
/// be baked again, else makes it the running world now.
void vw_app_reload(vw_app *a);

/// Makes a reloaded world whose bake has ended the running one.
void vw_app_poll_pending(vw_app *a);

/// Stops a reload's bake and drops its world.
void vw_app_cancel_pending(vw_app *a);

// --- simulation.c ----------------------------------------------------------------------

/// Starts counting steps and frames per second again.
void vw_app_reset_rates(vw_app *a);

/// One step, unless the simulation has run the scene's steps.
bool vw_app_step_once(vw_app *a);

/// Creates the simulation again at time 0; false (reported) on failure.
bool vw_app_restart(vw_app *a);

/// Steps the simulation for this frame (at wall-clock time `now`).
void vw_app_advance(vw_app *a, double now);

/// G: saves the dirt maps and the mask, and says where.
wx_result vw_app_gather(vw_app *a);

// --- keys.c ----------------------------------------------------------------------------

/// Computes the mask M asked for (after the frame that said so) and shows it.
void vw_app_compute_requested_mask(vw_app *a);

/// GLFW's input callbacks (the window's user pointer is the app).
void vw_app_on_key(GLFWwindow *window, int key, int scancode, int action, int mods);
void vw_app_on_mouse_button(GLFWwindow *window, int button, int action, int mods);
void vw_app_on_cursor(GLFWwindow *window, double x, double y);
void vw_app_on_scroll(GLFWwindow *window, double dx, double dy);

// --- window.c --------------------------------------------------------------------------

/// Opens the window and its OpenGL 3.3 core context; returns an exit status,
/// or -1 on success.
int vw_app_open_window(vw_app *a);

#endif
