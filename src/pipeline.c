// pipeline.c: run options, the output folder rules (DESIGN section 6) and the
// --stats file.
#include "pipeline.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
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
    return make_folders(opts->out_dir, err);
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
