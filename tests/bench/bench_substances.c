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

static double steps_seconds(const char *scene)
{
    char args[PATH_MAX];
    snprintf(args, sizeof args, "run '%s' --out out", scene);
    char *json = bench_run(program, dir, args);
    double s = ensure_json_number(json, NULL, "steps");
    free(json);
    return s;
}

// `text` with every `from` replaced by `to`, written to dir/name.
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
            fprintf(stderr, "bench_substances: '%s' not in the scene\n", pairs[2 * k]);
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
    if (!bench_workdir("bench_substances", program, dir)) {
        return 1;
    }
    char cmd[2 * PATH_MAX];
    snprintf(cmd, sizeof cmd, "cp xml_scenes/meshes/tank.obj xml_scenes/meshes/tank.mtl '%s/meshes/'",
             dir);
    char *scene = ensure_read_file("xml_scenes/rusty_tank.xml");
    if (system(cmd) != 0 || scene == NULL) {
        fprintf(stderr, "bench_substances: run from the repository's root\n");
        return 1;
    }
    // The derived masks are left out of both (they are gathered, not stepped,
    // and the mask `mossy` names the water the one-substance variant drops).
    char *masks = strstr(scene, "<Masks>");
    char *masks_end = masks != NULL ? strstr(masks, "</Masks>") : NULL;
    if (masks_end != NULL) {
        masks_end += strlen("</Masks>");
        memmove(masks, masks_end, strlen(masks_end) + 1);
    }
    // Four substances, no frames; and one substance (version 1's dirt), the same rain.
    const char *four[] = { "every=\"1\"", "every=\"0\"" };
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
    if (!write_variant(scene, four, 1, "four.xml") || !write_variant(scene, one, 8, "one.xml")) {
        return 1;
    }
    free(scene);
    double t1[3], t4[3];
    for (int k = 0; k < 3; ++k) {
        t1[k] = steps_seconds("one.xml");
        t4[k] = steps_seconds("four.xml");
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
