// run_fixture.h: what the tests that run the `weathering` command on scenes of
// their own share: running it in a folder (its output kept in `out`), the
// path of a file in tests/data (ensure_read_channel reads what it wrote). Include
// after defining _XOPEN_SOURCE 700 (realpath).
#ifndef WX_RUN_FIXTURE_H
#define WX_RUN_FIXTURE_H

#include <limits.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>

#include "ensure.h"
#include "io/exr.h"
#include "model/image.h"

/// What the last command printed (stdout and stderr).
static char out[65536];

/// Runs `weathering ARGS` in `dir`; its exit status. With show_failure, a
/// failure's output goes to stderr.
static inline int weathering_in(const char *dir, const char *args, bool show_failure)
{
    char build[PATH_MAX];
    if (realpath(ensure_build_dir(), build) == NULL) {
        return -1;
    }
    int status = ensure_shell(out, sizeof out, "cd '%s' && '%s/weathering' %s 2>&1", dir, build,
                              args);
    if (status != 0 && show_failure) {
        fprintf(stderr, "        %s", out);
    }
    return status;
}

/// The absolute path of tests/data/NAME.
static inline const char *data_file(const char *name)
{
    static char path[PATH_MAX + 64], tests[PATH_MAX];
    if (realpath(ensure_tests_dir(), tests) == NULL) {
        return name;
    }
    snprintf(path, sizeof path, "%s/data/%s", tests, name);
    return path;
}

#endif
