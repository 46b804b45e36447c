// args.c: the viewer's command line (app.h): its usage and the options read
// into the app's state.
#include "app.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "core/usage.h"

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
int vw_app_parse_args(int argc, char **argv, vw_app *a)
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
