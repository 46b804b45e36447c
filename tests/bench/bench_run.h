// bench_run.h: what the benchmarks that run the `weathering` command share:
// their folder under $WX_BUILD/tmp, the program's absolute path, one run of it
// that returns its --stats JSON (and the simulation's stepping time read from
// it), and the rusty tank's scene with variants of it written by text
// replacement. Include after defining _XOPEN_SOURCE 700 (realpath).
#ifndef WX_BENCH_RUN_H
#define WX_BENCH_RUN_H

#include <limits.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ensure.h"

/// `program` gets the absolute path of $WX_BUILD/weathering (default build),
/// `dir` that of $WX_BUILD/tmp/NAME, made with a meshes/ folder inside (both
/// PATH_MAX). False, with a message on stderr, when either cannot be had.
static inline bool bench_workdir(const char *name, char *program, char *dir)
{
    const char *build = getenv("WX_BUILD") != NULL ? getenv("WX_BUILD") : "build";
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/weathering", build);
    if (realpath(path, program) == NULL) {
        fprintf(stderr, "%s: no %s\n", name, path);
        return false;
    }
    char cmd[2 * PATH_MAX];
    snprintf(cmd, sizeof cmd, "mkdir -p '%s/tmp/%s/meshes'", build, name);
    snprintf(path, sizeof path, "%s/tmp/%s", build, name);
    if (system(cmd) != 0 || realpath(path, dir) == NULL) {
        fprintf(stderr, "%s: cannot make %s\n", name, path);
        return false;
    }
    return true;
}

/// Runs `PROGRAM ARGS --stats stats.json -q` in `dir`: the --stats JSON
/// (malloc'd), or NULL with the command on stderr.
static inline char *bench_run(const char *program, const char *dir, const char *args)
{
    char cmd[4 * PATH_MAX];
    snprintf(cmd, sizeof cmd, "cd '%s' && rm -f stats.json && '%s' %s --stats stats.json -q", dir,
             program, args);
    if (system(cmd) != 0) {
        fprintf(stderr, "bench: failed: %s\n", cmd);
        return NULL;
    }
    char path[PATH_MAX + 16];
    snprintf(path, sizeof path, "%s/stats.json", dir);
    return ensure_read_file(path);
}

/// `run SCENE --out out` in `dir`: the simulate phase's stepping seconds
/// (--stats simulate_seconds.steps), NAN when the run fails.
static inline double bench_steps_seconds(const char *program, const char *dir, const char *scene)
{
    char args[PATH_MAX];
    snprintf(args, sizeof args, "run '%s' --out out", scene);
    char *json = bench_run(program, dir, args);
    double s = json != NULL ? ensure_json_number(json, NULL, "steps") : NAN;
    free(json);
    return s;
}

/// xml_scenes/rusty_tank.xml (malloc'd) without its <Masks>, its meshes copied
/// to dir/meshes; NULL, with a message from `who` on stderr, when not run from
/// the repository's root.
static inline char *bench_tank_scene(const char *dir, const char *who)
{
    char cmd[2 * PATH_MAX];
    snprintf(cmd, sizeof cmd,
             "cp xml_scenes/meshes/tank.obj xml_scenes/meshes/tank.mtl '%s/meshes/'", dir);
    char *scene = ensure_read_file("xml_scenes/rusty_tank.xml");
    if (system(cmd) != 0 || scene == NULL) {
        fprintf(stderr, "%s: run from the repository's root\n", who);
        free(scene);
        return NULL;
    }
    char *masks = strstr(scene, "<Masks>");
    char *masks_end = masks != NULL ? strstr(masks, "</Masks>") : NULL;
    if (masks_end != NULL) {
        masks_end += strlen("</Masks>");
        memmove(masks, masks_end, strlen(masks_end) + 1);
    }
    return scene;
}

/// `text` with the first `from` of each of the n pairs (from, to) replaced by
/// `to`, written to dir/name; false, with a message from `who`, when a `from`
/// is not in it.
static inline bool bench_write_variant(const char *dir, const char *who, const char *text,
                                       const char *const *pairs, int n, const char *name)
{
    char *out = malloc(strlen(text) * 2 + 4096);
    if (out == NULL) {
        return false;
    }
    strcpy(out, text);
    for (int k = 0; k < n; ++k) {
        char *at = strstr(out, pairs[2 * k]);
        if (at == NULL) {
            fprintf(stderr, "%s: '%s' not in the scene\n", who, pairs[2 * k]);
            free(out);
            return false;
        }
        size_t from = strlen(pairs[2 * k]), to = strlen(pairs[2 * k + 1]);
        memmove(at + to, at + from, strlen(at + from) + 1);
        memcpy(at, pairs[2 * k + 1], to);
    }
    bool ok = ensure_write_file(dir, name, out) != NULL;
    free(out);
    return ok;
}

#endif
