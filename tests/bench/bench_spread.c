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

int main(void)
{
    if (!bench_workdir("bench_spread", program, dir)) {
        return 1;
    }
    char *scene = bench_tank_scene(dir, "bench_spread");
    if (scene == NULL) {
        return 1;
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
    if (!bench_write_variant(dir, "bench_spread", scene, plain, 3, "plain.xml") ||
        !bench_write_variant(dir, "bench_spread", scene, spread, 4, "spread.xml")) {
        return 1;
    }
    free(scene);
    enum { MAX_REPS = 9 };
    int reps = (int)bench_env_long("WX_BENCH_REPS", 3);
    reps = reps > MAX_REPS ? MAX_REPS : reps;
    double t0[MAX_REPS], t1[MAX_REPS];
    for (int k = 0; k < reps; ++k) {
        t0[k] = bench_steps_seconds(program, dir, "plain.xml");
        t1[k] = bench_steps_seconds(program, dir, "spread.xml");
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
