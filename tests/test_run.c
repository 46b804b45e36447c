// test_run.c: the whole pipeline through the command line. `run` equals `bake`,
// `simulate` and `gather` run one after the other; running a phase again into the
// same folder gives the same bytes (a simulated dirt map keeps the dirt it started
// from). The shipped scenes are run in test_shipped_scenes.c.
#define _DEFAULT_SOURCE // wait4
#include <dirent.h>
#include <math.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "ensure.h"
#include "io/exr.h"
#include "model/maps.h"
#include "io/maps_file.h"
#include "model/image.h"

// A cube [-1,1]^3 with dirt 0.5 on it, seen from the front and the top; drops fall
// on it from a point above.
static const char SCENE_XML[] =
    "<Weathering>\n"
    "  <Solver><Simulation timeStep=\"0.01\" steps=\"150\" seed=\"7\"/></Solver>\n"
    "  <ForceFields><Gravity acceleration=\"9.8\"/></ForceFields>\n"
    "  <Emitters>\n"
    "    <PointEmitter name=\"drops\" centerX=\"0.2\" centerY=\"3\" centerZ=\"0.1\" rate=\"2000\"\n"
    "                  end=\"0.5\" speed=\"1\" dirt=\"1\"/>\n"
    "  </Emitters>\n"
    "  <Collider>\n"
    "    <ProjectedMaps>\n"
    "      <Ortho cameraName=\"front\">\n"
    "        <View eye=\"0 0 5\" target=\"0 0 0\" up=\"0 1 0\" width=\"4\" height=\"4\" "
    "resolution=\"64\"/>\n"
    "      </Ortho>\n"
    "      <Ortho cameraName=\"top\">\n"
    "        <View eye=\"0 5 0\" target=\"0 0 0\" up=\"0 0 -1\" width=\"4\" height=\"4\" "
    "resolution=\"64\"/>\n"
    "      </Ortho>\n"
    "      <Ortho cameraName=\"shot\" out=\"true\">\n"
    "        <View eye=\"3 4 5\" target=\"0 0 0\" up=\"0 1 0\" width=\"5\" height=\"5\" "
    "resolution=\"48\"/>\n"
    "        <OutputMap file=\"mask.exr\" width=\"48\" height=\"48\"/>\n"
    "      </Ortho>\n"
    "    </ProjectedMaps>\n"
    "  </Collider>\n"
    "  <Geometry>\n"
    "    <Mesh file=\"box.obj\">\n"
    "      <Surface material=\"*\" absorption=\"0.1\" bounce=\"0.3\" dirt=\"0.5\" "
    "deposit=\"0.5\" erosion=\"0.25\"/>\n"
    "    </Mesh>\n"
    "  </Geometry>\n"
    "</Weathering>\n";

// `text` with its first `from` replaced by `to` (malloc'd).
static char *replace_once(const char *text, const char *from, const char *to)
{
    const char *at = strstr(text, from);
    if (at == NULL) {
        return NULL;
    }
    size_t head = (size_t)(at - text), n = strlen(text) - strlen(from) + strlen(to);
    char *out = malloc(n + 1);
    if (out != NULL) {
        snprintf(out, n + 1, "%.*s%s%s", (int)head, text, to, at + strlen(from));
    }
    return out;
}

static const char *scene_dir(void)
{
    static char dir[4200];
    if (dir[0] == '\0') {
        snprintf(dir, sizeof dir, "%s/scene", ensure_tmpdir());
        mkdir(dir, 0777);
        char src[4200];
        snprintf(src, sizeof src, "%s/data/bake_box.obj", ensure_tests_dir());
        char *box = ensure_read_file(src);
        ensure_write_file(dir, "box.obj", box != NULL ? box : "");
        free(box);
        ensure_write_file(dir, "scene.xml", SCENE_XML);
        // The same with three layers a camera and an accessibility mask: a run
        // keeps the bake's layered images for its simulation and steps through
        // the masks' collider (pipeline/run.c); the phases read files and build
        // a collider each.
        char *layered = replace_once(SCENE_XML, "<Ortho cameraName=\"front\">",
                                     "<Ortho cameraName=\"front\" layers=\"3\">");
        char *both = replace_once(layered, "<Ortho cameraName=\"top\">",
                                  "<Ortho cameraName=\"top\" layers=\"3\">");
        char *masked = replace_once(both, "  <Geometry>",
                                    "  <Masks><Accessibility name=\"ao\" rays=\"16\" "
                                    "distance=\"1\"/></Masks>\n  <Geometry>");
        ensure_write_file(dir, "layered.xml", masked != NULL ? masked : "");
        free(layered);
        free(both);
        free(masked);
    }
    return dir;
}

// Runs `weathering COMMAND` on the test scene file NAME with --out DIR; returns
// the exit status.
static int weathering_on(const char *command, const char *name, const char *out_dir)
{
    char log[4096];
    int status = ensure_shell(log, sizeof log, "'%s/weathering' %s '%s/%s' --out '%s' -q",
                              ensure_build_dir(), command, scene_dir(), name, out_dir);
    if (status != 0) {
        fprintf(stderr, "        weathering %s: status %d\n%s\n", command, status, log);
    }
    return status;
}

static int weathering(const char *command, const char *out_dir)
{
    return weathering_on(command, "scene.xml", out_dir);
}

static bool same_bytes(const char *dir_a, const char *dir_b, const char *name)
{
    char log[512];
    return ensure_shell(log, sizeof log, "cmp -s '%s/%s' '%s/%s'", dir_a, name, dir_b, name) == 0;
}

static const char *out_dir(const char *name)
{
    static char dirs[4][4200];
    static int next;
    char *dir = dirs[next++ % 4];
    snprintf(dir, sizeof dirs[0], "%s/%s", ensure_tmpdir(), name);
    return dir;
}

TEST(run_equals_bake_simulate_gather)
{
    const char *whole = out_dir("whole");
    const char *phases = out_dir("phases");
    ENSURE(weathering("run", whole) == 0);
    ENSURE(weathering("bake", phases) == 0);
    ENSURE(weathering("simulate", phases) == 0);
    ENSURE(weathering("gather", phases) == 0);
    static const char *const files[] = { "front_depth.exr", "top_normal.exr", "front_impact.exr",
                                         "front_dirt.exr", "top_dirt.exr", "mask.exr",
                                         "mask.png" };
    for (size_t f = 0; f < sizeof files / sizeof files[0]; ++f) {
        ENSURE(same_bytes(whole, phases, files[f]));
    }
}

TEST(a_layered_run_with_masks_equals_its_phases)
{
    const char *whole = out_dir("layered_whole");
    const char *phases = out_dir("layered_phases");
    ENSURE(weathering_on("run", "layered.xml", whole) == 0);
    ENSURE(weathering_on("bake", "layered.xml", phases) == 0);
    ENSURE(weathering_on("simulate", "layered.xml", phases) == 0);
    ENSURE(weathering_on("gather", "layered.xml", phases) == 0);
    static const char *const files[] = { "front_depth.exr", "top_impact.exr", "front_dirt.exr",
                                         "top_dirt.exr",    "mask.exr",       "mask_ao.png",
                                         "mask_dirt.png" };
    for (size_t f = 0; f < sizeof files / sizeof files[0]; ++f) {
        ENSURE(same_bytes(whole, phases, files[f]));
    }
    // The mask holds the accessibility, and the dirt the drops brought.
    wx_image mask;
    wx_error err;
    char path[4300];
    snprintf(path, sizeof path, "%s/mask.exr", whole);
    ENSURE(wx_exr_read(path, NULL, 0, &mask, &err) == WX_OK);
    bool has_ao = false;
    float most_dirt = 0.0f;
    size_t texels = (size_t)mask.width * (size_t)mask.height;
    for (int c = 0; c < mask.channel_count; ++c) {
        has_ao = has_ao || strcmp(mask.channel_names[c], "ao.Y") == 0;
        for (size_t t = 0; strcmp(mask.channel_names[c], "dirt.Y") == 0 && t < texels; ++t) {
            most_dirt = fmaxf(most_dirt, mask.channels[c][t]);
        }
    }
    wx_image_free(&mask);
    ENSURE(has_ao);
    ENSURE(most_dirt > 0.0f);
}

TEST(simulating_again_starts_from_the_initial_dirt)
{
    const char *first = out_dir("first");
    const char *again = out_dir("again");
    ENSURE(weathering("run", first) == 0);
    ENSURE(weathering("run", again) == 0);
    // The second simulate reads the dirt map the first one wrote: it must start
    // from the cube's 0.5, not from the first result.
    ENSURE(weathering("simulate", again) == 0);
    ENSURE(weathering("gather", again) == 0);
    ENSURE(same_bytes(first, again, "top_dirt.exr"));
    ENSURE(same_bytes(first, again, "mask.exr"));
}

TEST(simulated_dirt_map_holds_result_and_initial_dirt)
{
    const char *dir = out_dir("channels");
    ENSURE(weathering("run", dir) == 0);
    char path[4400];
    snprintf(path, sizeof path, "%s/top_dirt.exr", dir);
    static const char *const names[4] = { "R", "G", "B", WX_INITIAL_DIRT_CHANNEL };
    wx_image *image = calloc(1, sizeof *image);
    ENSURE(image != NULL);
    wx_error err;
    wx_result r = wx_exr_read(path, names, 4, image, &err);
    if (r != WX_OK) {
        fprintf(stderr, "        %s\n", err.message);
        free(image);
    }
    ENSURE(r == WX_OK);
    // The centre texel of the top view sees the cube's top face head-on (surface
    // values 0.5 dirt per square metre, 0.5 deposit, 0.25 erosion): it holds
    // 0.5 x its area (4 m / 64 texels)^2 of dirt. The drops fell there.
    size_t centre = (size_t)32 * 64 + 32, corner = 0;
    float initial = image->channels[3][centre], deposit = image->channels[1][centre];
    float erosion = image->channels[2][centre], corner_initial = image->channels[3][corner];
    double total = 0.0, total_initial = 0.0;
    for (size_t t = 0; t < (size_t)64 * 64; ++t) {
        total += image->channels[0][t];
        total_initial += image->channels[3][t];
    }
    wx_image_free(image);
    free(image);
    ENSURE_NEAR(initial, 0.5 * (4.0 / 64) * (4.0 / 64), 1e-9);
    ENSURE_NEAR(deposit, 0.5, 1e-6);
    ENSURE_NEAR(erosion, 0.25, 1e-6);
    ENSURE(corner_initial == 0.0f); // no surface in the corner of the frame
    ENSURE(total != total_initial); // the drops moved dirt
}

// Replaces every `from` in `text` by `to` (same length or not); returns a new string.
static char *replace_all(const char *text, const char *from, const char *to)
{
    size_t n = strlen(text), nf = strlen(from), nt = strlen(to), count = 0;
    for (const char *p = strstr(text, from); p != NULL; p = strstr(p + nf, from)) {
        count++;
    }
    char *out = malloc(n + count * (nt > nf ? nt - nf : 0) + 1);
    char *w = out;
    const char *r = text;
    for (const char *p = strstr(r, from); p != NULL; p = strstr(r, from)) {
        memcpy(w, r, (size_t)(p - r));
        w += p - r;
        memcpy(w, to, nt);
        w += nt;
        r = p + nf;
    }
    strcpy(w, r);
    return out;
}

// Mean of the building's mask over a world rectangle of the facade: the output
// camera looks at it from (0 6 20) with a 16 m frame, so world (x, y) is at
// column (x + 8) / 16 * W and row (14 - y) / 16 * H.
static double facade_mean(const wx_image *mask, double x0, double x1, double y0, double y1)
{
    int W = mask->width, H = mask->height, n = 0;
    double sum = 0.0;
    for (int j = 0; j < H; ++j) {
        double y = 14.0 - (j + 0.5) * 16.0 / H;
        for (int i = 0; i < W && y >= y0 && y <= y1; ++i) {
            double x = -8.0 + (i + 0.5) * 16.0 / W;
            if (x >= x0 && x <= x1) {
                sum += mask->channels[0][(size_t)j * (size_t)W + (size_t)i];
                n++;
            }
        }
    }
    return n > 0 ? sum / n : 0.0;
}

// Runs the default scene at half resolution and a quarter of the rain, with the
// sills' dust as shipped (dusty) or none; reads the mask's regions: the wall
// under the roof (piers, 10.5-11.6 m), the exposed piers (4.5-8.5 m) and the
// wall under the side windows' sills (0.3-1.0 m below each of floors 1-3).
static bool building_regions(bool dusty_sills, double *band, double *exposed, double *below)
{
    char path[4400];
    snprintf(path, sizeof path, "%s/../xml_scenes/building.xml", ensure_tests_dir());
    char *xml = ensure_read_file(path);
    if (xml == NULL) {
        return false;
    }
    char *a = replace_all(xml, "rate=\"200000\"", "rate=\"50000\"");
    char *b = replace_all(a, "resolution=\"1024\"", "resolution=\"512\"");
    char *c = replace_all(b, "width=\"1024\" height=\"1024\"", "width=\"512\" height=\"512\"");
    char *d = replace_all(c, "dirt=\"2000\"", dusty_sills ? "dirt=\"2000\"" : "dirt=\"0\"");
    const char *name = dusty_sills ? "dusty" : "clean";
    char dir[4300], log[4096];
    snprintf(dir, sizeof dir, "%s/building_%s", ensure_tmpdir(), name);
    int status = ensure_shell(log, sizeof log,
                              "mkdir -p '%s/meshes' && cp '%s/../xml_scenes/meshes/building.obj' "
                              "'%s/../xml_scenes/meshes/building.mtl' '%s/meshes/'",
                              dir, ensure_tests_dir(), ensure_tests_dir(), dir);
    ensure_write_file(dir, "building.xml", d);
    free(xml);
    free(a);
    free(b);
    free(c);
    free(d);
    if (status == 0) {
        status =
            ensure_shell(log, sizeof log, "'%s/weathering' run '%s/building.xml' --out '%s/out' -q",
                         ensure_build_dir(), dir, dir);
    }
    if (status != 0) {
        fprintf(stderr, "        building (%s): status %d\n%s\n", name, status, log);
        return false;
    }
    snprintf(path, sizeof path, "%s/out/mask.exr", dir);
    static const char *const y[1] = { "Y" };
    wx_image *mask = calloc(1, sizeof *mask);
    wx_error err;
    if (mask == NULL || wx_exr_read(path, y, 1, mask, &err) != WX_OK) {
        free(mask);
        return false;
    }
    *band =
        (facade_mean(mask, -2.5, -0.9, 10.5, 11.6) + facade_mean(mask, 0.9, 2.5, 10.5, 11.6)) / 2;
    *exposed =
        (facade_mean(mask, -2.5, -0.9, 4.5, 8.5) + facade_mean(mask, 0.9, 2.5, 4.5, 8.5)) / 2;
    *below = 0.0;
    for (int floor = 1; floor < 4; ++floor) {
        double sill = 3.0 * floor + 0.9; // top of the sill at the wall
        for (int side = -1; side <= 1; side += 2) {
            double cx = side * 10.0 / 3.0; // centre of the side window bays
            *below += facade_mean(mask, cx - 0.6, cx + 0.6, sill - 1.0, sill - 0.3) / 6.0;
        }
    }
    wx_image_free(mask);
    free(mask);
    return true;
}

// The default scene shows what README promises: a clean band under the roof's
// overhang (the wind slants the rain: the band is about 0.7 x 9.8 / 2 = 3.4 m
// deep) and streaks under the sills that are the sills' dust washed down (they
// vanish when the sills start clean).
TEST(default_scene_has_a_clean_band_and_streaks_below_the_sills)
{
    SLOW();
    double band, exposed, below, band0, exposed0, below0;
    ENSURE(building_regions(true, &band, &exposed, &below));
    ENSURE(building_regions(false, &band0, &exposed0, &below0));
    fprintf(stderr, "        band %.3g, exposed wall %.3g, below sills %.3g (clean sills: %.3g)\n",
            band, exposed, below, below0);
    ENSURE(exposed > 0.0);
    ENSURE(band < 0.05 * exposed);
    ENSURE(below > 0.3 * exposed);
    ENSURE(below > 5.0 * below0);
}

// A run in which no particle reaches the geometry ends with exit 0, an all-zero
// mask and a warning that says so (issue 13).
TEST(a_run_without_a_single_hit_warns)
{
    // The drops start 2 m above the top of a solver box of 10 m around the
    // origin: every one of the 1000 leaves it at once.
    char *far = replace_once(SCENE_XML, "centerY=\"3\"", "centerY=\"7\"");
    char *xml = far != NULL ? replace_once(far, "<Solver>", "<Solver><BoundingBox size=\"10\"/>")
                            : NULL;
    free(far);
    ENSURE(xml != NULL);
    const char *path = ensure_write_file(scene_dir(), "far.xml", xml);
    free(xml);
    const char *dir = out_dir("no_hit");
    char log[8192];
    int status = ensure_shell(log, sizeof log, "'%s/weathering' run '%s' --out '%s'",
                              ensure_build_dir(), path, dir);
    ENSURE(status == 0);
    ENSURE(ensure_contains(log, "weathering: warning: "));
    ENSURE(ensure_contains(log, "no particle hit a surface (1000 emitted, 1000 escaped"));
    // -q keeps it quiet.
    status = ensure_shell(log, sizeof log, "'%s/weathering' run '%s' --out '%s' -q",
                          ensure_build_dir(), path, dir);
    ENSURE(status == 0 && log[0] == '\0');
}

// Every input is read once per run: the simulation's maps are the gather's. A
// map replaced while the run flies its particles changes nothing (issue 13).
TEST(inputs_are_read_once_per_run)
{
    SLOW();
    const char *dir = out_dir("read_once");
    char log[8192];
    // The thesis box (given maps) with a longer simulation, and its maps copied.
    int status = ensure_shell(
        log, sizeof log,
        "set -e; mkdir -p '%s/maps'; cp maps/thesis_box_* '%s/maps/'; "
        "sed -e 's|../maps/|maps/|g' -e 's|<BoundingBox|<Simulation steps=\"4000\"/><BoundingBox|' "
        "-e 's|end=\"2\"|end=\"40\"|' xml_scenes/thesis_box.xml > '%s/scene.xml'",
        dir, dir, dir);
    ENSURE(status == 0);
    status = ensure_shell(log, sizeof log, "'%s/weathering' run '%s/scene.xml' --out '%s/a' -q",
                          ensure_build_dir(), dir, dir);
    ENSURE(status == 0);
    // Again, replacing the front camera's depth map with the top camera's while
    // the particles fly: the mask must not change.
    status = ensure_shell(
        log, sizeof log,
        "'%s/weathering' run '%s/scene.xml' --out '%s/b' -q & pid=$!; "
        "while [ ! -e '%s/b' ]; do sleep 0.01; done; sleep 0.3; "
        "cp '%s/maps/thesis_box_top_depth.exr' '%s/maps/thesis_box_front_depth.exr'; "
        "cp '%s/maps/thesis_box_top_normal.exr' '%s/maps/thesis_box_front_normal.exr'; "
        "wait $pid",
        ensure_build_dir(), dir, dir, dir, dir, dir, dir, dir);
    ENSURE(status == 0);
    char a[4300], b[4300];
    snprintf(a, sizeof a, "%s/a", dir);
    snprintf(b, sizeof b, "%s/b", dir);
    ENSURE(same_bytes(a, b, "thesis_box_mask.exr"));
}

// A phase that fails leaves no folder it made, and a scene whose output would
// replace one of its inputs is refused before anything is written (issue 13).
TEST(failures_leave_nothing_behind)
{
    const char *dir = out_dir("failed");
    mkdir(dir, 0777);
    char log[8192];
    // A mesh that is not a mesh: the geometry is refused before the folder exists.
    const char *bad = ensure_write_file(dir, "bad.xml", SCENE_XML);
    ENSURE(ensure_shell(log, sizeof log, "cp '%s/data/bake_not_a_mesh.txt' '%s/box.obj'",
                        ensure_tests_dir(), dir) == 0);
    int status = ensure_shell(log, sizeof log, "'%s/weathering' run '%s' --out '%s/new/deeper'",
                              ensure_build_dir(), bad, dir);
    ENSURE(status == 2);
    char path[4300];
    snprintf(path, sizeof path, "%s/new", dir);
    struct stat st;
    ENSURE(stat(path, &st) != 0);
    // simulate without a bake: the missing maps are refused, no folder made.
    status = ensure_shell(log, sizeof log, "'%s/weathering' simulate '%s' --out '%s/new'",
                          ensure_build_dir(), bad, dir);
    ENSURE(status == 2);
    ENSURE(ensure_contains(log, "run `weathering bake"));
    ENSURE(stat(path, &st) != 0);
    // The thesis box run into the folder of its own maps: front_dirt.exr would
    // replace an input. Refused at once: the 22 files of bake and simulate are
    // never written (the check used to come after the simulation).
    status = ensure_shell(
        log, sizeof log,
        "set -e; mkdir -p '%s/inputs'; cd '%s/inputs'; m=$OLDPWD/maps/thesis_box_; "
        "for c in front top; do for k in depth normal impact dirt; do "
        "cp $m${c}_$k.exr ${c}_$k.exr; done; done; "
        "cp ${m}out_depth.exr out_depth.exr; cp ${m}out_normal.exr out_normal.exr; "
        "sed -e 's|../maps/thesis_box_||g' "
        "-e 's|<BoundingBox|<Simulation steps=\"100000\"/><BoundingBox|' "
        "$OLDPWD/xml_scenes/thesis_box.xml > scene.xml",
        dir, dir);
    ENSURE(status == 0);
    double t0 = (double)time(NULL);
    status =
        ensure_shell(log, sizeof log, "'%s/weathering' run '%s/inputs/scene.xml' --out '%s/inputs'",
                     ensure_build_dir(), dir, dir);
    ENSURE(status == 2);
    ENSURE(ensure_contains(log, "front_dirt.exr: is an input of scene"));
    ENSURE((double)time(NULL) - t0 < 5.0); // 100000 steps were never flown
}

int main(void)
{
    RUN(run_equals_bake_simulate_gather);
    RUN(a_layered_run_with_masks_equals_its_phases);
    RUN(simulating_again_starts_from_the_initial_dirt);
    RUN(simulated_dirt_map_holds_result_and_initial_dirt);
    RUN(default_scene_has_a_clean_band_and_streaks_below_the_sills);
    RUN(a_run_without_a_single_hit_warns);
    RUN(inputs_are_read_once_per_run);
    RUN(failures_leave_nothing_behind);
    return ensure_summary();
}
