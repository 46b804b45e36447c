// messages.c: what the viewer tells its user (app.h): reports on stdout or
// stderr and in the overlay, the window's title and status line, the key and
// colour help, and the overlay drawn over the scene.
#include "app.h"

#include <inttypes.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "sim/simulate.h"

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

void vw_app_print_key_help(void)
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

static void status_line(const vw_app *a, bool live, char *out, size_t cap)
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

void vw_app_update_title(vw_app *a)
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

// A message for the user: stderr for errors, stdout otherwise, and the overlay.
void vw_app_report(vw_app *a, bool is_error, const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    vsnprintf(a->message, sizeof a->message, fmt, args);
    va_end(args);
    a->message_is_error = is_error;
    FILE *out = is_error ? stderr : stdout;
    fprintf(out, "weathering-viewer: %s\n", a->message);
    fflush(out);
    vw_app_update_title(a);
}

// What the shown mask's colours mean; `seconds` it took to compute (< 0: it
// was known), said only interactively (a run of --frames gives the same
// pixels every time).
void vw_app_report_mask(vw_app *a, double seconds)
{
    const vw_world *w = a->world;
    int m = w->mask;
    if (m < 0) {
        vw_app_report(a, false, "mask off: depth samples in their cameras' colours%s",
                      vw_world_shows_deposits(w) ? ", tinted by the substance shown" : "");
        return;
    }
    char took[64] = "";
    if (seconds >= 0.0 && a->frames == 0) {
        snprintf(took, sizeof took, " (computed in %.1f s)", seconds);
    }
    const wx_mask_def *md = &w->scene.masks[m];
    if (md->kind == WX_MASK_CURVATURE) {
        vw_app_report(
            a, false,
            "mask %s %d/%d (curvature) on the depth samples: blue concave, grey flat, red "
            "convex, full colour at |curvature| %.3g per unit (99th percentile)%s",
            md->name, m + 1, w->scene.mask_count, (double)w->mask_scale[m], took);
    } else {
        vw_app_report(a, false,
                      "mask %s %d/%d (%s) on the depth samples: dark violet 0 to pale yellow 1%s",
                      md->name, m + 1, w->scene.mask_count, vw_world_mask_kind_name(w, m), took);
    }
}

// Says that mask m is being computed: rays per sample, how many samples.
void vw_app_report_computing(vw_app *a, const char *prefix, int m)
{
    const vw_world *w = a->world;
    const wx_mask_def *md = &w->scene.masks[m];
    char rays[64] = "";
    if (wx_mask_rays(md) > 0) {
        snprintf(rays, sizeof rays, ", %d ray%s a sample", wx_mask_rays(md),
                 wx_mask_rays(md) == 1 ? "" : "s");
    }
    vw_app_report(a, false, "%scomputing mask %s (%s%s) at %d depth samples ...", prefix, md->name,
                  vw_world_mask_kind_name(w, m), rays, w->point_count);
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

void vw_app_draw_overlay(vw_app *a, int fb_w, int fb_h)
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
