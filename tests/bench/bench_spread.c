// bench_spread.c: spreading costs little (issue 28). The rusty tank
// (xml_scenes/rusty_tank.xml) over 20 iterations without frames, with a fifth
// substance "bloom" that a <Seed> starts where water lies and a <Spread>
// (radius 5 cm, probability 0.5) carries along the surface after every
// iteration, against the same scene with "bloom" declared and no rule for it:
// the simulate phase's stepping (--stats simulate_seconds.steps, which holds
// the ageing) with the automata must take at most 1.5 times as long. Median of
// WX_BENCH_REPS (default 3) runs each, alternating. The scene's <Masks> are
// removed from both variants.
#define _XOPEN_SOURCE 700 // realpath
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_report.h"
#include "bench_run.h"
#include "ensure.h"

static char dir[PATH_MAX];
static char program[PATH_MAX];

static double steps_seconds(const char *scene)
{
    char args[PATH_MAX];
    snprintf(args, sizeof args, "run '%s' --out out", scene);
    char *json = bench_run(program, dir, args);
    double s = json != NULL ? ensure_json_number(json, NULL, "steps") : NAN;
    free(json);
    return s;
}

// `text` with the first `from` of each pair replaced by `to`, written to dir/name.
static bool write_variant(const char *text, const char *const *pairs, int n, const char *name)
{
    char *out = malloc(strlen(text) * 2 + 4096);
    if (out == NULL) {
        return false;
    }
    strcpy(out, text);
    for (int k = 0; k < n; ++k) {
        char *at = strstr(out, pairs[2 * k]);
        if (at == NULL) {
            fprintf(stderr, "bench_spread: '%s' not in the scene\n", pairs[2 * k]);
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

int main(void)
{
    if (!bench_workdir("bench_spread", program, dir)) {
        return 1;
    }
    char cmd[2 * PATH_MAX];
    snprintf(cmd, sizeof cmd,
             "cp xml_scenes/meshes/tank.obj xml_scenes/meshes/tank.mtl '%s/meshes/'", dir);
    char *scene = ensure_read_file("xml_scenes/rusty_tank.xml");
    if (system(cmd) != 0 || scene == NULL) {
        fprintf(stderr, "bench_spread: run from the repository's root\n");
        return 1;
    }
    char *masks = strstr(scene, "<Masks>");
    char *masks_end = masks != NULL ? strstr(masks, "</Masks>") : NULL;
    if (masks_end != NULL) {
        masks_end += strlen("</Masks>");
        memmove(masks, masks_end, strlen(masks_end) + 1);
    }
    const char *plain[] = {
        "every=\"1\"",
        "every=\"0\"",
        "iterations=\"10\"",
        "iterations=\"20\"",
        "<Substance name=\"moss\"/>",
        "<Substance name=\"moss\"/><Substance name=\"bloom\"/>",
    };
    const char *spread[] = {
        "every=\"1\"",
        "every=\"0\"",
        "iterations=\"10\"",
        "iterations=\"20\"",
        "<Substance name=\"moss\"/>",
        "<Substance name=\"moss\"/><Substance name=\"bloom\"/>",
        "<Decay substance=\"water\" rate=\"0.5\"/>",
        "<Decay substance=\"water\" rate=\"0.5\"/>"
        "<Seed substance=\"bloom\" where=\"water\" min=\"0.2\" density=\"2\"/>"
        "<Spread substance=\"bloom\" radius=\"0.05\" probability=\"0.5\" where=\"water\" "
        "min=\"0.2\"/>",
    };
    if (!write_variant(scene, plain, 3, "plain.xml") ||
        !write_variant(scene, spread, 4, "spread.xml")) {
        return 1;
    }
    free(scene);
    enum { MAX_REPS = 9 };
    int reps = (int)bench_env_long("WX_BENCH_REPS", 3);
    reps = reps > MAX_REPS ? MAX_REPS : reps;
    double t0[MAX_REPS], t1[MAX_REPS];
    for (int k = 0; k < reps; ++k) {
        t0[k] = steps_seconds("plain.xml");
        t1[k] = steps_seconds("spread.xml");
    }
    double s0 = bench_median(t0, reps), s1 = bench_median(t1, reps);
    double ratio = s1 / s0;
    printf("spread: rusty tank, 20 iterations, simulate steps (median of %d)\n", reps);
    printf("  without Seed/Spread %.2f s\n  with Seed/Spread    %.2f s\n  ratio %.2fx\n", s0, s1,
           ratio);
    bench_row("spread", "simulate steps", s0, "s", NULL, false, "rusty tank 20 it. no Spread");
    bench_row("spread", "simulate steps", s1, "s", NULL, false, "rusty tank 20 it. Seed+Spread");
    bench_row("spread", "time with / without Spread", ratio, "x", "<= 1.5", ratio <= 1.5,
              "rusty tank 20 iterations");
    return isfinite(ratio) ? 0 : 1;
}
