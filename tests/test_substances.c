// test_substances.c: several substances over several iterations (docs/design.md
// sections 9 and 10), checked against numbers worked out by hand.
//
// A 2 m x 2 m plane under uniform vertical rain that carries only water, every
// particle absorbed on its first hit (so one iteration deposits exactly what the
// box emits over the plane, up to Poisson noise), with the rules
//   Transfer water -> rust 0.5, Decay water 0.5, Grow moss 2 per square metre
// over 3 iterations. After iteration k, with W the water one iteration deposits
// per square metre: water_k = 0.5 * 0.5 * (water_{k-1} + W) and rust_k =
// rust_{k-1} + 0.5 * (water_{k-1} + W), so water / W = 0.25, 0.3125, 0.328125
// and rust / W = 0.5, 1.125, 1.78125; moss = 2k exactly. The plane's right half
// is "stone", whose own rule Decay rust 1 removes all rust after each iteration.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <dirent.h>
#include <sys/stat.h>

#include "core/limits.h"
#include "ensure.h"
#include "io/exr.h"
#include "model/image.h"

enum { OUT_PX = 64, ITERATIONS = 3 };
#define FRAME_M 2.4
#define RATE 400000.0
#define EMIT_SECONDS 0.5
#define BOX_SIDE 3.0

static const char PLANE_OBJ[] =
    "# y = 0, x in [-1, 0] iron, x in [0, 1] stone, facing +y\n"
    "mtllib plane.mtl\n"
    "v -1 0 -1\nv 0 0 -1\nv 0 0 1\nv -1 0 1\nv 1 0 -1\nv 1 0 1\n"
    "vn 0 1 0\n"
    "usemtl iron\nf 1//1 4//1 3//1 2//1\n"
    "usemtl stone\nf 2//1 3//1 6//1 5//1\n";

static const char PLANE_MTL[] = "newmtl iron\nKd 0.5 0.5 0.5\nnewmtl stone\nKd 0.7 0.7 0.7\n";

static const char SCENE_XML[] =
    "<Weathering>\n"
    "  <Substances>\n"
    "    <Substance name=\"water\"/>\n"
    "    <Substance name=\"rust\"/>\n"
    "    <Substance name=\"moss\"/>\n"
    "  </Substances>\n"
    "  <Solver>\n"
    "    <Simulation timeStep=\"0.01\" steps=\"100\" seed=\"5\" iterations=\"3\"/>\n"
    "    <BoundingBox size=\"8\"/>\n"
    "  </Solver>\n"
    "  <Emitters>\n"
    "    <BoxEmitter name=\"rain\" minX=\"-1.5\" minY=\"1\" minZ=\"-1.5\" maxX=\"1.5\" maxY=\"1\"\n"
    "                maxZ=\"1.5\" rate=\"400000\" end=\"0.5\" speed=\"10\">\n"
    "      <Load substance=\"water\" amount=\"1\"/>\n"
    "    </BoxEmitter>\n"
    "  </Emitters>\n"
    "  <Ageing>\n"
    "    <Transfer from=\"water\" to=\"rust\" rate=\"0.5\"/>\n"
    "    <Decay substance=\"water\" rate=\"0.5\"/>\n"
    "    <Grow substance=\"moss\" amount=\"2\"/>\n"
    "  </Ageing>\n"
    "  <Collider>\n"
    "    <ProjectedMaps>\n"
    "      <Ortho cameraName=\"top\">\n"
    "        <View eye=\"0 3 0\" target=\"0 0 0\" up=\"0 0 -1\" width=\"2.4\" height=\"2.4\" "
    "resolution=\"128\"/>\n"
    "      </Ortho>\n"
    "      <Ortho cameraName=\"side\">\n"
    "        <View eye=\"0 3 3\" target=\"0 0 0\" up=\"0 1 0\" width=\"3\" height=\"3\" "
    "resolution=\"96\"/>\n"
    "      </Ortho>\n"
    "      <Ortho cameraName=\"shot\" out=\"true\">\n"
    "        <View eye=\"0 3 0\" target=\"0 0 0\" up=\"0 0 -1\" width=\"2.4\" height=\"2.4\" "
    "resolution=\"64\"/>\n"
    "        <OutputMap file=\"mask.exr\" width=\"64\" height=\"64\" every=\"1\"/>\n"
    "      </Ortho>\n"
    "    </ProjectedMaps>\n"
    "  </Collider>\n"
    "  <Geometry>\n"
    "    <Mesh file=\"plane.obj\">\n"
    "      <Surface material=\"iron\" absorption=\"1\">\n"
    "        <Exchange substance=\"water\" deposit=\"1\"/>\n"
    "      </Surface>\n"
    "      <Surface material=\"stone\" absorption=\"1\">\n"
    "        <Exchange substance=\"water\" deposit=\"1\"/>\n"
    "        <Decay substance=\"rust\" rate=\"1\"/>\n"
    "      </Surface>\n"
    "    </Mesh>\n"
    "  </Geometry>\n"
    "</Weathering>\n";

static const char *run_dir(void)
{
    static char out[4300];
    if (out[0] != '\0') {
        return out;
    }
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/substances", ensure_tmpdir());
    mkdir(dir, 0777);
    ensure_write_file(dir, "plane.obj", PLANE_OBJ);
    ensure_write_file(dir, "plane.mtl", PLANE_MTL);
    ensure_write_file(dir, "scene.xml", SCENE_XML);
    snprintf(out, sizeof out, "%s/out", dir);
    char log[8192];
    int status = ensure_shell(log, sizeof log,
                              "'%s/weathering' run '%s/scene.xml' --out '%s' -q --stats "
                              "'%s/stats.json'",
                              ensure_build_dir(), dir, out, dir);
    if (status != 0) {
        fprintf(stderr, "        weathering run: status %d\n%s\n", status, log);
    }
    return out;
}

// Mean of a channel over the output texels whose centre lies on the plane's
// half x < 0 (side -1) or x > 0 (side 1), 0.1 m away from its edges.
static double half_mean(const wx_image *img, int channel, int side)
{
    double sum = 0.0;
    int n = 0;
    for (int j = 0; j < img->height; ++j) {
        for (int i = 0; i < img->width; ++i) {
            double x = ((i + 0.5) / img->width - 0.5) * FRAME_M;
            double z = ((j + 0.5) / img->height - 0.5) * FRAME_M;
            if (fabs(z) > 0.9 || x * side < 0.1 || x * side > 0.9) {
                continue;
            }
            sum += img->channels[channel][(size_t)j * (size_t)img->width + (size_t)i];
            n++;
        }
    }
    return n > 0 ? sum / n : NAN;
}

static bool read_mask(const char *name, wx_image *img)
{
    char path[4400];
    snprintf(path, sizeof path, "%s/%s", run_dir(), name);
    static const char *const channels[3] = { "water.Y", "rust.Y", "moss.Y" };
    wx_error err;
    if (wx_exr_read(path, channels, 3, img, &err) != WX_OK) {
        fprintf(stderr, "        %s\n", err.message);
        return false;
    }
    return true;
}

// Water per square metre one iteration deposits: the box's particles that
// start over the plane (area 4 of the box's 9 square metres).
static double one_iteration(void)
{
    return RATE * EMIT_SECONDS / (BOX_SIDE * BOX_SIDE);
}

TEST(water_and_rust_follow_the_recurrence_in_every_frame)
{
    const double water[ITERATIONS] = { 0.25, 0.3125, 0.328125 };
    const double rust[ITERATIONS] = { 0.5, 1.125, 1.78125 };
    double W = one_iteration();
    for (int k = 0; k < ITERATIONS; ++k) {
        char name[64];
        snprintf(name, sizeof name, "mask.%04d.exr", k + 1);
        wx_image *img = calloc(1, sizeof *img);
        ENSURE(read_mask(name, img));
        ENSURE(img->width == OUT_PX && img->height == OUT_PX);
        double w_iron = half_mean(img, 0, -1) / W, w_stone = half_mean(img, 0, 1) / W;
        double r_iron = half_mean(img, 1, -1) / W, r_stone = half_mean(img, 1, 1) / W;
        printf("        iteration %d: water %.5f / %.5f (exact %.6f), rust %.5f (exact %.5f), "
               "stone rust %.3g\n",
               k + 1, w_iron, w_stone, water[k], r_iron, rust[k], r_stone);
        ENSURE_NEAR(w_iron, water[k], 0.02 * water[k]);
        ENSURE_NEAR(w_stone, water[k], 0.02 * water[k]);
        ENSURE_NEAR(r_iron, rust[k], 0.02 * rust[k]);
        // Stone has its own rule: every bit of rust decays after each iteration.
        ENSURE(fabs(r_stone) < 1e-6 * W);
        wx_image_free(img);
        free(img);
    }
}

TEST(grow_gives_exactly_two_per_square_metre_per_iteration)
{
    for (int k = 1; k <= ITERATIONS + 1; ++k) {
        char name[64];
        if (k <= ITERATIONS) {
            snprintf(name, sizeof name, "mask.%04d.exr", k);
        } else {
            snprintf(name, sizeof name, "mask.exr");
        }
        wx_image *img = calloc(1, sizeof *img);
        ENSURE(read_mask(name, img));
        double expect = 2.0 * (k <= ITERATIONS ? k : ITERATIONS);
        int seen = 0, off = 0;
        for (int t = 0; t < img->width * img->height; ++t) {
            float moss = img->channels[2][t];
            if (moss != 0.0f) {
                if (fabs(moss - expect) > 1e-4 * expect && off++ < 10) {
                    printf("        texel (%d, %d): %g\n", t % img->width, t / img->width, moss);
                }
                seen++;
            }
        }
        printf("        %d of %d texels off\n", off, seen);
        ENSURE(off == 0);
        // The plane fills (2 / 2.4)^2 of the frame.
        ENSURE(seen > 0.6 * OUT_PX * OUT_PX && seen < 0.75 * OUT_PX * OUT_PX);
        wx_image_free(img);
        free(img);
    }
}

TEST(the_final_mask_is_the_last_frame_and_every_channel_has_a_preview)
{
    char log[4096];
    const char *out = run_dir();
    ENSURE(ensure_shell(log, sizeof log, "cmp -s '%s/mask.exr' '%s/mask.%04d.exr'", out, out,
                        ITERATIONS) == 0);
    const char *previews[] = { "mask_water.png", "mask_rust.png", "mask_moss.png" };
    for (int k = 0; k < 3; ++k) {
        char path[4400];
        snprintf(path, sizeof path, "%s/%s", out, previews[k]);
        struct stat st;
        ENSURE(stat(path, &st) == 0 && st.st_size > 0);
    }
    char path[4400];
    snprintf(path, sizeof path, "%s/mask.png", out);
    struct stat st;
    ENSURE(stat(path, &st) != 0); // a multi-channel mask has no single preview
    snprintf(path, sizeof path, "%s/mask.0001.png", out);
    ENSURE(stat(path, &st) != 0); // frames have none
}

TEST(the_ledger_balances_for_every_substance)
{
    run_dir();
    char path[4200];
    snprintf(path, sizeof path, "%s/substances/stats.json", ensure_tmpdir());
    char *json = ensure_read_file(path);
    ENSURE(json != NULL);
    ENSURE(ensure_json_number(json, NULL, "iterations") == ITERATIONS);
    ENSURE(strstr(json, "\"dirt\": {") == NULL); // the scene declares no substance dirt
    const char *names[3] = { "water", "rust", "moss" };
    for (int s = 0; s < 3; ++s) {
        char key[32];
        snprintf(key, sizeof key, "\"%s\": {", names[s]);
        const char *at = strstr(json, key);
        ENSURE(at != NULL);
        double in, out;
        ensure_ledger_sides(at, &in, &out);
        printf("        %s: in %.17g, out %.17g\n", names[s], in, out);
        ENSURE(fabs(in - out) <= 1e-9 * (fabs(in) + 1.0));
    }
    // Rust comes only from water: what water gave, rust received.
    const char *water = strstr(json, "\"water\": {"), *rust = strstr(json, "\"rust\": {");
    double given = ensure_json_number(water, NULL, "transferred_out");
    double received = ensure_json_number(rust, NULL, "transferred_in");
    ENSURE_NEAR(given, received, 1e-9 * received);
    free(json);
}

TEST(several_substances_give_the_same_bytes_for_any_thread_count)
{
    const char *out = run_dir();
    char dir[4200], log[8192];
    snprintf(dir, sizeof dir, "%s/substances", ensure_tmpdir());
    ENSURE(ensure_shell(log, sizeof log,
                        "'%s/weathering' run '%s/scene.xml' --out '%s/one' -q --threads 1",
                        ensure_build_dir(), dir, dir) == 0);
    const char *files[] = { "mask.exr", "mask.0001.exr", "mask.0002.exr", "top_dirt.exr",
                            "side_dirt.exr" };
    for (size_t k = 0; k < sizeof files / sizeof files[0]; ++k) {
        ENSURE(ensure_shell(log, sizeof log, "cmp -s '%s/%s' '%s/one/%s'", out, files[k], dir,
                            files[k]) == 0);
    }
}

// A scene of over a thousand <Surface>s (a city's materials): the bake and the
// ageing look each texel's surface up by its global index with no cap. The
// plane's two materials are the last two of 1100 surfaces (the others match
// no material); iron grows 2 and stone 5 of moss per square metre per
// iteration and stone starts with 3 of water per square metre, so after three
// iterations, with no particle, moss is exactly 6 and 15 and water 0 and 3.
TEST(surfaces_beyond_a_thousand_keep_their_rules)
{
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/many_surfaces", ensure_tmpdir());
    mkdir(dir, 0777);
    ensure_write_file(dir, "plane.obj", PLANE_OBJ);
    ensure_write_file(dir, "plane.mtl", PLANE_MTL);
    enum { SURFACES = 1100 };
    size_t cap = 200000, n = 0;
    char *xml = malloc(cap);
    ENSURE(xml != NULL);
    if (xml == NULL) {
        return;
    }
    n += (size_t)snprintf(xml + n, cap - n,
                          "<Weathering>\n"
                          "  <Substances><Substance name=\"water\"/><Substance name=\"moss\"/>"
                          "</Substances>\n"
                          "  <Solver><Simulation timeStep=\"0.01\" steps=\"10\" iterations=\"3\"/>"
                          "<BoundingBox size=\"8\"/></Solver>\n"
                          "  <Collider><ProjectedMaps>\n"
                          "    <Ortho cameraName=\"top\"><View eye=\"0 3 0\" target=\"0 0 0\" "
                          "up=\"0 0 -1\" width=\"2.4\" height=\"2.4\" resolution=\"64\"/></Ortho>\n"
                          "    <Ortho cameraName=\"shot\" out=\"true\"><View eye=\"0 3 0\" "
                          "target=\"0 0 0\" up=\"0 0 -1\" width=\"2.4\" height=\"2.4\" "
                          "resolution=\"64\"/><OutputMap file=\"mask.exr\" radius=\"0\"/></Ortho>\n"
                          "  </ProjectedMaps></Collider>\n"
                          "  <Geometry><Mesh file=\"plane.obj\">\n");
    for (int k = 0; k < SURFACES - 2; ++k) {
        n += (size_t)snprintf(xml + n, cap - n, "    <Surface material=\"unused%d\"/>\n", k);
    }
    n += (size_t)snprintf(xml + n, cap - n,
                          "    <Surface material=\"iron\"><Grow substance=\"moss\" amount=\"2\"/>"
                          "</Surface>\n"
                          "    <Surface material=\"stone\"><Exchange substance=\"water\" "
                          "initial=\"3\"/><Grow substance=\"moss\" amount=\"5\"/></Surface>\n"
                          "  </Mesh></Geometry>\n"
                          "</Weathering>\n");
    ensure_write_file(dir, "scene.xml", xml);
    free(xml);
    char log[8192];
    int status = ensure_shell(log, sizeof log,
                              "'%s/weathering' run '%s/scene.xml' --out '%s/out' -q",
                              ensure_build_dir(), dir, dir);
    if (status != 0) {
        fprintf(stderr, "        weathering run: status %d\n%s\n", status, log);
    }
    ENSURE(status == 0);
    char path[4400];
    snprintf(path, sizeof path, "%s/out/mask.exr", dir);
    static const char *const channels[2] = { "water.Y", "moss.Y" };
    wx_image *img = calloc(1, sizeof *img);
    wx_error err;
    ENSURE(img != NULL && wx_exr_read(path, channels, 2, img, &err) == WX_OK);
    if (img != NULL && img->channels[0] != NULL) {
        double iron_water = half_mean(img, 0, -1), stone_water = half_mean(img, 0, 1);
        double iron_moss = half_mean(img, 1, -1), stone_moss = half_mean(img, 1, 1);
        printf("        iron: water %g, moss %g; stone: water %g, moss %g\n", iron_water,
               iron_moss, stone_water, stone_moss);
        ENSURE_NEAR(iron_water, 0.0, 1e-6);
        ENSURE_NEAR(stone_water, 3.0, 1e-4);
        ENSURE_NEAR(iron_moss, 6.0, 1e-4);
        ENSURE_NEAR(stone_moss, 15.0, 1e-4);
        wx_image_free(img);
    }
    free(img);
}

// Replaces every `from` in `text` by `to` (malloc'd; NULL when out of memory).
static char *replace_all(const char *text, const char *from, const char *to)
{
    size_t nf = strlen(from), nt = strlen(to), count = 0;
    for (const char *p = strstr(text, from); p != NULL; p = strstr(p + nf, from)) {
        count++;
    }
    char *out = malloc(strlen(text) + count * (nt > nf ? nt - nf : 0) + 1);
    if (out == NULL) {
        return NULL;
    }
    char *o = out;
    for (const char *p = text;;) {
        const char *hit = strstr(p, from);
        size_t keep = hit != NULL ? (size_t)(hit - p) : strlen(p);
        memcpy(o, p, keep);
        o += keep;
        if (hit == NULL) {
            break;
        }
        memcpy(o, to, nt);
        o += nt;
        p = hit + nf;
    }
    *o = '\0';
    return out;
}

TEST(names_of_32_characters_run_to_the_end)
{
    // Issue 24: a substance name of 24+ characters or a mask name of 30+ made
    // channel names over 31 characters, and the EXR writer hung for ever. The
    // scene above with water renamed to a 32-character name and a Height mask
    // of a 32-character name: the run finishes (timeout-guarded) and the renamed
    // channel holds exactly what water.Y holds.
    static const char LONG_SUBSTANCE[] = "water_water_water_water_water_32";
    static const char LONG_MASK[] = "height_height_height_height_he32";
    _Static_assert(sizeof LONG_SUBSTANCE - 1 == WX_SUBSTANCE_NAME_MAX, "32 characters");
    _Static_assert(sizeof LONG_MASK - 1 == WX_SUBSTANCE_NAME_MAX, "32 characters");
    char *renamed = replace_all(SCENE_XML, "\"water\"", "\"water_water_water_water_water_32\"");
    char *xml = renamed != NULL ? replace_all(renamed, "  <Geometry>\n",
                                              "  <Masks><Height name=\"height_height_height_"
                                              "height_he32\"/></Masks>\n  <Geometry>\n")
                                : NULL;
    free(renamed);
    ENSURE(xml != NULL);
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/long_names", ensure_tmpdir());
    mkdir(dir, 0777);
    ensure_write_file(dir, "plane.obj", PLANE_OBJ);
    ensure_write_file(dir, "plane.mtl", PLANE_MTL);
    ensure_write_file(dir, "scene.xml", xml);
    free(xml);
    char log[8192];
    int status = ensure_shell(log, sizeof log,
                              "timeout 120 '%s/weathering' run '%s/scene.xml' --out '%s/out' -q",
                              ensure_build_dir(), dir, dir);
    if (status != 0) {
        fprintf(stderr, "        weathering run: status %d (124: it hung)\n%s\n", status, log);
    }
    ENSURE(status == 0);

    char path[4400], base_path[4400];
    const char *channels[2] = { "water_water_water_water_water_32.Y",
                                "height_height_height_height_he32.Y" };
    static const char *const water[1] = { "water.Y" };
    bool same = true;
    for (int k = 1; k <= ITERATIONS + 1 && same; ++k) {
        char name[64];
        if (k <= ITERATIONS) {
            snprintf(name, sizeof name, "mask.%04d.exr", k);
        } else {
            snprintf(name, sizeof name, "mask.exr");
        }
        snprintf(path, sizeof path, "%s/out/%s", dir, name);
        snprintf(base_path, sizeof base_path, "%s/%s", run_dir(), name);
        wx_image *img = calloc(1, sizeof *img), *base = calloc(1, sizeof *base);
        wx_error err;
        same = img != NULL && base != NULL &&
               wx_exr_read(path, channels, 2, img, &err) == WX_OK &&
               wx_exr_read(base_path, water, 1, base, &err) == WX_OK &&
               memcmp(img->channels[0], base->channels[0],
                      sizeof(float) * (size_t)(OUT_PX * OUT_PX)) == 0;
        if (!same) {
            fprintf(stderr, "        %s differs from the run with water (or is unreadable)\n",
                    name);
        }
        wx_image_free(img);
        wx_image_free(base);
        free(img);
        free(base);
    }
    ENSURE(same);
    // The dirt maps hold the long substance channels; previews are named after them.
    snprintf(path, sizeof path, "%s/out/top_dirt.exr", dir);
    int w = 0, h = 0;
    float *deposit = ensure_read_channel(path, "water_water_water_water_water_32.deposit", &w,
                                         &h);
    ENSURE(deposit != NULL);
    free(deposit);
    snprintf(path, sizeof path, "%s/out/mask_%s.png", dir, LONG_MASK);
    struct stat st;
    ENSURE(stat(path, &st) == 0 && st.st_size > 0);
    snprintf(path, sizeof path, "%s/out/mask_%s.png", dir, LONG_SUBSTANCE);
    ENSURE(stat(path, &st) == 0 && st.st_size > 0);
}

int main(void)
{
    RUN(water_and_rust_follow_the_recurrence_in_every_frame);
    RUN(grow_gives_exactly_two_per_square_metre_per_iteration);
    RUN(the_final_mask_is_the_last_frame_and_every_channel_has_a_preview);
    RUN(the_ledger_balances_for_every_substance);
    RUN(several_substances_give_the_same_bytes_for_any_thread_count);
    RUN(surfaces_beyond_a_thousand_keep_their_rules);
    RUN(names_of_32_characters_run_to_the_end);
    return ensure_summary();
}
