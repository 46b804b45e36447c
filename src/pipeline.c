// pipeline.c: run options, the output folder rules (DESIGN section 6) and the
// --stats file.
#define _XOPEN_SOURCE 700 // realpath
#include "pipeline.h"

#include <errno.h>
#include <limits.h>
#include <stdarg.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "atomic_file.h"
#include "emitter.h"
#include "exr_io.h"
#include "progress.h"

int wx_cpu_count(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n >= 1 ? (int)n : 1;
}

void wx_default_out_name(const char *scene_name, char *out, size_t cap)
{
    size_t n = 0;
    bool leading = true;
    for (const char *c = scene_name; *c != '\0' && n + 1 < cap; ++c) {
        bool plain = (*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') ||
                     (*c >= '0' && *c <= '9') || *c == '_' || *c == '-' || *c == '.';
        out[n++] = plain && !(leading && *c == '.') ? *c : '_';
        leading = leading && *c == '.';
    }
    out[n] = '\0';
    if (n == 0) {
        snprintf(out, cap, "scene");
    }
}

void wx_run_options_default(const wx_scene *scene, wx_run_options *opts)
{
    memset(opts, 0, sizeof *opts);
    char name[sizeof scene->name];
    wx_default_out_name(scene->name, name, sizeof name);
    snprintf(opts->out_dir, sizeof opts->out_dir, "out/%s", name);
    opts->seed = scene->seed;
    opts->threads = wx_cpu_count();
}

// --- the output folder and what goes into it ------------------------------------

void wx_preview_name(const char *mask_name, char *out, size_t cap)
{
    const char *dot = strrchr(mask_name, '.');
    int stem = dot != NULL && dot != mask_name ? (int)(dot - mask_name) : (int)strlen(mask_name);
    bool is_png = dot != NULL && dot != mask_name && strcmp(dot, ".png") == 0;
    snprintf(out, cap, "%.*s%s", stem, mask_name, is_png ? ".preview.png" : ".png");
}

// A <View> camera whose maps `bake` writes into the output folder.
static bool baked_camera(const wx_scene_camera *cam)
{
    return cam->has_view && (cam->depth_path[0] == '\0' || cam->maps_in_output);
}

static wx_result add_name(wx_output_names *list, int *capacity, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static wx_result add_name(wx_output_names *list, int *capacity, const char *fmt, ...)
{
    if (list->count == *capacity) {
        int grown_capacity = *capacity > 0 ? 2 * *capacity : 16;
        void *grown = realloc(list->names, (size_t)grown_capacity * sizeof *list->names);
        if (grown == NULL) {
            return WX_FAIL;
        }
        list->names = grown;
        *capacity = grown_capacity;
    }
    va_list args;
    va_start(args, fmt);
    vsnprintf(list->names[list->count], WX_OUTPUT_NAME_MAX, fmt, args);
    va_end(args);
    for (int k = 0; k < list->count; ++k) {
        if (strcmp(list->names[k], list->names[list->count]) == 0) {
            return WX_OK; // bake and simulate both write <camera>_dirt.exr
        }
    }
    list->count++;
    return WX_OK;
}

wx_result wx_output_names_list(const wx_scene *scene, unsigned phases, wx_output_names *out,
                               wx_error *err)
{
    static const char *const kinds[4] = { "depth", "normal", "impact", "dirt" };
    memset(out, 0, sizeof *out);
    int capacity = 0;
    wx_result r = WX_OK;
    for (int c = 0; c < scene->camera_count && r == WX_OK; ++c) {
        const wx_scene_camera *cam = &scene->cameras[c];
        int baked = (phases & WX_PHASE_BAKE) && baked_camera(cam) ? (cam->is_output ? 2 : 4) : 0;
        for (int k = 0; k < baked && r == WX_OK; ++k) {
            r = add_name(out, &capacity, "%s_%s.exr", cam->name, kinds[k]);
        }
        if (r == WX_OK && (phases & WX_PHASE_SIMULATE) && !cam->is_output) {
            r = add_name(out, &capacity, "%s_dirt.exr", cam->name);
        }
    }
    if (r == WX_OK && (phases & WX_PHASE_GATHER) && scene->output_index >= 0) {
        const wx_scene_camera *cam = &scene->cameras[scene->output_index];
        char png[WX_OUTPUT_NAME_MAX];
        wx_preview_name(cam->output_file, png, sizeof png);
        r = add_name(out, &capacity, "%s", cam->output_file);
        if (r == WX_OK) {
            r = add_name(out, &capacity, "%s", png);
        }
    }
    if (r != WX_OK) {
        wx_output_names_free(out);
        return wx_error_set(err, WX_FAIL, "out of memory (output names)");
    }
    return WX_OK;
}

void wx_output_names_free(wx_output_names *names)
{
    free(names->names);
    memset(names, 0, sizeof *names);
}

// mkdir -p: creates every missing folder of `path`; `created` gets the first one made.
static wx_result make_folders(const char *path, char created[WX_PATH_MAX], wx_error *err)
{
    char partial[WX_PATH_MAX];
    size_t len = strlen(path);
    created[0] = '\0';
    if (len == 0 || len >= sizeof partial) {
        return wx_error_set(err, WX_BAD_INPUT, "output folder name is empty or too long");
    }
    memcpy(partial, path, len + 1);
    for (size_t i = 1; i <= len; ++i) {
        if (partial[i] != '/' && partial[i] != '\0') {
            continue;
        }
        char saved = partial[i];
        partial[i] = '\0';
        if (mkdir(partial, 0777) == 0) {
            if (created[0] == '\0') {
                memcpy(created, partial, i + 1);
            }
        } else if (errno != EEXIST) {
            return wx_error_set(err, WX_FAIL, "%s: cannot create folder (%s)", partial,
                                strerror(errno));
        }
        partial[i] = saved;
    }
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISDIR(st.st_mode)) {
        return wx_error_set(err, WX_BAD_INPUT, "%s: exists and is not a folder", path);
    }
    return WX_OK;
}

// Whether a file name in the output folder is the temporary of one of ours.
typedef struct temp_owner {
    const wx_output_names *names;
    const char *stats_name; ///< --stats file's name when it lies in the folder, else NULL
} temp_owner;

static bool is_our_output(const char *name, void *context)
{
    const temp_owner *owner = context;
    if (owner->stats_name != NULL && strcmp(name, owner->stats_name) == 0) {
        return true;
    }
    for (int k = 0; k < owner->names->count; ++k) {
        if (strcmp(name, owner->names->names[k]) == 0) {
            return true;
        }
    }
    return false;
}

static bool canonical_path(const char *path, char out[WX_PATH_MAX]);

wx_result wx_output_prepare(const wx_scene *scene, const wx_run_options *opts,
                            char created[WX_PATH_MAX], wx_error *err)
{
    char made[WX_PATH_MAX];
    wx_result r = make_folders(opts->out_dir, made, err);
    if (created != NULL) {
        memcpy(created, made, sizeof made);
    }
    if (r != WX_OK) {
        wx_output_remove_empty(opts->out_dir, made);
        return r;
    }
    // Temporaries of an earlier run that was killed (SIGKILL, power loss): only
    // those of the files this program writes there.
    wx_output_names names;
    r = wx_output_names_list(scene, WX_PHASE_ALL, &names, err);
    if (r != WX_OK) {
        return r;
    }
    temp_owner owner = { .names = &names };
    char folder[WX_PATH_MAX], stats_folder[WX_PATH_MAX];
    if (opts->stats_path != NULL) {
        const char *slash = strrchr(opts->stats_path, '/');
        int n = slash != NULL ? (int)(slash - opts->stats_path) : 1;
        snprintf(stats_folder, sizeof stats_folder, "%.*s", n,
                 slash != NULL ? opts->stats_path : ".");
        if (canonical_path(opts->out_dir, folder) && canonical_path(stats_folder, stats_folder) &&
            strcmp(folder, stats_folder) == 0) {
            owner.stats_name = slash != NULL ? slash + 1 : opts->stats_path;
        }
    }
    wx_temp_remove_stale(opts->out_dir, is_our_output, &owner);
    wx_output_names_free(&names);
    return WX_OK;
}

void wx_output_remove_empty(const char *out_dir, const char *created)
{
    if (created == NULL || created[0] == '\0') {
        return;
    }
    char folder[WX_PATH_MAX];
    snprintf(folder, sizeof folder, "%s", out_dir);
    size_t stop = strlen(created);
    for (;;) {
        size_t len = strlen(folder);
        while (len > 1 && folder[len - 1] == '/') {
            folder[--len] = '\0';
        }
        if (len < stop || rmdir(folder) != 0) {
            return; // not empty (or not ours): keep it and its parents
        }
        char *slash = strrchr(folder, '/');
        if (len == stop || slash == NULL) {
            return;
        }
        *slash = '\0';
    }
}

// --- memory limits (docs/reliability.md) ---------------------------------------

void wx_memory_estimate(const wx_scene *scene, unsigned phases, wx_memory_need *need)
{
    memset(need, 0, sizeof *need);
    need->baseline_bytes = WX_MEMORY_BASELINE;
    need->camera_line = scene->path[0] != '\0' ? 1 : 0;
    double largest = -1.0, input_texels = 0.0, largest_input = 0.0, output_texels = 0.0;
    double framebuffer = 0.0, images = 0.0, baked_inputs = 0.0;
    bool bake = (phases & WX_PHASE_BAKE) && wx_scene_needs_bake(scene);
    for (int c = 0; c < scene->camera_count; ++c) {
        const wx_scene_camera *sc = &scene->cameras[c];
        double texels = (double)sc->camera.width * (double)sc->camera.height;
        if (sc->is_output) {
            output_texels = texels;
        } else {
            input_texels += texels;
            largest_input = fmax(largest_input, texels);
        }
        if (texels > largest) {
            largest = texels;
            need->camera_line = sc->line;
        }
        if (bake && sc->has_view && sc->depth_path[0] == '\0') {
            framebuffer = fmax(framebuffer, WX_BAKE_FRAMEBUFFER_BYTES_PER_TEXEL * texels);
            images = fmax(images, texels * (sc->is_output ? WX_BAKE_OUTPUT_IMAGE_BYTES_PER_TEXEL
                                                          : WX_BAKE_INPUT_IMAGE_BYTES_PER_TEXEL));
            baked_inputs += sc->is_output ? 0.0 : texels;
        }
    }
    if (bake) {
        double largest_file = -1.0;
        for (int m = 0; m < scene->mesh_count; ++m) {
            struct stat st;
            double bytes = stat(scene->meshes[m].path, &st) == 0 ? (double)st.st_size : 0.0;
            need->mesh_bytes += WX_MESH_BYTES_PER_FILE_BYTE * bytes;
            if (bytes > largest_file) {
                largest_file = bytes;
                need->mesh_line = scene->meshes[m].line;
            }
        }
        // Two cameras' images at once, the visibility test's depth planes, the
        // readback strip (1 Mi floats), and the meshes as imported and uploaded.
        need->bake_bytes = WX_BAKE_CONTEXT_BYTES + framebuffer + 2.0 * images +
                           4.0 * (input_texels > baked_inputs ? input_texels : baked_inputs) +
                           4.0 * 1024.0 * 1024.0 + need->mesh_bytes;
    }
    if (phases & WX_PHASE_SIMULATE) {
        need->sim_map_bytes = WX_SIM_BYTES_PER_INPUT_TEXEL * input_texels +
                              WX_SIM_WRITE_BYTES_PER_TEXEL * largest_input;
        largest = -1.0;
        double duration = wx_scene_duration(scene);
        for (int e = 0; e < scene->emitter_count; ++e) {
            double n = (double)wx_emitter_count_at(&scene->emitters[e], duration);
            need->particles += n;
            if (n > largest) {
                largest = n;
                need->emitter_line = scene->emitters[e].line;
            }
        }
        need->particle_bytes = need->particles * WX_BYTES_PER_PARTICLE;
    }
    if (phases & WX_PHASE_GATHER) {
        need->gather_bytes = WX_GATHER_BYTES_PER_INPUT_TEXEL * input_texels +
                             WX_GATHER_BYTES_PER_OUTPUT_TEXEL * output_texels;
    }
    double sim = need->sim_map_bytes + need->particle_bytes;
    double peak = need->bake_bytes;
    need->phase = "bake";
    if (sim > peak) {
        peak = sim;
        need->phase = "simulate";
    }
    if (need->gather_bytes > peak) {
        peak = need->gather_bytes;
        need->phase = "gather";
    }
    need->total_bytes = need->baseline_bytes + WX_MEMORY_MARGIN * peak;
}

// A "Key:   1234 kB" line of /proc/meminfo, in bytes; < 0 when absent.
static double meminfo_bytes(const char *key)
{
    FILE *f = fopen("/proc/meminfo", "r");
    if (f == NULL) {
        return -1.0;
    }
    char line[256];
    double bytes = -1.0;
    size_t key_len = strlen(key);
    while (fgets(line, sizeof line, f) != NULL) {
        if (strncmp(line, key, key_len) == 0 && line[key_len] == ':') {
            bytes = 1024.0 * strtod(line + key_len + 1, NULL);
            break;
        }
    }
    fclose(f);
    return bytes;
}

// A cgroup v2 number file ("max" or bytes); < 0 when absent or "max".
static double cgroup_number(const char *path)
{
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        return -1.0;
    }
    char text[64] = "";
    double value = -1.0;
    if (fgets(text, sizeof text, f) != NULL && text[0] >= '0' && text[0] <= '9') {
        value = strtod(text, NULL);
    }
    fclose(f);
    return value;
}

static void take_min(double *least, double value)
{
    if (value >= 0.0 && (*least < 0.0 || value < *least)) {
        *least = value;
    }
}

double wx_memory_available(void)
{
    const char *override = getenv("WX_MEMORY_AVAILABLE_MB");
    if (override != NULL && override[0] != '\0') {
        char *end = NULL;
        double mb = strtod(override, &end);
        if (end != override && *end == '\0' && mb >= 0.0) {
            return mb * 1024.0 * 1024.0;
        }
    }
    double least = meminfo_bytes("MemAvailable");
    if (least < 0.0) {
        long pages = sysconf(_SC_AVPHYS_PAGES);
        long page = sysconf(_SC_PAGESIZE);
        if (pages > 0 && page > 0) {
            least = (double)pages * (double)page;
        }
    }
    double cg_max = cgroup_number("/sys/fs/cgroup/memory.max");
    double cg_now = cgroup_number("/sys/fs/cgroup/memory.current");
    if (cg_max >= 0.0) {
        take_min(&least, cg_now >= 0.0 && cg_now < cg_max ? cg_max - cg_now : 0.0);
    }
    struct rlimit rl;
    if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY) {
        take_min(&least, (double)rl.rlim_cur);
    }
    if (getrlimit(RLIMIT_DATA, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY) {
        take_min(&least, (double)rl.rlim_cur);
    }
    return least;
}

static double gib(double bytes)
{
    return bytes / (1024.0 * 1024.0 * 1024.0);
}

wx_result wx_memory_check(const wx_scene *scene, unsigned phases, wx_error *err)
{
    wx_memory_need need;
    wx_memory_estimate(scene, phases, &need);
    double available = wx_memory_available();
    if (available < 0.0 || need.total_bytes <= available) {
        return WX_OK;
    }
    if (strcmp(need.phase, "simulate") == 0 && need.particle_bytes > need.sim_map_bytes) {
        return wx_error_set(err, WX_BAD_INPUT,
                            "%s:%d: the emitters would emit %.4g particles: with the maps that "
                            "needs about %.3g GiB (%.0f bytes per particle, %.3g GiB of maps), "
                            "but only %.3g GiB of memory is available; lower the rate or the "
                            "duration (see docs/reliability.md)",
                            scene->path, need.emitter_line, need.particles, gib(need.total_bytes),
                            WX_BYTES_PER_PARTICLE, gib(need.sim_map_bytes), gib(available));
    }
    if (strcmp(need.phase, "bake") == 0 && need.mesh_bytes > need.bake_bytes - need.mesh_bytes) {
        return wx_error_set(err, WX_BAD_INPUT,
                            "%s:%d: importing and baking the meshes needs about %.3g GiB (%.3g "
                            "GiB to import %.0f MiB of mesh files), but only %.3g GiB of memory "
                            "is available (see docs/reliability.md)",
                            scene->path, need.mesh_line, gib(need.total_bytes),
                            gib(need.mesh_bytes),
                            need.mesh_bytes / WX_MESH_BYTES_PER_FILE_BYTE / (1024.0 * 1024.0),
                            gib(available));
    }
    return wx_error_set(err, WX_BAD_INPUT,
                        "%s:%d: the maps need about %.3g GiB at the peak (the %s), but only %.3g "
                        "GiB of memory is available; use smaller maps (see docs/reliability.md)",
                        scene->path, need.camera_line, gib(need.total_bytes), need.phase,
                        gib(available));
}

static bool same_file(const struct stat *a, const char *path)
{
    struct stat b;
    return path[0] != '\0' && stat(path, &b) == 0 && a->st_dev == b.st_dev &&
           a->st_ino == b.st_ino;
}

// True when the file `st` describes is the scene or a map or mesh it names.
// Maps this program baked into the output folder (maps_in_output) are not inputs.
static bool is_scene_input(const wx_scene *scene, const struct stat *st)
{
    if (same_file(st, scene->path)) {
        return true;
    }
    for (int c = 0; c < scene->camera_count; ++c) {
        const wx_scene_camera *cam = &scene->cameras[c];
        if (cam->maps_in_output) {
            continue; // baked by us: a later phase may write the next stage over them
        }
        if (same_file(st, cam->depth_path) || same_file(st, cam->normal_path) ||
            same_file(st, cam->impact_path) || same_file(st, cam->dirt_path)) {
            return true;
        }
    }
    for (int m = 0; m < scene->mesh_count; ++m) {
        if (same_file(st, scene->meshes[m].path)) {
            return true;
        }
    }
    return false;
}

wx_result wx_output_path(const wx_scene *scene, const wx_run_options *opts, const char *name,
                         char path[WX_PATH_MAX], wx_error *err)
{
    if (name[0] == '\0' || strchr(name, '/') != NULL || strcmp(name, ".") == 0 ||
        strcmp(name, "..") == 0) {
        return wx_error_set(err, WX_BAD_INPUT, "'%s' is not a plain file name", name);
    }
    int n = snprintf(path, WX_PATH_MAX, "%s/%s", opts->out_dir, name);
    if (n < 0 || n >= WX_PATH_MAX) {
        return wx_error_set(err, WX_BAD_INPUT, "%s/%s: path too long", opts->out_dir, name);
    }
    struct stat st;
    if (stat(path, &st) == 0 && is_scene_input(scene, &st)) {
        return wx_error_set(err, WX_BAD_INPUT,
                            "%s: is an input of scene %s and would be overwritten; choose "
                            "another --out folder",
                            path, scene->path);
    }
    return WX_OK;
}

// What a path that is not a regular file is, for messages (lstat: a link is a link).
static const char *file_kind(mode_t mode)
{
    return S_ISLNK(mode)    ? "a symbolic link"
           : S_ISDIR(mode)  ? "a folder"
           : S_ISFIFO(mode) ? "a FIFO"
           : S_ISCHR(mode) || S_ISBLK(mode) ? "a device"
                                             : "not a regular file";
}

// Removes "." and resolves ".." in the part of a path that does not exist yet.
static void append_lexical(char out[WX_PATH_MAX], const char *rest)
{
    char copy[WX_PATH_MAX];
    snprintf(copy, sizeof copy, "%s", rest);
    char *save = NULL;
    for (char *part = strtok_r(copy, "/", &save); part != NULL; part = strtok_r(NULL, "/", &save)) {
        if (strcmp(part, ".") == 0) {
            continue;
        }
        size_t len = strlen(out);
        if (strcmp(part, "..") == 0) {
            char *slash = strrchr(out, '/');
            if (slash != NULL) {
                *(slash == out ? slash + 1 : slash) = '\0';
            }
            continue;
        }
        snprintf(out + len, WX_PATH_MAX - len, "%s%s", len > 0 && out[len - 1] == '/' ? "" : "/",
                 part);
    }
}

// The absolute path of `path` with its symbolic links resolved as far as it
// exists (realpath of its longest existing prefix, then the rest as written).
static bool canonical_path(const char *path, char out[WX_PATH_MAX])
{
    char prefix[WX_PATH_MAX];
    if (snprintf(prefix, sizeof prefix, "%s", path) >= (int)sizeof prefix) {
        return false;
    }
    char resolved[PATH_MAX];
    for (;;) {
        const char *start = prefix[0] != '\0' ? prefix : ".";
        if (realpath(start, resolved) != NULL) {
            break;
        }
        char *slash = strrchr(prefix, '/');
        if (slash == NULL) {
            prefix[0] = '\0';
        } else if (slash == prefix) {
            prefix[1] = '\0'; // "/" exists
        } else {
            *slash = '\0';
        }
    }
    if (snprintf(out, WX_PATH_MAX, "%s", resolved) >= WX_PATH_MAX) {
        return false;
    }
    size_t used = strlen(prefix);
    if (strcmp(prefix, path) != 0) {
        append_lexical(out, path + used);
    }
    return true;
}

// The --stats file (DESIGN section 6): never an input, an output of the run or an
// existing non-regular file; its folder exists or is the output folder.
static wx_result check_stats_path(const wx_scene *scene, const wx_run_options *opts,
                                  const wx_output_names *outputs, wx_error *err)
{
    const char *path = opts->stats_path;
    struct stat st;
    if (lstat(path, &st) == 0) {
        if (!S_ISREG(st.st_mode)) {
            return wx_error_set(err, WX_BAD_INPUT,
                                "--stats %s: exists and is %s; the statistics are written only "
                                "to a new or a regular file",
                                path, file_kind(st.st_mode));
        }
        if (is_scene_input(scene, &st)) {
            return wx_error_set(err, WX_BAD_INPUT,
                                "--stats %s: is an input of scene %s and would be overwritten",
                                path, scene->path);
        }
    }
    char stats[WX_PATH_MAX], out_dir[WX_PATH_MAX], output[WX_PATH_MAX];
    if (!canonical_path(path, stats) || !canonical_path(opts->out_dir, out_dir)) {
        return wx_error_set(err, WX_BAD_INPUT, "--stats %s: path too long", path);
    }
    for (int k = 0; k < outputs->count; ++k) {
        int n = snprintf(output, sizeof output, "%s/%s", out_dir, outputs->names[k]);
        if (n > 0 && n < (int)sizeof output && strcmp(output, stats) == 0) {
            return wx_error_set(err, WX_BAD_INPUT,
                                "--stats %s: is the run's output %s; choose another file name",
                                path, outputs->names[k]);
        }
    }
    char folder[WX_PATH_MAX];
    snprintf(folder, sizeof folder, "%s", stats);
    *strrchr(folder, '/') = '\0';
    struct stat dir;
    bool exists = stat(folder[0] != '\0' ? folder : "/", &dir) == 0 && S_ISDIR(dir.st_mode);
    if (!exists && strcmp(folder, out_dir) != 0) {
        return wx_error_set(err, WX_BAD_INPUT,
                            "--stats %s: folder %s does not exist (only the output folder is "
                            "made by the run)",
                            path, folder);
    }
    return WX_OK;
}

wx_result wx_check_outputs(const wx_scene *scene, const wx_run_options *opts, unsigned phases,
                           wx_error *err)
{
    wx_output_names names;
    wx_result r = wx_output_names_list(scene, phases, &names, err);
    for (int k = 0; k < names.count && r == WX_OK; ++k) {
        char path[WX_PATH_MAX];
        r = wx_output_path(scene, opts, names.names[k], path, err);
        struct stat st;
        if (r == WX_OK && lstat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
            r = wx_error_set(err, WX_BAD_INPUT,
                             "%s: exists and is %s, where the run writes its output %s; remove "
                             "it or choose another --out folder",
                             path, file_kind(st.st_mode), names.names[k]);
        }
    }
    if (r == WX_OK && opts->stats_path != NULL) {
        wx_output_names all;
        r = wx_output_names_list(scene, WX_PHASE_ALL, &all, err);
        if (r == WX_OK) {
            r = check_stats_path(scene, opts, &all, err);
        }
        wx_output_names_free(&all);
    }
    wx_output_names_free(&names);
    return r;
}

bool wx_scene_needs_bake(const wx_scene *scene)
{
    for (int c = 0; c < scene->camera_count; ++c) {
        if (scene->cameras[c].has_view && scene->cameras[c].depth_path[0] == '\0') {
            return true;
        }
    }
    return false;
}

wx_result wx_use_baked_maps(wx_scene *scene, const wx_run_options *opts, wx_error *err)
{
    static const char *const kinds[4] = { "depth", "normal", "impact", "dirt" };
    for (int c = 0; c < scene->camera_count; ++c) {
        wx_scene_camera *cam = &scene->cameras[c];
        if (!cam->has_view || cam->depth_path[0] != '\0') {
            continue;
        }
        cam->maps_in_output = true;
        char *paths[4] = { cam->depth_path, cam->normal_path, cam->impact_path, cam->dirt_path };
        int count = cam->is_output ? 2 : 4;
        for (int k = 0; k < count; ++k) {
            int n = snprintf(paths[k], WX_PATH_MAX, "%s/%s_%s.exr", opts->out_dir, cam->name,
                             kinds[k]);
            if (n < 0 || n >= WX_PATH_MAX) {
                return wx_error_set(err, WX_BAD_INPUT, "%s: output path too long", opts->out_dir);
            }
            if (access(paths[k], R_OK) != 0) {
                return wx_error_set(err, WX_BAD_INPUT,
                                    "%s: camera '%s' has no baked %s map in %s; run `weathering "
                                    "bake %s --out %s` first",
                                    scene->path, cam->name, kinds[k], opts->out_dir, scene->path,
                                    opts->out_dir);
            }
        }
    }
    return WX_OK;
}

wx_result wx_write_stats(const char *path, const wx_run_options *opts, const wx_sim_stats *stats,
                         const wx_phase_times *times, wx_error *err)
{
    char json[4096];
    int n = snprintf(
        json, sizeof json,
        "{\n"
        "  \"particles_emitted\": %lld,\n"
        "  \"particle_steps\": %lld,\n"
        "  \"collisions\": %lld,\n"
        "  \"absorbed\": %lld,\n"
        "  \"settled\": %lld,\n"
        "  \"escaped\": %lld,\n"
        "  \"alive\": %lld,\n"
        "  \"dirt\": {\n"
        "    \"initial_surface\": %.17g,\n"
        "    \"emitted\": %.17g,\n"
        "    \"final_surface\": %.17g,\n"
        "    \"in_flight\": %.17g,\n"
        "    \"escaped\": %.17g\n"
        "  },\n"
        "  \"seconds\": {\n"
        "    \"load\": %.6f,\n"
        "    \"bake\": %.6f,\n"
        "    \"simulate\": %.6f,\n"
        "    \"gather\": %.6f,\n"
        "    \"total\": %.6f\n"
        "  },\n"
        "  \"threads\": %d,\n"
        "  \"seed\": %llu\n"
        "}\n",
        (long long)stats->particles_emitted, (long long)stats->particle_steps,
        (long long)stats->collisions, (long long)stats->absorbed, (long long)stats->settled,
        (long long)stats->escaped, (long long)stats->alive, stats->dirt_initial_surface,
        stats->dirt_emitted, stats->dirt_final_surface, stats->dirt_in_flight,
        stats->dirt_escaped, times->load, times->bake, times->simulate, times->gather,
        times->total, opts->threads, (unsigned long long)opts->seed);
    if (n < 0 || n >= (int)sizeof json) {
        return wx_error_set(err, WX_FAIL, "%s: statistics too long", path);
    }
    return wx_write_file_atomic(path, json, (size_t)n, err);
}

// --- the phases -------------------------------------------------------------------

wx_result wx_load_simulation_maps(const wx_scene *scene, wx_maps *maps, wx_error *err)
{
    int k = 0;
    for (int c = 0; c < scene->camera_count; ++c) {
        const wx_scene_camera *cam = &scene->cameras[c];
        if (cam->is_output) {
            continue;
        }
        if (cam->depth_path[0] == '\0') {
            return wx_error_set(err, WX_BAD_INPUT,
                                "%s: camera '%s' has no maps yet; run `weathering bake` first",
                                scene->path, cam->name);
        }
        unsigned which = WX_MAPS_DEPTH | WX_MAPS_NORMAL | WX_MAPS_IMPACT;
        if (cam->dirt_path[0] != '\0') {
            // A dirt map that an earlier `simulate` wrote starts from the dirt it
            // started from (channel initialDirt), so running again is repeatable.
            which |= WX_MAPS_DIRT | WX_MAPS_INITIAL_DIRT;
        }
        wx_result r = wx_maps_load(&maps[k], which, cam->depth_path, cam->normal_path,
                                   cam->impact_path, cam->dirt_path, err);
        if (r != WX_OK) {
            wx_error_prefix(err, "camera '%s'", cam->name);
            return r;
        }
        k++;
    }
    return WX_OK;
}

// True when the EXR at `path` has a channel named `name` (header only).
static bool has_channel(const char *path, const char *name)
{
    wx_image *header = calloc(1, sizeof *header); // attributes inline: off the stack
    bool found = false;
    if (header != NULL && wx_exr_read_header(path, header, NULL) == WX_OK) {
        for (int c = 0; c < header->channel_count && !found; ++c) {
            found = strcmp(header->channel_names[c], name) == 0;
        }
    }
    free(header);
    return found;
}

wx_result wx_load_gather_maps(const wx_scene *scene, const wx_run_options *opts, wx_maps *maps,
                              wx_error *err)
{
    int k = 0;
    for (int c = 0; c < scene->camera_count; ++c) {
        const wx_scene_camera *cam = &scene->cameras[c];
        if (cam->is_output) {
            continue;
        }
        char simulated[WX_PATH_MAX];
        int n = snprintf(simulated, sizeof simulated, "%s/%s_dirt.exr", opts->out_dir, cam->name);
        if (n < 0 || n >= (int)sizeof simulated) {
            return wx_error_set(err, WX_BAD_INPUT, "%s: output path too long", opts->out_dir);
        }
        const char *dirt_path = simulated;
        if (access(simulated, R_OK) != 0) {
            if (cam->dirt_path[0] == '\0') {
                return wx_error_set(err, WX_BAD_INPUT,
                                    "%s: camera '%s' has no dirt map (no %s); run `weathering "
                                    "simulate %s --out %s` first",
                                    scene->path, cam->name, simulated, scene->path,
                                    opts->out_dir);
            }
            dirt_path = cam->dirt_path;
            wx_note(opts->quiet,
                    "gather: no simulated dirt map %s; camera '%s' uses its scene dirt map %s",
                    simulated, cam->name, dirt_path);
        } else if (!has_channel(simulated, WX_INITIAL_DIRT_CHANNEL)) {
            wx_note(opts->quiet,
                    "gather: %s was never simulated (it holds the initial dirt bake wrote); run "
                    "`weathering simulate` first for the particles' dirt",
                    simulated);
        }
        wx_result r = wx_maps_load(&maps[k], WX_MAPS_DEPTH | WX_MAPS_NORMAL | WX_MAPS_DIRT,
                                   cam->depth_path, cam->normal_path, NULL, dirt_path, err);
        if (r != WX_OK) {
            wx_error_prefix(err, "camera '%s'", cam->name);
            return r;
        }
        // Only the dirt plane is read: release deposit and erosion now.
        free(maps[k].deposit);
        free(maps[k].erosion);
        maps[k].deposit = maps[k].erosion = NULL;
        k++;
    }
    return WX_OK;
}
