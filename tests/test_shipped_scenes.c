// test_shipped_scenes.c: every shipped scene (xml_scenes/*.xml), run once as a
// user runs it. `weathering info` validates it and estimates its memory; one
// `weathering run --stats` under wait4 then checks both that the estimate bounds
// the run's real peak, by at most 3 times (issue 13), and that every
// substance's ledger of the stats balances (docs/design.md section 10). These
// are the suite's longest tests (a minute on two cores): one run per scene
// serves both checks.
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

// Every shipped scene validates (info), its run takes no more memory than info
// estimates and at least a third of it, and every substance's ledger balances.
TEST(every_shipped_scene_runs_within_its_memory_estimate_and_balances)
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
        char scene[4500], out[4500], stats[4500];
        snprintf(scene, sizeof scene, "%s/%s", dir, e->d_name);
        snprintf(out, sizeof out, "%s/%s", ensure_tmpdir(), e->d_name);
        snprintf(stats, sizeof stats, "%s/%s.json", ensure_tmpdir(), e->d_name);
        double estimate = estimate_mib(scene);
        double peak = run_peak_mib(scene, out, stats);
        char *json = ensure_read_file(stats);
        int balanced = json != NULL ? ledger_balances(json) : -1;
        free(json);
        bool bounded = peak > 0.0 && estimate >= peak && estimate <= 3.0 * peak;
        fprintf(stderr,
                "        %-16s estimate %6.0f MiB, peak %6.0f MiB (%.2fx)%s; "
                "%d substance(s) balance\n",
                e->d_name, estimate, peak, estimate / peak, bounded ? "" : " NOT BOUNDED",
                balanced);
        failures += !bounded || balanced < 1;
    }
    closedir(d);
    ENSURE(scenes >= 6); // the shipped scenes are part of the project
    ENSURE(failures == 0);
}

int main(void)
{
    RUN(every_shipped_scene_runs_within_its_memory_estimate_and_balances);
    return ensure_summary();
}
