// memory_fixture.h: what the tests of the memory estimate share
// (test_memory.c, test_shipped_scenes.c): a run's real peak and info's
// estimate of it. Include after defining _DEFAULT_SOURCE (wait4).
#ifndef WX_MEMORY_FIXTURE_H
#define WX_MEMORY_FIXTURE_H

#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "ensure.h"

/// Runs `weathering COMMAND SCENE --out DIR -q` (with `--stats STATS` unless
/// stats is NULL) from the repository's root and returns its peak resident
/// memory in MiB (wait4's ru_maxrss), or -1 when it did not exit with status 0.
/// With a log, the run is not quiet and its stderr (warnings, notes, the
/// summary) goes to that file.
static inline double command_peak_mib_logged(const char *command, const char *scene,
                                             const char *dir, const char *stats, const char *log)
{
    char program[4200];
    snprintf(program, sizeof program, "%s/weathering", ensure_build_dir());
    pid_t pid = fork();
    if (pid == 0) {
        int null = open("/dev/null", O_WRONLY);
        int err = log != NULL ? open(log, O_WRONLY | O_CREAT | O_TRUNC, 0644) : null;
        dup2(null, STDOUT_FILENO);
        dup2(err >= 0 ? err : null, STDERR_FILENO);
        const char *argv[10] = { program, command, scene, "--out", dir };
        int n = 5;
        if (log == NULL) {
            argv[n++] = "-q";
        }
        if (stats != NULL) {
            argv[n++] = "--stats";
            argv[n++] = stats;
        }
        argv[n] = NULL;
        execv(program, (char *const *)argv);
        _exit(98);
    }
    int status = 0;
    struct rusage usage;
    if (pid < 0 || wait4(pid, &status, 0, &usage) != pid || !WIFEXITED(status) ||
        WEXITSTATUS(status) != 0) {
        return -1.0;
    }
    return (double)usage.ru_maxrss / 1024.0;
}

/// command_peak_mib_logged without a log: a quiet run.
static inline double command_peak_mib(const char *command, const char *scene, const char *dir,
                                      const char *stats)
{
    return command_peak_mib_logged(command, scene, dir, stats, NULL);
}

/// command_peak_mib of `weathering run`.
static inline double run_peak_mib(const char *scene, const char *dir, const char *stats)
{
    return command_peak_mib("run", scene, dir, stats);
}

/// info's "memory: about N MiB at the peak" of a scene; -1 when info fails (the
/// scene does not validate: its output goes to stderr) or does not say it.
static inline double estimate_mib(const char *scene)
{
    static char log[16384];
    int status =
        ensure_shell(log, sizeof log, "'%s/weathering' info '%s'", ensure_build_dir(), scene);
    if (status != 0) {
        fprintf(stderr, "        info %s: status %d\n%s\n", scene, status, log);
        return -1.0;
    }
    const char *at = strstr(log, "memory: about ");
    return at != NULL ? atof(at + strlen("memory: about ")) : -1.0;
}

#endif
