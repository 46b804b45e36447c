// bench_masks.c: the derived masks' cost (issue 18). The default house
// (xml_scenes/building.xml: three 1024-px input cameras, a 1024 x 1024 output
// camera) is run once; its gather is then repeated on the maps it left, without
// masks, with an Accessibility of 32 rays over 2 m, and with an Exposure of a
// sun and two side suns. A mask's cost is its gather's compute time
// (--stats gather_seconds.compute) minus the gather's without masks, on 2
// threads. Targets: accessibility at most 15 s, exposure at most 2 s.
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

// The gather's compute seconds of `scene` on the maps in dir/out.
static double gather_seconds(const char *scene)
{
    char args[PATH_MAX];
    snprintf(args, sizeof args, "gather '%s' --out out --threads 2", scene);
    char *json = bench_run(program, dir, args);
    double s = ensure_json_number(json, "\"gather_seconds\"", "compute");
    free(json);
    return s;
}

// The house's scene with `masks` (a <Masks> element, or "") and no TextureMap.
static bool write_variant(const char *text, const char *masks, const char *name)
{
    char *out = malloc(strlen(text) + strlen(masks) + 64);
    if (out == NULL) {
        return false;
    }
    strcpy(out, text);
    char *tex = strstr(out, "<TextureMap");
    if (tex != NULL) {
        char *end = strstr(tex, "/>");
        memmove(tex, end + 2, strlen(end + 2) + 1);
    }
    char *root = strstr(out, "</Weathering>");
    if (root == NULL) {
        free(out);
        return false;
    }
    sprintf(root, "%s\n</Weathering>\n", masks);
    bool ok = ensure_write_file(dir, name, out) != NULL;
    free(out);
    return ok;
}

int main(void)
{
    if (!bench_workdir("bench_masks", program, dir)) {
        return 1;
    }
    char cmd[3 * PATH_MAX];
    snprintf(cmd, sizeof cmd,
             "cp xml_scenes/meshes/building.obj xml_scenes/meshes/building.mtl '%s/meshes/'", dir);
    char *scene = ensure_read_file("xml_scenes/building.xml");
    if (system(cmd) != 0 || scene == NULL) {
        fprintf(stderr, "bench_masks: run from the repository's root\n");
        return 1;
    }
    bool ok = write_variant(scene, "", "none.xml") &&
              write_variant(scene,
                            "<Masks><Accessibility name=\"ao\" rays=\"32\" distance=\"2\"/></Masks>",
                            "ao.xml") &&
              write_variant(scene,
                            "<Masks><Exposure name=\"sun\" elevation=\"40\" azimuth=\"60\" "
                            "sideWeight=\"0.5\" sideElevation=\"0.6\" sideSpread=\"50\"/></Masks>",
                            "sun.xml");
    free(scene);
    char *json = ok ? bench_run(program, dir, "run none.xml --out out --threads 2") : NULL;
    free(json);
    if (json == NULL) {
        fprintf(stderr, "bench_masks: cannot run the house\n");
        return 1;
    }
    double base[3], ao[3], sun[3];
    for (int k = 0; k < 3; ++k) {
        base[k] = gather_seconds("none.xml");
        ao[k] = gather_seconds("ao.xml");
        sun[k] = gather_seconds("sun.xml");
    }
    double b = bench_median(base, 3);
    double a = bench_median(ao, 3) - b, s = bench_median(sun, 3) - b;
    printf("masks: the default house, 1024 x 1024 output texels, three 1024-px input cameras, "
           "2 threads (median of 3)\n");
    printf("  gather without masks %.2f s\n  accessibility, 32 rays over 2 m: %.2f s\n"
           "  exposure, a sun and two side suns: %.2f s\n",
           b, a, s);
    bench_row("masks", "gather without masks", b, "s", NULL, false, "house 1024");
    bench_row("masks", "accessibility 32 rays", a, "s", "<= 15", a <= 15.0, "house 1024");
    bench_row("masks", "exposure 3 suns", s, "s", "<= 2", s <= 2.0, "house 1024");
    return isfinite(a) && isfinite(s) ? 0 : 1;
}
