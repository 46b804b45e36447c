// test_viewer.c: weathering-viewer.
//
// The program under a virtual display (xvfb-run -a): a screenshot of the
// thesis scene after 30 frames must be the window's size, show both input
// cameras in their colours and the particles, and come out the same on every
// run; bad input gives exit status 2 and names the file, without any display.
//
// The viewer's GL-free parts (linked from its library) are checked against
// numbers worked out by hand: the geometry drawn for the thesis scene, when
// maps must be baked again, the nearest-point-per-pixel filter and the
// initial view.
// With several substances (the thesis scene with <Substances> water, dirt,
// rust): S walks through them and wraps, particles are coloured by their load
// of the shown one (scaled by its emitter load), depth samples by its amount
// on their texel, and a screenshot shows particles in the shown substance's
// colour. With <Masks> (the thesis scene with Height, Curvature,
// Accessibility and Combine masks): M's cycle, each mask's value at every
// sample (Height by its formula; at the samples of the input cameras, the
// values wx_masks_at_camera gives on their maps; at a stride of 3 too), the
// ramps' colours and Curvature's scale, and a screenshot with --mask showing
// the bright end of the ramp above its dark end; a bad --mask exits 2. With
// a layered camera (maps written by hand, as a peeling bake writes them):
// every layer's depth samples, each naming its view of the simulation, deeper
// layers darker, L's cycle, hits' views, masks per layer, and G and a reload
// keeping every layer; with one layer per camera, nothing changes. G gathers
// from the simulation in memory: every file it saves is the bytes of the dirt
// maps written and gathered from files (wx_gather_scene), layered or not.
#include <dirent.h>
#include <fcntl.h>
#include <math.h>
#include <png.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "../viewer/palette.h"
#include "../viewer/points.h"
#include "../viewer/view.h"
#include "../viewer/world.h"
#include "ensure.h"
#include "io/exr.h"
#include "model/camera.h"
#include "pipeline/gather_phase.h"
#include "pipeline/outputs.h"
#include "pipeline/simulate_phase.h"
#include "sim/simulate.h"

enum { WIDTH = 1024, HEIGHT = 640 }; // the viewer's default window size

static char out[65536];

static bool have_xvfb(void)
{
    if (ensure_shell(NULL, 0, "command -v xvfb-run >/dev/null && command -v xauth >/dev/null") ==
        0) {
        return true;
    }
    fprintf(stderr, "xvfb-run or xauth is missing: install the Debian packages xvfb and xauth "
                    "(make deps does)\n");
    return false;
}

// Runs the viewer on a scene (the thesis scene when NULL) for `frames` frames
// and saves `png`; `extra` adds options.
static int screenshot_of(const char *scene, const char *png, int frames, const char *extra)
{
    const char *tmp = ensure_tmpdir();
    return ensure_shell(out, sizeof out,
                        "xvfb-run -a %s/weathering-viewer %s --out %s/out "
                        "--screenshot %s/%s --frames %d %s",
                        ensure_build_dir(), scene != NULL ? scene : "xml_scenes/thesis_box.xml",
                        tmp, tmp, png, frames, extra);
}

static int screenshot(const char *png, int frames)
{
    return screenshot_of(NULL, png, frames, "");
}

// The thesis scene written into the temporary folder as `file`, with the
// maps' absolute paths, `before_solver` inserted before its <Solver> and,
// with `water`, its emitter carrying 2 of water and 0.25 of dirt (instead of
// 1 of dirt). NULL when thesis_box.xml changed so that the edits miss.
static const char *thesis_variant(const char *file, const char *before_solver, bool water)
{
    char *text = ensure_read_file("xml_scenes/thesis_box.xml");
    char maps[4200], *cwd = getcwd(NULL, 0);
    snprintf(maps, sizeof maps, "%s/maps/", cwd);
    free(cwd);
    static char scene[65536];
    size_t n = 0;
    bool solver = false, emitter = !water;
    for (const char *p = text; *p != '\0' && n + 4300 < sizeof scene;) {
        if (strncmp(p, "../maps/", 8) == 0) {
            n += (size_t)snprintf(scene + n, sizeof scene - n, "%s", maps);
            p += 8;
        } else if (strncmp(p, "<Solver>", 8) == 0) {
            n += (size_t)snprintf(scene + n, sizeof scene - n, "%s\n  <Solver>", before_solver);
            p += 8;
            solver = true;
        } else if (water && strncmp(p, "dirt=\"1\" maxCollisions=\"50\"/>", 29) == 0) {
            n += (size_t)snprintf(scene + n, sizeof scene - n,
                                  "dirt=\"0.25\" maxCollisions=\"50\">"
                                  "<Load substance=\"water\" amount=\"2\"/></PointEmitter>");
            p += 29;
            emitter = true;
        } else {
            scene[n++] = *p++;
        }
    }
    scene[n] = '\0';
    free(text);
    if (!solver || !emitter || strstr(scene, "../maps/") != NULL) {
        return NULL; // thesis_box.xml changed: the test must follow
    }
    return ensure_write_file(ensure_tmpdir(), file, scene);
}

// The thesis scene with three substances: its emitter carries 2 of water and
// 0.25 of dirt, none of rust (the thesis' maps are substance dirt's). Written
// once into the temporary folder, with the maps' absolute paths.
static const char *substance_scene(void)
{
    static const char *path;
    if (path == NULL) {
        path = thesis_variant("substances.xml",
                              "<Substances><Substance name=\"water\"/>"
                              "<Substance name=\"dirt\"/><Substance name=\"rust\"/>"
                              "</Substances>",
                              true);
    }
    return path;
}

// The thesis scene (a 2 m cube, y 0 to 2, on a slab, y -0.2 to 0) with
// derived masks: `step` is 0 below y = 1 and 1 above y = 1.0001 (the cube's
// top and upper half bright, its lower half and the slab dark), `height` y / 2;
// `both` combines height and ao.
static const char *mask_scene(void)
{
    static const char *path;
    if (path == NULL) {
        path = thesis_variant("masks.xml",
                              "<Masks>\n"
                              "    <Height name=\"step\" min=\"1\" max=\"1.0001\"/>\n"
                              "    <Height name=\"height\" min=\"0\" max=\"2\"/>\n"
                              "    <Curvature name=\"curv\"/>\n"
                              "    <Accessibility name=\"ao\" rays=\"4\" distance=\"1\"/>\n"
                              "    <Combine name=\"both\">\n"
                              "      <Term mask=\"height\" weight=\"0.5\"/>\n"
                              "      <Term mask=\"ao\" weight=\"0.5\" offset=\"0.5\""
                              " steepness=\"10\"/>\n"
                              "      <Term constant=\"0.1\"/>\n"
                              "    </Combine>\n"
                              "  </Masks>",
                              false);
    }
    return path;
}

typedef struct image {
    int width, height;
    uint8_t *rgb;
} image;

static bool read_png(const char *name, image *img)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/%s", ensure_tmpdir(), name);
    png_image png;
    memset(&png, 0, sizeof png);
    png.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&png, path)) {
        fprintf(stderr, "%s: %s\n", path, png.message);
        return false;
    }
    png.format = PNG_FORMAT_RGB;
    img->width = (int)png.width;
    img->height = (int)png.height;
    img->rgb = malloc(PNG_IMAGE_SIZE(png));
    if (img->rgb == NULL || !png_image_finish_read(&png, NULL, img->rgb, 0, NULL)) {
        fprintf(stderr, "%s: %s\n", path, png.message);
        png_image_free(&png);
        free(img->rgb);
        return false;
    }
    return true;
}

// Pixels within `tol` of `rgb` in every channel.
static long count_color(const image *img, const uint8_t rgb[3], int tol)
{
    long n = 0;
    for (long p = 0; p < (long)img->width * img->height; ++p) {
        const uint8_t *px = &img->rgb[3 * p];
        if (abs(px[0] - rgb[0]) <= tol && abs(px[1] - rgb[1]) <= tol &&
            abs(px[2] - rgb[2]) <= tol) {
            n++;
        }
    }
    return n;
}

TEST(screenshot_shows_cameras_and_particles)
{
    ENSURE(have_xvfb());
    int status = screenshot("shot.png", 30);
    if (status != 0) {
        fprintf(stderr, "%s", out);
    }
    ENSURE(status == 0);
    ENSURE(ensure_contains(out, "shot.png"));
    image img;
    ENSURE(read_png("shot.png", &img));
    bool size_ok = img.width == WIDTH && img.height == HEIGHT;
    long total = (long)img.width * img.height;
    long background = count_color(&img, VW_BACKGROUND_COLOR, 0);
    // The frames of the two input cameras, drawn in their exact colours.
    long front = count_color(&img, VW_CAMERA_COLORS[0], 1);
    long top = count_color(&img, VW_CAMERA_COLORS[1], 1);
    // 30 steps of 0.01 s at 20000 particles/s: 6000 particles, still carrying all
    // their dirt, so drawn in the dirty colour.
    long dirty = count_color(&img, VW_PARTICLE_DIRTY_COLOR, 1);
    free(img.rgb);
    ENSURE(size_ok);
    ENSURE(total - background >= total / 100);
    ENSURE(front >= 50);
    ENSURE(top >= 50);
    ENSURE(dirty >= 20);
}

TEST(screenshot_is_reproducible)
{
    ENSURE(have_xvfb());
    ENSURE(screenshot("a.png", 12) == 0);
    ENSURE(screenshot("b.png", 12) == 0);
    image a, b;
    ENSURE(read_png("a.png", &a));
    if (!read_png("b.png", &b)) {
        free(a.rgb);
        ENSURE(false);
    }
    bool same = a.width == b.width && a.height == b.height &&
                memcmp(a.rgb, b.rgb, 3 * (size_t)a.width * (size_t)a.height) == 0;
    free(a.rgb);
    free(b.rgb);
    ENSURE(same);
}

// The thesis scene with three substances, water shown: its particles carry
// water 2, the largest water load, so they are drawn in water's colour, and
// none in dirt's brown; with --substance dirt, the other way round.
TEST(screenshot_shows_the_chosen_substance)
{
    ENSURE(have_xvfb());
    const char *scene = substance_scene();
    ENSURE(scene != NULL);
    int status = screenshot_of(scene, "water.png", 30, "--substance water");
    if (status != 0) {
        fprintf(stderr, "%s", out);
    }
    ENSURE(status == 0);
    ENSURE(screenshot_of(scene, "dirt.png", 30, "--substance dirt") == 0);
    image water, dirt;
    ENSURE(read_png("water.png", &water));
    if (!read_png("dirt.png", &dirt)) {
        free(water.rgb);
        ENSURE(false);
    }
    long water_blue = count_color(&water, VW_SUBSTANCE_COLORS[0], 1);
    long water_brown = count_color(&water, VW_PARTICLE_DIRTY_COLOR, 1);
    long dirt_blue = count_color(&dirt, VW_SUBSTANCE_COLORS[0], 1);
    long dirt_brown = count_color(&dirt, VW_PARTICLE_DIRTY_COLOR, 1);
    free(water.rgb);
    free(dirt.rgb);
    ENSURE(water_blue >= 20);
    ENSURE(water_brown == 0);
    ENSURE(dirt_brown >= 20);
    ENSURE(dirt_blue == 0);
}

// Mean row (from the top) of the pixels exactly of colour rgb, and how many.
static long rows_of(const image *img, const uint8_t rgb[3], double *mean_row)
{
    long n = 0;
    double sum = 0.0;
    for (long p = 0; p < (long)img->width * img->height; ++p) {
        const uint8_t *px = &img->rgb[3 * p];
        if (px[0] == rgb[0] && px[1] == rgb[1] && px[2] == rgb[2]) {
            n++;
            sum += (double)(p / img->width);
        }
    }
    *mean_row = n > 0 ? sum / (double)n : 0.0;
    return n;
}

// --mask step: the depth samples above y = 1 (the cube's top and the upper
// half of its front) in the ramp's bright end, those below (the slab, the
// lower half) in its dark end, higher up the picture on average; particles
// keep their colour. Without --mask the same scene shows neither colour.
TEST(screenshot_shows_the_chosen_mask)
{
    ENSURE(have_xvfb());
    const char *scene = mask_scene();
    ENSURE(scene != NULL);
    int status = screenshot_of(scene, "step.png", 30, "--mask step");
    if (status != 0) {
        fprintf(stderr, "%s", out);
    }
    ENSURE(status == 0);
    ENSURE(ensure_contains(out, "mask step 1/5 (height)"));
    ENSURE(screenshot_of(scene, "no_mask.png", 30, "") == 0);
    image step, plain;
    ENSURE(read_png("step.png", &step));
    if (!read_png("no_mask.png", &plain)) {
        free(step.rgb);
        ENSURE(false);
    }
    const uint8_t *dark = VW_MASK_RAMP[0], *bright = VW_MASK_RAMP[VW_MASK_RAMP_COUNT - 1];
    double dark_row, bright_row, unused;
    long dark_px = rows_of(&step, dark, &dark_row);
    long bright_px = rows_of(&step, bright, &bright_row);
    long dirty = count_color(&step, VW_PARTICLE_DIRTY_COLOR, 1);
    long plain_dark = rows_of(&plain, dark, &unused);
    long plain_bright = rows_of(&plain, bright, &unused);
    free(step.rgb);
    free(plain.rgb);
    ENSURE(dark_px >= 2000 && bright_px >= 500);
    ENSURE(bright_row + 20.0 < dark_row);
    ENSURE(dirty >= 20);
    ENSURE(plain_dark == 0 && plain_bright == 0);
}

// Bad input is found before any window opens: no display needed.
static int viewer_without_display(const char *args)
{
    return ensure_shell(out, sizeof out, "env -u DISPLAY %s/weathering-viewer %s",
                        ensure_build_dir(), args);
}

TEST(bad_scene_exits_2_and_names_the_file)
{
    ENSURE(viewer_without_display("tests/bad/malformed.xml") == 2);
    ENSURE(ensure_contains(out, "malformed.xml"));
    ENSURE(viewer_without_display("tests/bad/unknown_element.xml") == 2);
    ENSURE(ensure_contains(out, "unknown_element.xml:"));
    ENSURE(viewer_without_display("no/such/scene.xml") == 2);
    ENSURE(ensure_contains(out, "no/such/scene.xml"));
}

TEST(bad_usage_exits_2)
{
    ENSURE(viewer_without_display("") == 2);
    ENSURE(ensure_contains(out, "usage: weathering-viewer SCENE.xml"));
    ENSURE(viewer_without_display("--help") == 0);
    ENSURE(ensure_contains(out, "--screenshot FILE.png"));
    ENSURE(viewer_without_display("xml_scenes/thesis_box.xml --frames 0") == 2);
    ENSURE(ensure_contains(out, "--frames takes a whole number"));
    ENSURE(viewer_without_display("xml_scenes/thesis_box.xml --bogus") == 2);
    ENSURE(ensure_contains(out, "unknown option '--bogus'"));
    ENSURE(viewer_without_display("xml_scenes/thesis_box.xml --size 10x") == 2);
    ENSURE(viewer_without_display("xml_scenes/thesis_box.xml --substance") == 2);
    ENSURE(viewer_without_display("xml_scenes/thesis_box.xml --substance rust") == 2);
    ENSURE(ensure_contains(out, "no such substance (it has dirt)"));
    // --mask names a mask of <Masks>; the message lists them.
    ENSURE(viewer_without_display("--help") == 0);
    ENSURE(ensure_contains(out, "--mask NAME"));
    ENSURE(viewer_without_display("xml_scenes/thesis_box.xml --mask") == 2);
    ENSURE(viewer_without_display("xml_scenes/thesis_box.xml --mask ao") == 2);
    ENSURE(ensure_contains(out, "--mask ao: xml_scenes/thesis_box.xml has no such mask (it has "
                                "no <Masks>)"));
    const char *scene = mask_scene();
    ENSURE(scene != NULL);
    char args[4400];
    snprintf(args, sizeof args, "%s --mask moss", scene);
    ENSURE(viewer_without_display(args) == 2);
    ENSURE(ensure_contains(out, "no such mask (it has step, height, curv, ao, both)"));
}

// A <View> camera without maps: the viewer runs `weathering bake` in a child
// process; a mesh that is not one makes the bake, and so the viewer, fail with
// status 2 before any window opens.
TEST(failed_bake_exits_2)
{
    const char *tmp = ensure_tmpdir();
    ensure_write_file(tmp, "not_a_mesh.obj", "this is not a mesh\n");
    const char *scene = ensure_write_file(
        tmp, "needs_bake.xml",
        "<Weathering>\n"
        "  <Collider>\n"
        "    <ProjectedMaps>\n"
        "      <Ortho cameraName=\"front\">\n"
        "        <View eye=\"0 0 10\" target=\"0 0 0\" up=\"0 1 0\" width=\"4\" height=\"4\"\n"
        "              resolution=\"16\"/>\n"
        "      </Ortho>\n"
        "    </ProjectedMaps>\n"
        "  </Collider>\n"
        "  <Geometry>\n"
        "    <Mesh file=\"not_a_mesh.obj\"><Surface material=\"*\"/></Mesh>\n"
        "  </Geometry>\n"
        "</Weathering>\n");
    char args[8400];
    snprintf(args, sizeof args, "%s --out %s/baked", scene, tmp);
    ENSURE(viewer_without_display(args) == 2);
    ENSURE(ensure_contains(out, "weathering bake"));
}

// --- the GL-free parts -----------------------------------------------------------

static vw_settings thesis_settings(void)
{
    static char out_dir[4200];
    snprintf(out_dir, sizeof out_dir, "%s/world_out", ensure_tmpdir());
    vw_settings s = { .scene_path = "xml_scenes/thesis_box.xml", .out_dir = out_dir,
                      .threads = 1, .hit_capacity = 64 };
    return s;
}

// Smallest and largest coordinates of a run of vertices.
static void extent(const vw_vertex *v, vw_range r, float lo[3], float hi[3])
{
    for (int a = 0; a < 3; ++a) {
        lo[a] = INFINITY;
        hi[a] = -INFINITY;
    }
    for (int i = r.first; i < r.first + r.count; ++i) {
        for (int a = 0; a < 3; ++a) {
            lo[a] = fminf(lo[a], v[i].position[a]);
            hi[a] = fmaxf(hi[a], v[i].position[a]);
        }
    }
}

TEST(thesis_scene_geometry)
{
    vw_settings settings = thesis_settings();
    static vw_world w;
    wx_error err;
    ENSURE(vw_world_parse(&w, &settings, &err) == WX_OK);
    ENSURE(!vw_world_needs_bake(&w, NULL)); // matrices and maps, no <View>
    ENSURE(vw_world_finish(&w, &settings, &err) == WX_OK);
    ENSURE(w.scene.camera_count == 3);
    float lo[3], hi[3];
    // front: [u v d 1] * CTW = (8u - 4, 8v - 3, 10 - d); its frame at d = 0,
    // then a line along the view and the top tick: 6 lines.
    ENSURE(w.camera_lines[0].count == 12);
    extent(w.lines, w.camera_lines[0], lo, hi);
    ENSURE_NEAR(lo[0], -4, 1e-5);
    ENSURE_NEAR(hi[0], 4, 1e-5);
    ENSURE_NEAR(lo[1], -3, 1e-5);
    ENSURE_NEAR(hi[1], 5, 1e-5);
    ENSURE_NEAR(lo[2], 8, 1e-5); // the view line: a quarter of the 8 m frame towards -Z
    ENSURE_NEAR(hi[2], 10, 1e-5);
    // top: (8u - 4, 10 - d, 4 - 8v), seen from y = 10 looking down.
    extent(w.lines, w.camera_lines[1], lo, hi);
    ENSURE_NEAR(lo[0], -4, 1e-5);
    ENSURE_NEAR(hi[2], 4, 1e-5);
    ENSURE_NEAR(lo[1], 8, 1e-5);
    ENSURE_NEAR(hi[1], 10, 1e-5);
    // The output camera shares the front frame, drawn 1% inside it.
    extent(w.lines, (vw_range){ w.camera_lines[2].first, 8 }, lo, hi);
    ENSURE_NEAR(lo[0], -4 + 0.08, 1e-5);
    ENSURE_NEAR(hi[1], 5 - 0.08, 1e-5);
    // The initial view frames the frames: x, z in [-4, 4] and [-4, 10], y in [-3, 10].
    ENSURE_NEAR(w.frame_lo[0], -4, 1e-5);
    ENSURE_NEAR(w.frame_lo[1], -3, 1e-5);
    ENSURE_NEAR(w.frame_lo[2], -4, 1e-5);
    ENSURE_NEAR(w.frame_hi[1], 10, 1e-5);
    ENSURE_NEAR(w.frame_hi[2], 10, 1e-5);
    // One point emitter: a box (12 edges) and a 3-line cross; the 30 m bounding
    // box centred at (0, 5, 0).
    ENSURE(w.emitter_lines.count == 30);
    ENSURE(w.bbox_lines.count == 24);
    extent(w.lines, w.bbox_lines, lo, hi);
    ENSURE_NEAR(lo[1], -10, 1e-5);
    ENSURE_NEAR(hi[1], 20, 1e-5);
    ENSURE_NEAR(hi[0], 15, 1e-5);
    // 3 maps of 256 x 256 = 196608 texels fit the 250k budget: every texel with
    // a surface becomes a sample, which lies on its texel centre at its depth.
    int total = 0;
    for (int c = 0; c < 3; ++c) {
        const wx_maps *m = &w.maps[w.camera_maps[c]];
        int surface = 0;
        for (int t = 0; t < m->width * m->height; ++t) {
            surface += !wx_depth_is_empty(m->depth[t]);
        }
        ENSURE(w.camera_points[c].count == surface);
        total += surface;
    }
    ENSURE(total == w.point_count && total > 0 && total <= VW_MAX_DEPTH_SAMPLES);
    // One layer per camera: L has nothing to cycle, every sample is of layer
    // 0 in full colour, and its view is its input camera.
    ENSURE(w.max_layers == 1 && vw_world_next_layer(&w, -1) == -1);
    ENSURE(wx_sim_input_count(w.sim) == 2 && w.first_view[0] == 0 && w.first_view[1] == 1);
    for (int c = 0; c < 3; ++c) {
        vw_range r = w.camera_points[c], r0 = vw_world_layer_points(&w, c, 0);
        ENSURE(vw_world_camera_layers(&w, c) == 1 && vw_world_layer_points(&w, c, 1).count == 0);
        ENSURE(r0.first == r.first && r0.count == r.count);
        int wrong = 0;
        for (int i = r.first; i < r.first + r.count; ++i) {
            wrong += w.samples[i].layer != 0 ||
                     w.samples[i].input != (w.scene.cameras[c].is_output ? -1 : c);
        }
        ENSURE(wrong == 0);
    }
    const vw_vertex *first = &w.points[w.camera_points[0].first];
    float uvd[3];
    wx_camera_world_to_map(&w.scene.cameras[0].camera, first->position, uvd);
    int i = -1, j = -1;
    ENSURE(wx_map_texel(256, 256, uvd[0], uvd[1], &i, &j));
    ENSURE_NEAR(uvd[0] * 256 - (float)i, 0.5, 1e-3);
    ENSURE_NEAR(uvd[2], w.maps[w.camera_maps[0]].depth[j * 256 + i], 1e-4);
    ENSURE_NEAR(w.load_scale, 1, 0);
    ENSURE(wx_sim_step_count(w.sim) == 0);
    ENSURE(!vw_world_finished(&w));
    vw_world_free(&w);
}

static void set_mtime(const char *path, time_t t)
{
    struct timespec times[2] = { { t, 0 }, { t, 0 } };
    utimensat(AT_FDCWD, path, times, 0);
}

// A <View> camera: bake when its maps are missing, older than the scene, or
// when a reload changes the camera; not for an emitter edit.
TEST(maps_are_baked_again_when_needed)
{
    const char *tmp = ensure_tmpdir();
    ensure_write_file(tmp, "box.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const char *scene_text =
        "<Weathering>\n"
        "  <Emitters><PointEmitter centerY=\"2\" rate=\"%s\"/></Emitters>\n"
        "  <Collider><ProjectedMaps><Ortho cameraName=\"cam\">\n"
        "    <View eye=\"0 0 %s\" target=\"0 0 0\" up=\"0 1 0\" width=\"2\" height=\"2\"\n"
        "          resolution=\"8\"/>\n"
        "  </Ortho></ProjectedMaps></Collider>\n"
        "  <Geometry><Mesh file=\"box.obj\"><Surface material=\"*\"/></Mesh></Geometry>\n"
        "</Weathering>\n";
    char text[2048], out_dir[4200], map[4300];
    snprintf(text, sizeof text, scene_text, "100", "5");
    const char *scene = ensure_write_file(tmp, "view.xml", text);
    snprintf(out_dir, sizeof out_dir, "%s/view_out", tmp);
    mkdir(out_dir, 0777);
    vw_settings settings = { .scene_path = scene, .out_dir = out_dir, .threads = 1 };
    static vw_world first, reloaded;
    wx_error err;
    ENSURE(vw_world_parse(&first, &settings, &err) == WX_OK);
    ENSURE(vw_world_needs_bake(&first, NULL)); // no maps yet
    time_t now = time(NULL);
    set_mtime(scene, now - 100);
    static const char *const kinds[4] = { "depth", "normal", "impact", "dirt" };
    for (int k = 0; k < 4; ++k) {
        snprintf(map, sizeof map, "%s/cam_%s.exr", out_dir, kinds[k]);
        ensure_write_file(out_dir, strrchr(map, '/') + 1, "fake");
        set_mtime(map, now - 50);
    }
    set_mtime(ensure_write_file(tmp, "box.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
              now - 200);
    ENSURE(!vw_world_needs_bake(&first, NULL)); // maps newer than scene and mesh
    set_mtime(scene, now - 10);
    ENSURE(vw_world_needs_bake(&first, NULL)); // the scene changed since the bake
    // Reloads compare with the running scene instead.
    snprintf(text, sizeof text, scene_text, "500", "5"); // another emitter rate
    ensure_write_file(tmp, "view.xml", text);
    ENSURE(vw_world_parse(&reloaded, &settings, &err) == WX_OK);
    ENSURE(!vw_world_needs_bake(&reloaded, &first));
    // G rewriting cam_dirt.exr needs no bake: the simulated map keeps its
    // initial dirt (channel initialDirt), which the next load reads.
    set_mtime(map, now);
    ENSURE(!vw_world_needs_bake(&reloaded, &first));
    vw_world_free(&reloaded);
    snprintf(text, sizeof text, scene_text, "500", "6"); // the camera moved
    ensure_write_file(tmp, "view.xml", text);
    ENSURE(vw_world_parse(&reloaded, &settings, &err) == WX_OK);
    ENSURE(vw_world_needs_bake(&reloaded, &first));
    vw_world_free(&reloaded);
    vw_world_free(&first);
}

// Identity view: NDC = world, a 128 x 128 screen of 2 x 2 tiles of 64 pixels.
TEST(nearest_point_per_pixel_in_tile_order)
{
    static vw_point_filter f;
    static const float identity[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };
    ENSURE(vw_points_begin(&f, identity, 128, 128, 16));
    vw_points_offer(&f, 0.0f, 0.0f, 0.5f, 1, 0, 0, 0);     // pixel (64, 64): tile 3
    vw_points_offer(&f, 0.001f, 0.001f, 0.2f, 2, 0, 0, 0); // same pixel, nearer: wins
    vw_points_offer(&f, 0.005f, 0.005f, 0.2f, 3, 0, 0, 0); // same pixel, same depth: loses
    vw_points_offer(&f, -0.99f, -0.99f, 0.0f, 4, 0, 0, 0); // pixel (0, 0): tile 0
    vw_points_offer(&f, 0.5f, -0.5f, 0.9f, 5, 0, 0, 0);    // pixel (96, 32): tile 1
    vw_points_offer(&f, 0.51f, -0.5f, 0.9f, 6, 0, 0, 0);   // pixel (96, 32) too: first wins
    vw_points_offer(&f, -0.5f, 0.5f, 0.0f, 7, 0, 0, 0);    // pixel (32, 96): tile 2
    vw_points_offer(&f, 1.5f, 0.0f, 0.0f, 8, 0, 0, 0);     // off screen
    vw_points_offer(&f, 0.0f, 0.0f, 1.5f, 9, 0, 0, 0);     // beyond the far plane
    float got[4 * 16];
    size_t n = vw_points_winners(&f, got);
    ENSURE(n == 4);
    ENSURE(got[0] == 4 && got[4] == 5 && got[8] == 7 && got[12] == 2);
    // A new pass forgets the last one.
    ENSURE(vw_points_begin(&f, identity, 128, 128, 16));
    vw_points_offer(&f, 0.0f, 0.0f, 0.7f, 10, 11, 12, 13);
    ENSURE(vw_points_winners(&f, got) == 1);
    ENSURE(got[0] == 10 && got[1] == 11 && got[2] == 12 && got[3] == 13);
    vw_points_free(&f);
}

// Projects a world point with a column-major matrix to NDC.
static void project(const float m[16], const float p[3], float ndc[3])
{
    float c[4];
    for (int r = 0; r < 4; ++r) {
        c[r] = m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r];
    }
    for (int r = 0; r < 3; ++r) {
        ndc[r] = c[r] / c[3];
    }
}

TEST(initial_view_frames_the_box)
{
    vw_orbit orbit;
    const float lo[3] = { -4, -3, -4 }, hi[3] = { 4, 10, 10 };
    vw_orbit_frame(&orbit, lo, hi, 1.6f);
    float mvp[16], ndc[3];
    vw_orbit_matrix(&orbit, 1.6f, mvp);
    const float centre[3] = { 0, 3.5f, 3 };
    project(mvp, centre, ndc);
    ENSURE_NEAR(ndc[0], 0, 1e-5);
    ENSURE_NEAR(ndc[1], 0, 1e-5);
    for (int k = 0; k < 8; ++k) {
        const float corner[3] = { k & 1 ? hi[0] : lo[0], k & 2 ? hi[1] : lo[1],
                                  k & 4 ? hi[2] : lo[2] };
        project(mvp, corner, ndc);
        ENSURE(fabsf(ndc[0]) < 1 && fabsf(ndc[1]) < 1 && ndc[2] > -1 && ndc[2] < 1);
    }
    // Zooming in moves closer; the eye stays above the target.
    float eye[3];
    vw_orbit_eye(&orbit, eye);
    ENSURE(eye[1] > centre[1]);
    float before = orbit.distance;
    vw_orbit_zoom(&orbit, 1);
    ENSURE_NEAR(orbit.distance, before * 0.85f, 1e-4 * before);
}

// Without <Substances>: the one substance dirt, as before.
TEST(one_substance_is_dirt)
{
    vw_settings settings = thesis_settings();
    static vw_world w;
    wx_error err;
    ENSURE(vw_world_parse(&w, &settings, &err) == WX_OK);
    ENSURE(vw_world_finish(&w, &settings, &err) == WX_OK);
    ENSURE(vw_world_substance_count(&w) == 1);
    ENSURE(strcmp(vw_world_substance_name(&w), "dirt") == 0);
    ENSURE(vw_world_next_substance(&w) == 0);
    ENSURE_NEAR(w.load_scale, 1, 0);
    ENSURE(!vw_world_shows_deposits(&w)); // depth samples keep their camera's colour
    float c[3];
    vw_world_substance_color(&w, 0, c);
    ENSURE(c[0] == 150 / 255.0f && c[1] == 100 / 255.0f && c[2] == 50 / 255.0f);
    ENSURE(vw_world_total_steps(&w) == w.scene.steps);
    vw_world_free(&w);
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return x < y ? -1 : x > y;
}

TEST(substances_cycle_and_colour_by_the_shown_one)
{
    const char *scene = substance_scene();
    ENSURE(scene != NULL);
    vw_settings settings = thesis_settings();
    settings.scene_path = scene;
    static vw_world w;
    wx_error err;
    ENSURE(vw_world_parse(&w, &settings, &err) == WX_OK);
    ENSURE(vw_world_finish(&w, &settings, &err) == WX_OK);
    ENSURE(vw_world_substance_count(&w) == 3);
    ENSURE(vw_world_shows_deposits(&w));
    // The first is shown first; S walks water, dirt, rust and wraps. The scale
    // is the shown substance's largest emitter load; nobody emits rust, so the
    // largest load of any substance.
    ENSURE(w.substance == 0 && strcmp(vw_world_substance_name(&w), "water") == 0);
    ENSURE_NEAR(w.load_scale, 2, 0);
    ENSURE(vw_world_next_substance(&w) == 1 && strcmp(vw_world_substance_name(&w), "dirt") == 0);
    ENSURE_NEAR(w.load_scale, 0.25, 0);
    ENSURE(vw_world_next_substance(&w) == 2 && strcmp(vw_world_substance_name(&w), "rust") == 0);
    ENSURE_NEAR(w.load_scale, 2, 0);
    ENSURE(vw_world_next_substance(&w) == 0);
    ENSURE_NEAR(w.load_scale, 2, 0);
    // A reload keeps the shown substance by name, else shows the first.
    vw_world_keep_substance(&w, "rust");
    ENSURE(w.substance == 2);
    vw_world_keep_substance(&w, "moss");
    ENSURE(w.substance == 0);
    ENSURE(vw_world_find_substance(&w, "dirt") == 1 && vw_world_find_substance(&w, "Y") == -1);
    // Substance dirt keeps the brown of version 1; water is the palette's first.
    float rgb[3];
    vw_world_substance_color(&w, 1, rgb);
    ENSURE(rgb[0] == 150 / 255.0f && rgb[2] == 50 / 255.0f);
    vw_world_substance_color(&w, 0, rgb);
    ENSURE(rgb[0] == VW_SUBSTANCE_COLORS[0][0] / 255.0f &&
           rgb[2] == VW_SUBSTANCE_COLORS[0][2] / 255.0f);

    // Ten steps of 200 particles, falling from 6 m: nothing has hit the box
    // yet, so every particle still carries what it was emitted with, at
    // load[i * 3 + s].
    for (int k = 0; k < 10; ++k) {
        ENSURE(wx_sim_step(w.sim, &err) == WX_OK);
    }
    wx_particle_view view;
    wx_sim_particles(w.sim, &view);
    ENSURE(view.count > 1000);
    static const double want[3] = { 2, 0.25, 0 };
    for (int s = 0; s < 3; ++s) {
        vw_world_show_substance(&w, s);
        int wrong = 0;
        for (int64_t i = 0; i < view.count; ++i) {
            wrong += vw_particle_load(&w, &view, i) != want[s];
        }
        ENSURE(wrong == 0);
    }

    // After 150 steps particles have landed. A depth sample's deposit is the
    // amount of the shown substance on the texel it was made from, found
    // again here from its position: texel t's substance s at texels[t * 3 + s].
    for (int k = 10; k < 150; ++k) {
        ENSURE(wx_sim_step(w.sim, &err) == WX_OK);
    }
    int wrong = 0, out_samples = 0;
    double water_total = 0.0;
    for (int c = 0; c < w.scene.camera_count; ++c) {
        vw_range r = w.camera_points[c];
        for (int i = r.first; i < r.first + r.count; ++i) {
            if (w.scene.cameras[c].is_output) {
                vw_world_show_substance(&w, 0);
                out_samples += vw_world_deposit(&w, i) == -1.0;
                continue;
            }
            const wx_dirt_map *map = wx_sim_dirt_map(w.sim, w.first_view[c]);
            ENSURE(map->substances == 3);
            float uvd[3];
            int ti = -1, tj = -1;
            wx_camera_world_to_map(&w.scene.cameras[c].camera, w.points[i].position, uvd);
            ENSURE(wx_map_texel(map->width, map->height, uvd[0], uvd[1], &ti, &tj));
            size_t t = (size_t)tj * (size_t)map->width + (size_t)ti;
            for (int s = 0; s < 3; ++s) {
                vw_world_show_substance(&w, s);
                wrong += vw_world_deposit(&w, i) != map->texels[t * 3 + s].dirt;
            }
            water_total += map->texels[t * 3].dirt;
        }
    }
    ENSURE(wrong == 0);
    ENSURE(out_samples == w.camera_points[2].count);
    ENSURE(water_total > 0.0); // water has landed

    // Deposit colours of every sample of the input cameras, water shown: full
    // colour (times the sample's shading) at and above the 95% quantile of the
    // non-zero amounts, the camera's colour where there is none.
    vw_world_show_substance(&w, 0);
    size_t n = (size_t)(w.camera_points[0].count + w.camera_points[1].count);
    uint32_t *picked = malloc(n * sizeof *picked);
    float *scratch = malloc(n * sizeof *scratch), *sorted = malloc(n * sizeof *sorted);
    vw_vertex *colored = malloc(n * sizeof *colored);
    ENSURE(picked != NULL && scratch != NULL && sorted != NULL && colored != NULL);
    size_t nonzero = 0;
    for (size_t k = 0; k < n; ++k) {
        picked[k] = (uint32_t)(w.camera_points[0].first + (int)k); // inputs' samples come first
        double a = vw_world_deposit(&w, (int)picked[k]);
        if (a > 0.0) {
            sorted[nonzero++] = (float)a;
        }
    }
    ENSURE(nonzero > 100);
    qsort(sorted, nonzero, sizeof *sorted, cmp_float);
    float scale = vw_world_deposit_scale(&w, picked, n, scratch);
    ENSURE(scale == sorted[(size_t)((double)(nonzero - 1) * VW_DEPOSIT_QUANTILE)]);
    vw_world_deposit_colors(&w, picked, n, scratch, colored);
    float water[3];
    vw_world_substance_color(&w, 0, water);
    int full = 0, clean = 0, bad = 0;
    for (size_t k = 0; k < n; ++k) {
        const vw_vertex *src = &w.points[picked[k]];
        double a = vw_world_deposit(&w, (int)picked[k]);
        float shade = w.samples[picked[k]].shade;
        bad += memcmp(colored[k].position, src->position, sizeof src->position) != 0;
        if (a >= scale) {
            full++;
            for (int ch = 0; ch < 3; ++ch) {
                bad += fabsf(colored[k].color[ch] - water[ch] * shade) > 1e-6f;
            }
        } else if (!(a > 0.0)) {
            clean++;
            bad += memcmp(colored[k].color, src->color, sizeof src->color) != 0;
        } else {
            float t = sqrtf((float)a / scale);
            for (int ch = 0; ch < 3; ++ch) {
                float expect = src->color[ch] + t * (water[ch] * shade - src->color[ch]);
                bad += fabsf(colored[k].color[ch] - expect) > 1e-6f;
            }
        }
    }
    free(picked);
    free(scratch);
    free(sorted);
    free(colored);
    ENSURE(bad == 0);
    ENSURE(full >= (int)(nonzero / 20) && clean > 0);
    vw_world_free(&w);
}

// Height's value at a sample, as sim/masks.c works it out.
static float height_at(const vw_world *w, int m, int point)
{
    const wx_mask_def *md = &w->scene.masks[m];
    double lo = md->min, hi = md->max, y = w->points[point].position[1];
    return (float)fmin(1.0, fmax(0.0, (y - lo) / (hi - lo)));
}

static bool same_rgb(const float c[3], const uint8_t rgb[3])
{
    for (int k = 0; k < 3; ++k) {
        if (c[k] != (float)rgb[k] / 255.0f) {
            return false;
        }
    }
    return true;
}

// M's cycle, and each mask's value at every depth sample: Height by its
// formula at the sample's own point, every mask at an input camera's samples
// the very values wx_masks_at_camera gives on that camera's maps (the samples
// are every texel here), a Combine of masks already shown reading them back
// exactly; the colours of the ramps.
TEST(masks_cycle_and_colour_the_depth_samples)
{
    const char *scene = mask_scene();
    ENSURE(scene != NULL);
    vw_settings settings = thesis_settings();
    settings.scene_path = scene;
    static vw_world w;
    wx_error err;
    ENSURE(vw_world_parse(&w, &settings, &err) == WX_OK);
    ENSURE(vw_world_finish(&w, &settings, &err) == WX_OK);
    ENSURE(w.sample_stride == 1);
    ENSURE(vw_world_mask_count(&w) == 5);
    ENSURE(w.mask == -1 && isnan(vw_world_mask_value(&w, 0)));
    ENSURE(vw_world_find_mask(&w, "ao") == 3 && vw_world_find_mask(&w, "water") == -1);
    ENSURE(strcmp(vw_world_mask_kind_name(&w, 2), "curvature") == 0);
    // M: off -> step -> height -> curv -> ao -> both -> off, each computed
    // when first shown.
    static const char *const order[5] = { "step", "height", "curv", "ao", "both" };
    for (int k = 0; k < 5; ++k) {
        int m = vw_world_next_mask(&w);
        ENSURE(m == k && strcmp(w.scene.masks[m].name, order[k]) == 0);
        ENSURE(!vw_world_mask_ready(&w, m));
        ENSURE(vw_world_show_mask(&w, m, &err) == WX_OK);
        ENSURE(w.mask == m && vw_world_mask_ready(&w, m));
    }
    ENSURE(vw_world_next_mask(&w) == -1);
    ENSURE(vw_world_show_mask(&w, -1, &err) == WX_OK && w.mask == -1);
    ENSURE(vw_world_next_mask(&w) == 0 && vw_world_mask_ready(&w, 0));

    // Height at every sample, of every camera (the output camera's too).
    int wrong = 0, bright = 0, dark = 0;
    for (int i = 0; i < w.point_count; ++i) {
        for (int m = 0; m < 2; ++m) {
            wrong += w.mask_values[m][i] != height_at(&w, m, i);
        }
        bright += w.mask_values[0][i] == 1.0f;
        dark += w.mask_values[0][i] == 0.0f;
    }
    ENSURE(wrong == 0);
    // The cube's top (64 x 64 texels from above) and the upper half of its
    // front (64 x 32, by the front and the output camera) are bright.
    ENSURE(bright == 64 * 64 + 2 * 64 * 32 && dark > 20000 && bright + dark > w.point_count - 100);

    // The input cameras' samples against the library at their maps' texels.
    float *zero = calloc(256 * 256, sizeof *zero);
    float *planes[5];
    for (int m = 0; m < 5; ++m) {
        planes[m] = malloc(256 * 256 * sizeof *planes[m]);
        ENSURE(planes[m] != NULL);
    }
    const float *substances[1] = { zero };
    ENSURE(zero != NULL && w.mask_context != NULL);
    for (int c = 0; c < 2; ++c) {
        ENSURE(w.maps[w.camera_maps[c]].width == 256);
        ENSURE(wx_masks_at_camera(&w.scene, &w.opts, w.mask_context, -1,
                                  &w.scene.cameras[c].camera, &w.maps[w.camera_maps[c]],
                                  substances, planes, &err) == WX_OK);
        vw_range r = w.camera_points[c];
        for (int i = r.first; i < r.first + r.count; ++i) {
            for (int m = 0; m < 5; ++m) {
                wrong += w.mask_values[m][i] != planes[m][w.samples[i].texel];
            }
        }
    }
    for (int m = 0; m < 5; ++m) {
        free(planes[m]);
    }
    free(zero);
    ENSURE(wrong == 0);
    // Accessibility: open on top of the cube, less so where the cube meets the slab.
    double top = 0.0, foot = 0.0;
    int tops = 0, feet = 0;
    for (int i = 0; i < w.point_count; ++i) {
        const float *p = w.points[i].position;
        if (p[1] > 1.99f && fabsf(p[0]) < 0.5f && fabsf(p[2]) < 0.5f) {
            top += w.mask_values[3][i];
            tops++;
        } else if (fabsf(p[1]) < 0.01f && fabsf(p[0]) < 0.9f && p[2] > 1.0f && p[2] < 1.05f) {
            foot += w.mask_values[3][i];
            feet++;
        }
    }
    ENSURE(tops > 100 && feet > 10);
    ENSURE(top / tops > 0.95 && foot / feet < 0.8 * top / tops);

    // Curvature: the box's faces are flat (at an edge the other face's
    // points are left out), so 0 everywhere and the ramp's scale 1. On other
    // values it spans their 99th percentile of |value| (no value: left out).
    int curved = 0;
    for (int i = 0; i < w.point_count; ++i) {
        curved += w.mask_values[2][i] != 0.0f;
    }
    ENSURE(curved == 0 && w.mask_scale[2] == 1.0f);
    ENSURE(w.mask_scale[0] == 1.0f && w.mask_scale[3] == 1.0f);
    float *fake = malloc((size_t)w.point_count * sizeof *fake);
    ENSURE(fake != NULL);
    // The first 20000 samples: 10000 zeros and +-1, ..., +-5000; the others
    // no value. Sorted by |value|: 10000 zeros, then 1, 1, 2, 2, ..., so the
    // 99th percentile, at (20000 - 1) * 0.99 = 19799.01, is 4900.
    ENSURE(w.point_count > 20000);
    for (int i = 0; i < w.point_count; ++i) {
        int k = i / 4, pair = i % 4;
        fake[i] = i >= 20000 ? NAN : pair >= 2 ? 0.0f : (float)(k + 1) * (pair ? -1.0f : 1.0f);
    }
    ENSURE(vw_world_mask_scale(&w, 2, fake) == 4900.0f);
    for (int i = 0; i < w.point_count; ++i) {
        fake[i] = i == 5 ? -0.25f : i % 3 ? 0.0f : NAN; // one curved sample among flat ones
    }
    ENSURE(vw_world_mask_scale(&w, 2, fake) == 0.25f);
    ENSURE(vw_world_mask_scale(&w, 0, fake) == 1.0f); // not Curvature
    free(fake);

    // Colours: step's samples at the ends of the ramp, unshaded; Curvature's
    // grey where flat, blue and red at -scale and +scale and beyond.
    ENSURE(vw_world_show_mask(&w, 0, &err) == WX_OK);
    size_t n = (size_t)w.point_count;
    uint32_t *picked = malloc(n * sizeof *picked);
    vw_vertex *colored = malloc(n * sizeof *colored);
    ENSURE(picked != NULL && colored != NULL);
    for (size_t k = 0; k < n; ++k) {
        picked[k] = (uint32_t)k;
    }
    vw_world_mask_colors(&w, picked, n, colored);
    int bad = 0;
    for (size_t k = 0; k < n; ++k) {
        float v = w.mask_values[0][k];
        bad += memcmp(colored[k].position, w.points[k].position, sizeof colored[k].position) != 0;
        if (v == 0.0f) {
            bad += !same_rgb(colored[k].color, VW_MASK_RAMP[0]);
        } else if (v == 1.0f) {
            bad += !same_rgb(colored[k].color, VW_MASK_RAMP[VW_MASK_RAMP_COUNT - 1]);
        }
    }
    free(picked);
    free(colored);
    ENSURE(bad == 0);
    float rgb[3];
    vw_world_mask_color(&w, 0.5f, rgb);
    ENSURE(same_rgb(rgb, VW_MASK_RAMP[2]));
    vw_world_mask_color(&w, 7.0f, rgb); // clamped
    ENSURE(same_rgb(rgb, VW_MASK_RAMP[VW_MASK_RAMP_COUNT - 1]));
    ENSURE(vw_world_show_mask(&w, 2, &err) == WX_OK);
    float scale = w.mask_scale[2];
    vw_world_mask_color(&w, 0.0f, rgb);
    ENSURE(same_rgb(rgb, VW_CURVATURE_RAMP[1]));
    vw_world_mask_color(&w, -scale, rgb);
    ENSURE(same_rgb(rgb, VW_CURVATURE_RAMP[0]));
    vw_world_mask_color(&w, 3.0f * scale, rgb);
    ENSURE(same_rgb(rgb, VW_CURVATURE_RAMP[2]));

    // A reload keeps the mask by name, computed again; else shows none.
    ENSURE(vw_world_keep_mask(&w, "nothing", &err) == WX_OK && w.mask == -1);
    vw_world_free(&w);

    // Shown first, a Combine computes what it reads too, and those only.
    ENSURE(vw_world_parse(&w, &settings, &err) == WX_OK);
    ENSURE(vw_world_finish(&w, &settings, &err) == WX_OK);
    ENSURE(vw_world_keep_mask(&w, "both", &err) == WX_OK && w.mask == 4);
    ENSURE(vw_world_mask_ready(&w, 1) && vw_world_mask_ready(&w, 3));
    ENSURE(!vw_world_mask_ready(&w, 0) && !vw_world_mask_ready(&w, 2));
    wrong = 0;
    for (int i = 0; i < w.point_count; ++i) {
        wrong += w.mask_values[1][i] != height_at(&w, 1, i);
    }
    ENSURE(wrong == 0);
    vw_world_free(&w);

    // Without <Masks>: nothing to cycle.
    settings = thesis_settings();
    ENSURE(vw_world_parse(&w, &settings, &err) == WX_OK);
    ENSURE(vw_world_finish(&w, &settings, &err) == WX_OK);
    ENSURE(vw_world_mask_count(&w) == 0 && vw_world_next_mask(&w) == -1);
    ENSURE(w.mask_context == NULL);
    vw_world_free(&w);
}

// Fewer samples than texels (a stride of 3): each mask is evaluated on the
// grid of the sampled texels, and each sample gets its own texel's value.
TEST(masks_at_sparse_samples)
{
    const char *scene = mask_scene();
    ENSURE(scene != NULL);
    vw_settings settings = thesis_settings();
    settings.scene_path = scene;
    static vw_world w;
    wx_error err;
    ENSURE(vw_world_parse(&w, &settings, &err) == WX_OK);
    ENSURE(vw_world_finish(&w, &settings, &err) == WX_OK);
    free(w.lines);
    free(w.points);
    free(w.samples);
    free(w.camera_lines);
    free(w.camera_points);
    free(w.layer_points);
    ENSURE(vw_world_build_geometry_within(&w, 40000, &err) == WX_OK);
    ENSURE(w.sample_stride == 3);
    ENSURE(vw_world_show_mask(&w, 1, &err) == WX_OK);
    ENSURE(vw_world_show_mask(&w, 2, &err) == WX_OK);
    int wrong = 0, nan = 0, flat = 0, top = 0;
    for (int i = 0; i < w.point_count; ++i) {
        wrong += w.mask_values[1][i] != height_at(&w, 1, i);
        nan += isnan(w.mask_values[2][i]);
        // Flat in the middle of the cube's top, seen from above.
        const float *p = w.points[i].position;
        if (w.samples[i].input == 1 && p[1] > 1.99f && fabsf(p[0]) < 0.8f && fabsf(p[2]) < 0.8f) {
            top++;
            flat += fabsf(w.mask_values[2][i]) < 1e-3f;
        }
    }
    ENSURE(wrong == 0 && nan == 0);
    ENSURE(top > 100 && flat == top);
    // Where the samples are: texels 1, 4, 7, ... of every row and column.
    for (int i = 0; i < w.point_count; ++i) {
        int texel = w.samples[i].texel;
        wrong += texel % 256 % 3 != 1 || texel / 256 % 3 != 1;
    }
    ENSURE(wrong == 0);
    vw_world_free(&w);
}

// --- layers (docs/design.md section 14) ---------------------------------------------

// Value of channel `ch` of map `kind` of the layered fixture's camera `a` (two
// layers, 8 x 8) or `b` (one, 4 x 4) at layer `layer`, column i: a's layer 0
// is a front face at depth 2 everywhere, its layer 1 a back face at depth 3
// in columns 0-3 only (none elsewhere); b sees a face at depth 1.5. Normals
// point out of the solid; dirt (R) is 1 on a's layer 0, 2 on its layer 1, 3 on b.
static float layered_value(bool a, const char *kind, int layer, int ch, int i)
{
    if (strcmp(kind, "depth") == 0) {
        return layer == 0 ? (a ? 2.0f : 1.5f) : i < 4 ? 3.0f : 0.0f;
    }
    if (strcmp(kind, "normal") == 0) {
        return !a ? (ch == 2 ? 1.0f : 0.0f) : ch == 1 ? (layer == 0 ? 1.0f : -1.0f) : 0.0f;
    }
    if (strcmp(kind, "impact") == 0) {
        return 0.5f;
    }
    return ch == 0 ? (a ? 1.0f + (float)layer : 3.0f) : 1.0f; // dirt, deposit, erosion
}

// Camera `cam`'s four maps as `weathering bake` writes a layered camera's:
// layer k's channels as "layerK.R" and so on.
static bool write_layered_maps(const char *dir, const char *cam, int size, int layers)
{
    static const char *const kinds[4] = { "depth", "normal", "impact", "dirt" };
    static const char *const rgb[3] = { "R", "G", "B" };
    static const int counts[4] = { 1, 3, 2, 3 };
    for (int k = 0; k < 4; ++k) {
        char names[3 * WX_MAX_LAYERS][WX_NAME_MAX], path[4400];
        const char *channels[3 * WX_MAX_LAYERS];
        int n = 0;
        for (int layer = 0; layer < layers; ++layer) {
            for (int c = 0; c < counts[k]; ++c, ++n) {
                wx_layer_channel(names[n], layer, rgb[c]);
                channels[n] = names[n];
            }
        }
        wx_image file;
        if (wx_image_alloc(&file, size, size, n, channels, NULL) != WX_OK) {
            return false;
        }
        for (int c = 0; c < n; ++c) {
            for (int t = 0; t < size * size; ++t) {
                file.channels[c][t] = layered_value(cam[0] == 'a', kinds[k], c / counts[k],
                                                     c % counts[k], t % size);
            }
        }
        snprintf(path, sizeof path, "%s/%s_%s.exr", dir, cam, kinds[k]);
        bool ok = wx_exr_write(path, &file, NULL) == WX_OK;
        wx_image_free(&file);
        if (!ok) {
            return false;
        }
    }
    return true;
}

// A scene with a layered camera "a" (layers="2", from above: its layers at y
// = 3 and 2) and a camera "b" of one layer (from +z), with a Height mask, with
// the maps a bake that peels layers writes made by hand in `out_dir` (exact
// values, independent of the bake), newer than the scene and the mesh. NULL
// when they cannot be written.
static const char *layered_scene(char out_dir[4200])
{
    const char *tmp = ensure_tmpdir();
    const char *mesh = ensure_write_file(tmp, "layered.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const char *scene = ensure_write_file(
        tmp, "layered.xml",
        "<Weathering>\n"
        "  <Emitters><PointEmitter centerY=\"2\" rate=\"100\"/></Emitters>\n"
        "  <Collider><ProjectedMaps>\n"
        "    <Ortho cameraName=\"a\" layers=\"2\">\n"
        "      <View eye=\"0 5 0\" target=\"0 0 0\" up=\"0 0 -1\" width=\"2\" height=\"2\"\n"
        "            resolution=\"8\"/>\n"
        "    </Ortho>\n"
        "    <Ortho cameraName=\"b\">\n"
        "      <View eye=\"0 0 5\" target=\"0 0 0\" up=\"0 1 0\" width=\"2\" height=\"2\"\n"
        "            resolution=\"4\"/>\n"
        "    </Ortho>\n"
        "  </ProjectedMaps></Collider>\n"
        "  <Geometry><Mesh file=\"layered.obj\"><Surface material=\"*\"/></Mesh></Geometry>\n"
        "  <Masks><Height name=\"y\" min=\"0\" max=\"5\"/></Masks>\n"
        "</Weathering>\n");
    snprintf(out_dir, 4200, "%s/layered_out", tmp);
    mkdir(out_dir, 0777);
    if (!write_layered_maps(out_dir, "a", 8, 2) || !write_layered_maps(out_dir, "b", 4, 1)) {
        return NULL;
    }
    time_t now = time(NULL);
    set_mtime(scene, now - 100);
    set_mtime(mesh, now - 100);
    return scene;
}

// The deposits of every depth sample (the amount on its texel of its view)
// against the fixture's dirt; returns the samples that differ.
static int wrong_layered_deposits(const vw_world *w)
{
    int wrong = 0;
    for (int c = 0; c < 2; ++c) {
        for (int k = 0; k < vw_world_camera_layers(w, c); ++k) {
            vw_range r = vw_world_layer_points(w, c, k);
            for (int i = r.first; i < r.first + r.count; ++i) {
                wrong += vw_world_deposit(w, i) != layered_value(c == 0, "dirt", k, 0, 0);
            }
        }
    }
    return wrong;
}

// A layered camera: every layer's depth samples, each naming its view (its
// dirt map in the simulation), deeper ones darker; L's cycle; hits' views
// mapped to their cameras and layers; G writes and a reload reads every layer.
TEST(layers_cycle_and_samples_name_their_views)
{
    char out_dir[4200];
    const char *scene = layered_scene(out_dir);
    ENSURE(scene != NULL);
    vw_settings settings = { .scene_path = scene, .out_dir = out_dir, .threads = 1,
                             .hit_capacity = 64 };
    static vw_world w, again;
    wx_error err = { 0 };
    ENSURE(vw_world_parse(&w, &settings, &err) == WX_OK);
    ENSURE(!vw_world_needs_bake(&w, NULL));
    wx_result r = vw_world_finish(&w, &settings, &err);
    if (r != WX_OK) {
        fprintf(stderr, "        %s\n", err.message);
    }
    ENSURE(r == WX_OK);
    ENSURE(w.max_layers == 2 && w.sample_stride == 1);
    ENSURE(vw_world_camera_layers(&w, 0) == 2 && vw_world_camera_layers(&w, 1) == 1);
    // Views: a's layers 0 and 1, then b.
    ENSURE(wx_sim_input_count(w.sim) == 3 && w.first_view[0] == 0 && w.first_view[1] == 2);
    // L: every layer -> layer 0 -> layer 1 -> every layer.
    ENSURE(vw_world_next_layer(&w, -1) == 0);
    ENSURE(vw_world_next_layer(&w, 0) == 1);
    ENSURE(vw_world_next_layer(&w, 1) == -1);
    // Samples per layer: a's 64 front texels and 32 back ones, b's 16; b has
    // no layer 1. Every layer together is the camera's whole run.
    static const int want[2][2] = { { 64, 32 }, { 16, 0 } };
    int shown[3] = { 0, 0, 0 }; // per L setting: every layer, layer 0, layer 1
    for (int c = 0; c < 2; ++c) {
        for (int k = 0; k < 2; ++k) {
            ENSURE(vw_world_layer_points(&w, c, k).count == want[c][k]);
        }
        vw_range all = vw_world_layer_points(&w, c, -1);
        ENSURE(all.count == want[c][0] + want[c][1] && all.first == w.camera_points[c].first);
        for (int layer = -1, n = 0; n < 3; layer = vw_world_next_layer(&w, layer), ++n) {
            shown[n] += vw_world_layer_points(&w, c, layer).count;
        }
    }
    ENSURE(shown[0] == 112 && shown[1] == 80 && shown[2] == 32 && w.point_count == 112);
    // Each sample: its layer, its view, its point at its layer's depth.
    int wrong = 0;
    for (int c = 0; c < 2; ++c) {
        for (int k = 0; k < vw_world_camera_layers(&w, c); ++k) {
            vw_range lr = vw_world_layer_points(&w, c, k);
            for (int i = lr.first; i < lr.first + lr.count; ++i) {
                const vw_sample *smp = &w.samples[i];
                float uvd[3];
                wx_camera_world_to_map(&w.scene.cameras[c].camera, w.points[i].position, uvd);
                int size = c == 0 ? 8 : 4;
                wrong += smp->layer != k || smp->input != w.first_view[c] + k;
                wrong += fabsf(uvd[2] - layered_value(c == 0, "depth", k, 0, smp->texel % size)) >
                         1e-4f;
            }
        }
    }
    ENSURE(wrong == 0);
    // Deposits read each sample's own view: 1 and 2 on a's layers, 3 on b.
    ENSURE(wrong_layered_deposits(&w) == 0);
    // Layer 1 is drawn darker: a back face's sample is its front face's
    // colour (the same normal shading, the normals opposite) times 0.7.
    vw_range front = vw_world_layer_points(&w, 0, 0), back = vw_world_layer_points(&w, 0, 1);
    for (int i = back.first; i < back.first + back.count; ++i) {
        const vw_vertex *f = &w.points[front.first + w.samples[i].texel];
        ENSURE(w.samples[front.first + w.samples[i].texel].texel == w.samples[i].texel);
        for (int ch = 0; ch < 3; ++ch) {
            wrong += fabsf(w.points[i].color[ch] - VW_LAYER_SHADE[1] * f->color[ch]) > 1e-6f;
        }
        wrong += fabsf(w.samples[i].shade -
                       VW_LAYER_SHADE[1] * w.samples[front.first + w.samples[i].texel].shade) >
                 1e-6f;
    }
    ENSURE(wrong == 0 && VW_LAYER_SHADE[1] < 1.0f);
    // A hit's camera is a view: a's layer 1 is view 1, b is view 2.
    int layer = -1;
    ENSURE(vw_world_view_camera(&w, 0, &layer) == 0 && layer == 0);
    ENSURE(vw_world_view_camera(&w, 1, &layer) == 0 && layer == 1);
    ENSURE(vw_world_view_camera(&w, 2, &layer) == 1 && layer == 0);
    ENSURE(vw_world_view_camera(&w, 3, &layer) == -1 && vw_world_view_camera(&w, -1, NULL) == -1);
    // A mask is evaluated on each layer's own depth: Height at every sample's
    // own point, 0.6 on a's layer 0 and 0.4 on its layer 1.
    ENSURE(vw_world_show_mask(&w, 0, &err) == WX_OK);
    for (int i = 0; i < w.point_count; ++i) {
        wrong += !(fabsf(w.mask_values[0][i] - height_at(&w, 0, i)) <= 1e-6f);
    }
    ENSURE(wrong == 0);
    ENSURE(fabsf(w.mask_values[0][back.first] - 0.4f) < 1e-5f);

    // G: the dirt maps hold every layer ("layer1." channels for a), and the
    // next load starts each layer from its own initial dirt.
    for (int k = 0; k < 20; ++k) {
        ENSURE(wx_sim_step(w.sim, &err) == WX_OK);
    }
    char saved[WX_PATH_MAX], path[4400];
    r = vw_world_gather(&w, saved, &err);
    if (r != WX_OK) {
        fprintf(stderr, "        %s\n", err.message);
    }
    ENSURE(r == WX_OK);
    snprintf(path, sizeof path, "%s/a_dirt.exr", out_dir);
    wx_image *header = calloc(1, sizeof *header);
    ENSURE(header != NULL && wx_exr_read_header(path, header, &err) == WX_OK);
    bool layer1 = false;
    for (int c = 0; c < header->channel_count; ++c) {
        layer1 |= strcmp(header->channel_names[c], "layer1." WX_INITIAL_DIRT_CHANNEL) == 0;
    }
    free(header);
    ENSURE(layer1);
    ENSURE(vw_world_parse(&again, &settings, &err) == WX_OK);
    ENSURE(!vw_world_needs_bake(&again, &w));
    ENSURE(vw_world_finish(&again, &settings, &err) == WX_OK);
    ENSURE(again.max_layers == 2 && again.point_count == 112);
    ENSURE(wrong_layered_deposits(&again) == 0);
    vw_world_free(&again);
    vw_world_free(&w);
}

// --- G gathers from memory ------------------------------------------------------------

// Bytes of the file at `path` in *data (the caller frees it), its size in
// *size; false when it cannot be read.
static bool read_bytes(const char *path, unsigned char **data, size_t *size)
{
    FILE *f = fopen(path, "rb");
    *data = NULL;
    *size = 0;
    if (f == NULL) {
        return false;
    }
    size_t cap = 0;
    bool ok = true;
    for (;;) {
        if (*size == cap) {
            cap = cap > 0 ? 2 * cap : 65536;
            unsigned char *grown = realloc(*data, cap);
            if (grown == NULL) {
                ok = false;
                break;
            }
            *data = grown;
        }
        size_t n = fread(*data + *size, 1, cap - *size, f);
        *size += n;
        if (n == 0) {
            break;
        }
    }
    fclose(f);
    return ok;
}

// Files of folder `b` that differ from (or are missing in) folder `a`, and how
// many were compared; -1 when `b` cannot be listed.
static int different_files(const char *a, const char *b, int *compared)
{
    DIR *dir = opendir(b);
    if (dir == NULL) {
        return -1;
    }
    int differ = 0;
    *compared = 0;
    struct dirent *e;
    while ((e = readdir(dir)) != NULL) {
        if (e->d_name[0] == '.') {
            continue;
        }
        char pa[8400], pb[8400];
        snprintf(pa, sizeof pa, "%s/%s", a, e->d_name);
        snprintf(pb, sizeof pb, "%s/%s", b, e->d_name);
        unsigned char *da = NULL, *db = NULL;
        size_t na, nb;
        bool same = read_bytes(pa, &da, &na) && read_bytes(pb, &db, &nb) && na == nb &&
                    memcmp(da, db, na) == 0;
        free(da);
        free(db);
        if (!same) {
            fprintf(stderr, "        %s differs from %s\n", pb, pa);
        }
        differ += !same;
        (*compared)++;
    }
    closedir(dir);
    return differ;
}

// The world of `settings` after 20 steps, saved twice: by files (the dirt maps
// written, then wx_gather_scene reading them back) into <tmp>/<name>_files,
// and by G (vw_world_gather: the dirt maps written, the mask gathered from the
// simulation in memory) into <tmp>/<name>_memory. Returns the files of the
// second that differ from the first (-1: a step failed); `compared` counts
// them.
static int gather_both_ways(const vw_settings *settings, const char *name, int *compared)
{
    static vw_world w;
    wx_error err = { 0 };
    bool ok =
        vw_world_parse(&w, settings, &err) == WX_OK && vw_world_finish(&w, settings, &err) == WX_OK;
    for (int s = 0; ok && s < 20; ++s) {
        ok = wx_sim_step(w.sim, &err) == WX_OK;
    }
    // Outputs in folders of their own: the baked maps stay where they are.
    char files[2048], memory[2048], saved[WX_PATH_MAX];
    snprintf(files, sizeof files, "%s/%s_files", ensure_tmpdir(), name);
    snprintf(memory, sizeof memory, "%s/%s_memory", ensure_tmpdir(), name);
    snprintf(w.opts.out_dir, sizeof w.opts.out_dir, "%s", files);
    ok = ok && wx_output_prepare(&w.scene, &w.opts, NULL, &err) == WX_OK &&
         wx_write_dirt_maps(&w.scene, &w.opts, w.sim, w.maps, &err) == WX_OK &&
         wx_gather_scene(&w.scene, &w.opts, &err) == WX_OK;
    snprintf(w.opts.out_dir, sizeof w.opts.out_dir, "%s", memory);
    ok = ok && vw_world_gather(&w, saved, &err) == WX_OK;
    if (!ok) {
        fprintf(stderr, "        %s: %s\n", name, err.message);
    }
    vw_world_free(&w);
    return ok ? different_files(files, memory, compared) : -1;
}

// The output camera's maps of layered_scene_with_output: 8 x 8 texels of
// depth 7 with normal -y (from below, the face at y = 2 is 7 away).
static bool write_output_maps(const char *dir)
{
    static const char *const kinds[2] = { "depth", "normal" };
    static const char *const rgb[3] = { "R", "G", "B" };
    for (int k = 0; k < 2; ++k) {
        wx_image file;
        if (wx_image_alloc(&file, 8, 8, k == 0 ? 1 : 3, rgb, NULL) != WX_OK) {
            return false;
        }
        for (int t = 0; t < 64; ++t) {
            if (k == 0) {
                file.channels[0][t] = 7.0f;
            } else {
                file.channels[0][t] = file.channels[2][t] = 0.0f;
                file.channels[1][t] = -1.0f;
            }
        }
        char path[4400];
        snprintf(path, sizeof path, "%s/o_%s.exr", dir, kinds[k]);
        bool ok = wx_exr_write(path, &file, NULL) == WX_OK;
        wx_image_free(&file);
        if (!ok) {
            return false;
        }
    }
    return true;
}

// The layered fixture (layered_scene) with an output camera "o" below, which
// sees the back face of a's layer 1 (y = 2, its normal -y), and the maps
// written by hand into `out_dir`.
static const char *layered_scene_with_output(char out_dir[4200])
{
    const char *tmp = ensure_tmpdir();
    const char *mesh =
        ensure_write_file(tmp, "layered.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const char *scene = ensure_write_file(
        tmp, "layered_output.xml",
        "<Weathering>\n"
        "  <Emitters><PointEmitter centerY=\"2\" rate=\"2000\"/></Emitters>\n"
        "  <Collider><ProjectedMaps>\n"
        "    <Ortho cameraName=\"a\" layers=\"2\">\n"
        "      <View eye=\"0 5 0\" target=\"0 0 0\" up=\"0 0 -1\" width=\"2\" height=\"2\"\n"
        "            resolution=\"8\"/>\n"
        "    </Ortho>\n"
        "    <Ortho cameraName=\"b\">\n"
        "      <View eye=\"0 0 5\" target=\"0 0 0\" up=\"0 1 0\" width=\"2\" height=\"2\"\n"
        "            resolution=\"4\"/>\n"
        "    </Ortho>\n"
        "    <Ortho cameraName=\"o\" out=\"true\">\n"
        "      <View eye=\"0 -5 0\" target=\"0 0 0\" up=\"0 0 1\" width=\"2\" height=\"2\"\n"
        "            resolution=\"8\"/>\n"
        "      <OutputMap file=\"o_mask.exr\" width=\"8\" height=\"8\" radius=\"0\"/>\n"
        "    </Ortho>\n"
        "  </ProjectedMaps></Collider>\n"
        "  <Geometry><Mesh file=\"layered.obj\"><Surface material=\"*\"/></Mesh></Geometry>\n"
        "</Weathering>\n");
    snprintf(out_dir, 4200, "%s/layered_output_out", tmp);
    mkdir(out_dir, 0777);
    if (mesh == NULL || scene == NULL || !write_layered_maps(out_dir, "a", 8, 2) ||
        !write_layered_maps(out_dir, "b", 4, 1) || !write_output_maps(out_dir)) {
        return NULL;
    }
    time_t now = time(NULL);
    set_mtime(scene, now - 100);
    set_mtime(mesh, now - 100);
    return scene;
}

// G gathers from the simulation in memory (wx_gather_simulation), not from the
// dirt maps it has just written: every file it saves (dirt maps, mask,
// previews) is the same bytes as the dirt maps and wx_gather_scene's gather of
// them, for the thesis scene, with substances, with derived masks and with a
// layered camera (the output camera sees the back face of its layer 1).
TEST(gather_from_memory_is_the_gather_from_files)
{
    vw_settings settings = thesis_settings();
    int compared = 0;
    ENSURE(gather_both_ways(&settings, "gather_thesis", &compared) == 0);
    ENSURE(compared == 4); // front and top's dirt maps, the mask, its preview
    settings.scene_path = substance_scene();
    ENSURE(settings.scene_path != NULL);
    ENSURE(gather_both_ways(&settings, "gather_substances", &compared) == 0);
    ENSURE(compared >= 4);
    settings.scene_path = mask_scene();
    ENSURE(settings.scene_path != NULL);
    ENSURE(gather_both_ways(&settings, "gather_masks", &compared) == 0);
    ENSURE(compared >= 4);
    char out_dir[4200];
    vw_settings layered = { .out_dir = out_dir, .threads = 1, .hit_capacity = 64 };
    layered.scene_path = layered_scene_with_output(out_dir);
    ENSURE(layered.scene_path != NULL);
    ENSURE(gather_both_ways(&layered, "gather_layered", &compared) == 0);
    ENSURE(compared == 4); // a's and b's dirt maps, the mask, its preview
}

int main(void)
{
    RUN(thesis_scene_geometry);
    RUN(maps_are_baked_again_when_needed);
    RUN(nearest_point_per_pixel_in_tile_order);
    RUN(initial_view_frames_the_box);
    RUN(one_substance_is_dirt);
    RUN(substances_cycle_and_colour_by_the_shown_one);
    RUN(masks_cycle_and_colour_the_depth_samples);
    RUN(masks_at_sparse_samples);
    RUN(layers_cycle_and_samples_name_their_views);
    RUN(gather_from_memory_is_the_gather_from_files);
    RUN(bad_usage_exits_2);
    RUN(bad_scene_exits_2_and_names_the_file);
    RUN(failed_bake_exits_2);
    RUN(screenshot_shows_cameras_and_particles);
    RUN(screenshot_is_reproducible);
    RUN(screenshot_shows_the_chosen_substance);
    RUN(screenshot_shows_the_chosen_mask);
    return ensure_summary();
}
