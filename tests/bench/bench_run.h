// bench_run.h: what the benchmarks that run the `weathering` command share:
// their folder under $WX_BUILD/tmp, the program's absolute path, and one run
// of it that returns its --stats JSON. Include after defining _XOPEN_SOURCE 700
// (realpath).
#ifndef WX_BENCH_RUN_H
#define WX_BENCH_RUN_H

#include <limits.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>

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
    snprintf(cmd, sizeof cmd, "cd '%s' && rm -f stats.json && '%s' %s --stats stats.json -q",
             dir, program, args);
    if (system(cmd) != 0) {
        fprintf(stderr, "bench: failed: %s\n", cmd);
        return NULL;
    }
    char path[PATH_MAX + 16];
    snprintf(path, sizeof path, "%s/stats.json", dir);
    return ensure_read_file(path);
}

#endif
