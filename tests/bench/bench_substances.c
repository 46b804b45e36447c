// bench_substances.c: several substances cost little (issue 16). The rusty
// tank (xml_scenes/rusty_tank.xml) simulated with its four substances and with
// the same rain carrying one, ten iterations without frames: the simulate
// phase's stepping (--stats simulate_seconds.steps) with four substances must
// run at least 70% as fast as with one. Median of 3 runs each, alternating.
// The scene's <Masks> are removed from both variants.
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
    if (!bench_workdir("bench_substances", program, dir)) {
        return 1;
    }
    // The derived masks are left out of both (they are gathered, not stepped,
    // and the mask `mossy` names the water the one-substance variant drops).
    char *scene = bench_tank_scene(dir, "bench_substances");
    if (scene == NULL) {
        return 1;
    }
    // Four substances, no frames; and one substance (version 1's dirt), the same rain.
    const char *four[] = { "every=\"1\"", "every=\"0\"" };
    // clang-format off: the pairs (from, to), one a line
    const char *one[] = {
        "every=\"1\"", "every=\"0\"",
        "<Substance name=\"water\"/>\n    <Substance name=\"dirt\"/>\n    <Substance name=\"rust\"/>\n"
        "    <Substance name=\"moss\"/>",
        "<Substance name=\"dirt\"/>",
        "<Load substance=\"water\" amount=\"1\"/>", "",
        "<Decay substance=\"water\" rate=\"0.5\"/>", "<Decay substance=\"dirt\" rate=\"0.5\"/>",
        "<Exchange substance=\"water\" deposit=\"0.3\" erosion=\"0.05\"/>", "",
        "<Transfer from=\"water\" to=\"rust\" rate=\"0.2\"/>", "",
        "<Exchange substance=\"water\" deposit=\"0.8\" erosion=\"0.02\"/>", "",
        "<Transfer from=\"water\" to=\"moss\" rate=\"0.1\"/>", "",
    };
    // clang-format on
    if (!bench_write_variant(dir, "bench_substances", scene, four, 1, "four.xml") ||
        !bench_write_variant(dir, "bench_substances", scene, one, 8, "one.xml")) {
        return 1;
    }
    free(scene);
    double t1[3], t4[3];
    for (int k = 0; k < 3; ++k) {
        t1[k] = bench_steps_seconds(program, dir, "one.xml");
        t4[k] = bench_steps_seconds(program, dir, "four.xml");
    }
    double s1 = bench_median(t1, 3), s4 = bench_median(t4, 3);
    double share = s1 / s4;
    printf("substances: rusty tank, 600000 particles over 10 iterations, simulate steps "
           "(median of 3)\n");
    printf("  1 substance  %.2f s\n  4 substances %.2f s\n  speed with 4 / with 1: %.0f%%\n", s1,
           s4, 100 * share);
    bench_row("substances", "simulate steps", s1, "s", NULL, false, "1 substance");
    bench_row("substances", "simulate steps", s4, "s", NULL, false, "4 substances");
    bench_row("substances", "speed 4 / 1 substances", 100 * share, "%", ">= 70", share >= 0.7,
              "rusty tank");
    return isfinite(share) ? 0 : 1;
}
