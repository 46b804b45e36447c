// pipeline.c: run options, the output folder rules (DESIGN section 6) and the
// --stats file.
#include "pipeline.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "atomic_file.h"

int wx_cpu_count(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n >= 1 ? (int)n : 1;
}

void wx_run_options_default(const wx_scene *scene, wx_run_options *opts)
{
    memset(opts, 0, sizeof *opts);
    snprintf(opts->out_dir, sizeof opts->out_dir, "out/%s", scene->name);
    opts->seed = scene->seed;
    opts->threads = wx_cpu_count();
}

// mkdir -p: creates every missing folder of `path`.
static wx_result make_folders(const char *path, wx_error *err)
{
    char partial[WX_PATH_MAX];
    size_t len = strlen(path);
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
        if (mkdir(partial, 0777) != 0 && errno != EEXIST) {
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

wx_result wx_output_prepare(const wx_run_options *opts, wx_error *err)
{
    wx_result r = make_folders(opts->out_dir, err);
    if (r == WX_OK) {
        // Temporaries of an earlier run that was killed (SIGKILL, power loss).
        wx_temp_remove_stale(opts->out_dir);
    }
    return r;
}

// --- memory limits (docs/reliability.md) ---------------------------------------

static double emitter_particles(const wx_emitter *e, double duration)
{
    double end = e->end < duration ? e->end : duration;
    return end > e->start ? floor(e->rate * (end - e->start)) : 0.0;
}

void wx_memory_estimate(const wx_scene *scene, bool with_particles, wx_memory_need *need)
{
    memset(need, 0, sizeof *need);
    need->camera_line = scene->path[0] != '\0' ? 1 : 0;
    double largest = -1.0;
    for (int c = 0; c < scene->camera_count; ++c) {
        const wx_scene_camera *sc = &scene->cameras[c];
        double texels = (double)sc->camera.width * (double)sc->camera.height;
        double floats = sc->is_output ? WX_OUTPUT_FLOATS_PER_TEXEL : WX_INPUT_FLOATS_PER_TEXEL;
        need->map_bytes += texels * floats * (double)sizeof(float);
        if (texels > largest) {
            largest = texels;
            need->camera_line = sc->line;
        }
    }
    largest = -1.0;
    double duration = wx_scene_duration(scene);
    for (int e = 0; e < scene->emitter_count && with_particles; ++e) {
        double n = emitter_particles(&scene->emitters[e], duration);
        need->particles += n;
        if (n > largest) {
            largest = n;
            need->emitter_line = scene->emitters[e].line;
        }
    }
    need->particle_bytes = need->particles * WX_BYTES_PER_PARTICLE;
    need->total_bytes = need->map_bytes + need->particle_bytes;
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

wx_result wx_memory_check(const wx_scene *scene, bool with_particles, wx_error *err)
{
    wx_memory_need need;
    wx_memory_estimate(scene, with_particles, &need);
    double available = wx_memory_available();
    if (available < 0.0 || need.total_bytes <= available) {
        return WX_OK;
    }
    if (need.particle_bytes > need.map_bytes) {
        return wx_error_set(err, WX_BAD_INPUT,
                            "%s:%d: the emitters would emit %.4g particles: with the maps that "
                            "needs about %.3g GiB (%.0f bytes per particle, %.3g GiB of maps), "
                            "but only %.3g GiB of memory is available; lower the rate or the "
                            "duration (see docs/reliability.md)",
                            scene->path, need.emitter_line, need.particles, gib(need.total_bytes),
                            WX_BYTES_PER_PARTICLE, gib(need.map_bytes), gib(available));
    }
    return wx_error_set(err, WX_BAD_INPUT,
                        "%s:%d: the maps need about %.3g GiB (%.3g GiB with the particles), but "
                        "only %.3g GiB of memory is available; use smaller maps (see "
                        "docs/reliability.md)",
                        scene->path, need.camera_line, gib(need.map_bytes),
                        gib(need.total_bytes), gib(available));
}

static bool same_file(const struct stat *a, const char *path)
{
    struct stat b;
    return path[0] != '\0' && stat(path, &b) == 0 && a->st_dev == b.st_dev &&
           a->st_ino == b.st_ino;
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
    if (stat(path, &st) != 0) {
        return WX_OK; // a new file cannot be an input
    }
    bool is_input = same_file(&st, scene->path);
    for (int c = 0; c < scene->camera_count && !is_input; ++c) {
        const wx_scene_camera *cam = &scene->cameras[c];
        if (cam->maps_in_output) {
            continue; // baked by us: a later phase may write the next stage over them
        }
        is_input = same_file(&st, cam->depth_path) || same_file(&st, cam->normal_path) ||
                   same_file(&st, cam->impact_path) || same_file(&st, cam->dirt_path);
    }
    for (int m = 0; m < scene->mesh_count && !is_input; ++m) {
        is_input = same_file(&st, scene->meshes[m].path);
    }
    if (is_input) {
        return wx_error_set(err, WX_BAD_INPUT,
                            "%s: is an input of scene %s and would be overwritten; choose "
                            "another --out folder",
                            path, scene->path);
    }
    return WX_OK;
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
