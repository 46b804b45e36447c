// test_viewer.c: weathering-viewer.
//
// The program under a virtual display (xvfb-run -a): a screenshot of the
// thesis scene after 30 frames must be the window's size, show both input
// cameras in their colours and the particles, and come out the same on every
// run; bad input gives exit status 2 and names the file, without any display.
//
// The viewer's GL-free parts are compiled in here and checked against numbers
// worked out by hand: the geometry drawn for the thesis scene, when maps must
// be baked again, the nearest-point-per-pixel filter and the initial view.
#include <fcntl.h>
#include <png.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "../viewer/palette.h"
#include "../viewer/points.c"
#include "../viewer/view.c"
#include "../viewer/world.c"
#include "ensure.h"
#include "model/camera.h"
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

// Runs the viewer on the thesis scene for `frames` frames and saves `png`.
static int screenshot(const char *png, int frames)
{
    const char *tmp = ensure_tmpdir();
    return ensure_shell(out, sizeof out,
                        "xvfb-run -a %s/weathering-viewer xml_scenes/thesis_box.xml --out %s/out "
                        "--screenshot %s/%s --frames %d",
                        ensure_build_dir(), tmp, tmp, png, frames);
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

int main(void)
{
    RUN(thesis_scene_geometry);
    RUN(maps_are_baked_again_when_needed);
    RUN(nearest_point_per_pixel_in_tile_order);
    RUN(initial_view_frames_the_box);
    RUN(bad_usage_exits_2);
    RUN(bad_scene_exits_2_and_names_the_file);
    RUN(failed_bake_exits_2);
    RUN(screenshot_shows_cameras_and_particles);
    RUN(screenshot_is_reproducible);
    return ensure_summary();
}
