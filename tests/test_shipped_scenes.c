// test_shipped_scenes.c: every shipped scene (xml_scenes/*.xml), run once as a
// user runs it. `weathering info` validates it and estimates its memory; one
// `weathering run --stats` under wait4 then checks that the estimate bounds
// the run's real peak, by at most 3 times (issue 13), that every substance's
// ledger of the stats balances (docs/design.md section 10), and that the run
// warns of nothing: the examples are what users copy, and a warning of their
// own (half the particles wasted, many still flying at the end, the model
// outside the output camera's frame) teaches them to ignore warnings. These
// are the suite's longest tests (a minute on two cores): one run per scene
// serves every check.
#define _DEFAULT_SOURCE // wait4
#include <dirent.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "ensure.h"
#include "memory_fixture.h"

// Every substance's ledger of a --stats file balances (exact to rounding);
// returns how many substances it checked, -1 when one does not balance.
static int ledger_balances(const char *json)
{
    const char *at = strstr(json, "\"substances\": {");
    if (at == NULL) {
        return -1;
    }
    int checked = 0;
    for (at = strstr(at + 15, "\": { \"initial_surface\""); at != NULL;
         at = strstr(at + 1, "\": { \"initial_surface\"")) {
        double in, out;
        ensure_ledger_sides(at, &in, &out);
        if (!(fabs(in - out) <= 1e-9 * (fabs(in) + 1.0))) {
            fprintf(stderr, "        in %.17g, out %.17g\n", in, out);
            return -1;
        }
        checked++;
    }
    return checked;
}

// The lines of a run's stderr that are warnings, printed; how many there were.
static int print_warnings(const char *log)
{
    int warnings = 0;
    for (const char *line = log; line != NULL && *line != '\0';) {
        const char *end = strchr(line, '\n');
        size_t n = end != NULL ? (size_t)(end - line) : strlen(line);
        const char *label = strstr(line, "warning: ");
        if (label != NULL && label < line + n) {
            fprintf(stderr, "        %.*s\n", (int)n, line);
            warnings++;
        }
        line = end != NULL ? end + 1 : NULL;
    }
    return warnings;
}

// Every shipped scene validates (info), its run takes no more memory than info
// estimates and at least a third of it, every substance's ledger balances, and
// the run prints no warning.
TEST(every_shipped_scene_runs_within_its_memory_estimate_balances_and_warns_of_nothing)
{
    SLOW();
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
    SKIP("sanitizers change the memory a run takes, and the shipped scenes take minutes "
         "under them");
#endif
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/../xml_scenes", ensure_tests_dir());
    DIR *d = opendir(dir);
    ENSURE(d != NULL);
    int scenes = 0, failures = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        size_t n = strlen(e->d_name);
        if (n < 5 || strcmp(e->d_name + n - 4, ".xml") != 0) {
            continue;
        }
        scenes++;
        char scene[4500], out[4500], stats[4500], log[4500];
        snprintf(scene, sizeof scene, "%s/%s", dir, e->d_name);
        snprintf(out, sizeof out, "%s/%s", ensure_tmpdir(), e->d_name);
        snprintf(stats, sizeof stats, "%s/%s.json", ensure_tmpdir(), e->d_name);
        snprintf(log, sizeof log, "%s/%s.log", ensure_tmpdir(), e->d_name);
        double estimate = estimate_mib(scene);
        double peak = command_peak_mib_logged("run", scene, out, stats, log);
        char *json = ensure_read_file(stats);
        int balanced = json != NULL ? ledger_balances(json) : -1;
        free(json);
        char *printed = ensure_read_file(log);
        int warnings = printed != NULL ? print_warnings(printed) : -1;
        free(printed);
        bool bounded = peak > 0.0 && estimate >= peak && estimate <= 3.0 * peak;
        fprintf(stderr,
                "        %-16s estimate %6.0f MiB, peak %6.0f MiB (%.2fx)%s; "
                "%d substance(s) balance; %d warning(s)\n",
                e->d_name, estimate, peak, estimate / peak, bounded ? "" : " NOT BOUNDED", balanced,
                warnings);
        failures += !bounded || balanced < 1 || warnings != 0;
    }
    closedir(d);
    ENSURE(scenes >= 6); // the shipped scenes are part of the project
    ENSURE(failures == 0);
}

int main(void)
{
    RUN(every_shipped_scene_runs_within_its_memory_estimate_balances_and_warns_of_nothing);
    return ensure_summary();
}
