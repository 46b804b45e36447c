// test_run.c: the whole pipeline through the command line. `run` equals `bake`,
// `simulate` and `gather` run one after the other; running a phase again into the
// same folder gives the same bytes (a simulated dirt map keeps the dirt it started
// from); every shipped scene validates.
#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "ensure.h"
#include "exr_io.h"
#include "maps.h"

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
    }
    return dir;
}

// Runs `weathering ARGS` on the test scene with --out DIR; returns the exit status.
static int weathering(const char *command, const char *out_dir)
{
    char log[4096];
    int status = ensure_shell(log, sizeof log, "'%s/weathering' %s '%s/scene.xml' --out '%s' -q",
                              ensure_build_dir(), command, scene_dir(), out_dir);
    if (status != 0) {
        fprintf(stderr, "        weathering %s: status %d\n%s\n", command, status, log);
    }
    return status;
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

TEST(every_shipped_scene_validates)
{
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
        char log[4096];
        int status = ensure_shell(log, sizeof log, "'%s/weathering' info '%s/%s'",
                                  ensure_build_dir(), dir, e->d_name);
        if (status != 0) {
            fprintf(stderr, "        %s: status %d\n%s\n", e->d_name, status, log);
            failures++;
        }
        scenes++;
    }
    closedir(d);
    ENSURE(failures == 0);
    ENSURE(scenes >= 2);
}

int main(void)
{
    RUN(run_equals_bake_simulate_gather);
    RUN(simulating_again_starts_from_the_initial_dirt);
    RUN(simulated_dirt_map_holds_result_and_initial_dirt);
    RUN(every_shipped_scene_validates);
    return ensure_summary();
}
