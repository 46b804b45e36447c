// test_gather.c: the gather and the mask file (docs/design.md section 5), on scenes of
// flat quads rendered here by a tiny orthographic ray caster; expected values
// are worked out by hand in the comments.
#include <math.h>
#include <png.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "model/camera.h"
#include "ensure.h"
#include "io/exr.h"
#include "gather/gather.h"
#include "io/png_preview.h"
#include "core/limits.h"
#include "core/matrix.h"
#include "model/image.h"
#include "pipeline/gather_phase.h"
#include "pipeline/pipeline.h"

#define PI 3.14159265358979323846

// ---------------------------------------------------------------------------
// Test scenes: quads c + s*a + t*b (|s|, |t| <= 1, a and b orthogonal) with an
// outward unit normal n.

typedef struct quad {
    double c[3], a[3], b[3], n[3];
} quad;

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// Maps of one camera, owned by the test.
typedef struct test_maps {
    wx_camera cam;
    int w, h;
    float *depth, *normal, *dirt;
} test_maps;

static void maps_free(test_maps *m)
{
    free(m->depth);
    free(m->normal);
    free(m->dirt);
    memset(m, 0, sizeof *m);
}

static wx_camera make_camera(float ex, float ey, float ez, float tx, float ty, float tz, float ux,
                             float uy, float uz, float w_ws, float h_ws, int w_px, int h_px)
{
    wx_view view = { .eye = { ex, ey, ez }, .target = { tx, ty, tz }, .up = { ux, uy, uz },
                     .width_ws = w_ws, .height_ws = h_ws, .width_px = w_px, .height_px = h_px };
    wx_camera cam;
    memset(&cam, 0, sizeof cam);
    if (wx_camera_from_view(&view, &cam, NULL) != WX_OK) {
        abort();
    }
    return cam;
}

// World point where texel (i, j)'s ray starts (d = 0) and the ray direction.
static void texel_ray(const wx_camera *cam, int i, int j, double o[3], double dir[3])
{
    float u, v, uvd[3], p[3], vd[3];
    wx_map_texel_center(cam->width, cam->height, i, j, &u, &v);
    uvd[0] = u, uvd[1] = v, uvd[2] = 0.0f;
    wx_camera_map_to_world(cam, uvd, p);
    wx_camera_view_dir(cam, vd);
    for (int k = 0; k < 3; ++k) {
        o[k] = p[k];
        dir[k] = vd[k];
    }
}

// Renders depth and normal of the quads; dirt = density(point) * head-on texel
// area / max(|N.view|, 1e-3), the amount `bake` stores (docs/design.md section 3).
typedef double (*density_fn)(const double p[3], int quad_index);

static test_maps render(wx_camera cam, const quad *quads, int count, density_fn density)
{
    test_maps m;
    memset(&m, 0, sizeof m);
    m.cam = cam;
    m.w = cam.width;
    m.h = cam.height;
    size_t n = (size_t)m.w * (size_t)m.h;
    m.depth = malloc(n * sizeof(float));
    m.normal = calloc(3 * n, sizeof(float));
    m.dirt = calloc(n, sizeof(float));
    float wws, hws;
    wx_camera_frame_size(&cam, &wws, &hws);
    double head_area = (double)wws / m.w * (double)hws / m.h;
    for (int j = 0; j < m.h; ++j) {
        for (int i = 0; i < m.w; ++i) {
            size_t t = (size_t)j * m.w + i;
            double o[3], dir[3];
            texel_ray(&cam, i, j, o, dir);
            double best = INFINITY;
            int hit = -1;
            for (int q = 0; q < count; ++q) {
                double denom = dot3(dir, quads[q].n);
                if (fabs(denom) < 1e-12) {
                    continue;
                }
                double oc[3] = { quads[q].c[0] - o[0], quads[q].c[1] - o[1], quads[q].c[2] - o[2] };
                double tt = dot3(oc, quads[q].n) / denom;
                double p[3] = { o[0] + tt * dir[0] - quads[q].c[0],
                                o[1] + tt * dir[1] - quads[q].c[1],
                                o[2] + tt * dir[2] - quads[q].c[2] };
                double s = dot3(p, quads[q].a) / dot3(quads[q].a, quads[q].a);
                double r = dot3(p, quads[q].b) / dot3(quads[q].b, quads[q].b);
                if (tt > 0.0 && tt < best && fabs(s) <= 1.0 && fabs(r) <= 1.0) {
                    best = tt;
                    hit = q;
                }
            }
            m.depth[t] = (float)best;
            if (hit >= 0) {
                double cosv = fabs(dot3(dir, quads[hit].n));
                double p[3] = { o[0] + best * dir[0], o[1] + best * dir[1], o[2] + best * dir[2] };
                for (int k = 0; k < 3; ++k) {
                    m.normal[3 * t + k] = (float)quads[hit].n[k];
                }
                if (density != NULL) {
                    m.dirt[t] = (float)(density(p, hit) * head_area / fmax(cosv, 1e-3));
                }
            }
        }
    }
    return m;
}

static wx_gather_view view_of(const test_maps *m)
{
    wx_gather_view v = { .camera = &m->cam, .width = m->w, .height = m->h, .depth = m->depth,
                         .normal = m->normal, .dirt = m->dirt };
    return v;
}

static wx_target target_of(const test_maps *m)
{
    wx_target t = { .kind = WX_TARGET_CAMERA, .camera = &m->cam, .width = m->w, .height = m->h,
                    .depth = m->depth, .normal = m->normal };
    return t;
}

static quad make_quad(double cx, double cy, double cz, double ax, double ay, double az, double bx,
                      double by, double bz, double nx, double ny, double nz)
{
    quad q = { { cx, cy, cz }, { ax, ay, az }, { bx, by, bz }, { nx, ny, nz } };
    return q;
}

// The front camera of several tests: eye at z = 10 looking at -z, 4 x 2 m,
// 8 x 4 texels of 0.5 x 0.5 m (area 0.25 m^2).
static wx_camera front_camera(void)
{
    return make_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 4, 2, 8, 4);
}

// A wall z = 0 facing +z, larger than every frame used with it.
static quad big_wall(void)
{
    return make_quad(0, 0, 0, 20, 0, 0, 0, 20, 0, 0, 0, 1);
}

static float *run_gather(const test_maps *out, const test_maps *inputs, int count, float radius,
                         wx_second_pass mode, wx_gather_sampling sampling, int threads)
{
    wx_gather_view views[8];
    for (int k = 0; k < count; ++k) {
        views[k] = view_of(&inputs[k]);
    }
    wx_gather_def def = wx_default_gather_def();
    def.target = target_of(out);
    def.inputs = views;
    def.input_count = count;
    def.radius = radius;
    def.second_pass = mode;
    def.sampling = sampling;
    def.threads = threads;
    float *mask = malloc((size_t)out->w * out->h * sizeof(float));
    wx_error err;
    if (wx_gather_compute(&def, mask, NULL, &err) != WX_OK) {
        fprintf(stderr, "gather failed: %s\n", err.message);
        free(mask);
        return NULL;
    }
    return mask;
}

// ---------------------------------------------------------------------------
// First pass.

TEST(same_camera_gives_dirt_over_texel_area)
{
    quad wall = big_wall();
    test_maps in = render(front_camera(), &wall, 1, NULL);
    test_maps out = render(front_camera(), &wall, 1, NULL);
    // Spikes of dirt: texel (3, 1) holds 1.0, texel (6, 2) holds 0.3.
    in.dirt[1 * 8 + 3] = 1.0f;
    in.dirt[2 * 8 + 6] = 0.3f;
    for (int s = 0; s < 2; ++s) {
        wx_gather_sampling sampling = s == 0 ? WX_GATHER_NEAREST : WX_GATHER_BILINEAR;
        float *mask = run_gather(&out, &in, 1, 0.0f, WX_SECOND_PASS_MEAN, sampling, 1);
        ENSURE(mask != NULL);
        // 1.0 / 0.25 m^2 = 4 per m^2; 0.3 / 0.25 = 1.2; 0 elsewhere.
        double worst = 0.0;
        for (int t = 0; t < 32; ++t) {
            double expected = t == 1 * 8 + 3 ? 4.0 : t == 2 * 8 + 6 ? 1.2 : 0.0;
            worst = fmax(worst, fabs(mask[t] - expected));
        }
        free(mask);
        ENSURE(worst <= 1e-5);
    }
    maps_free(&in);
    maps_free(&out);
}

static double slope_density(const double p[3], int q)
{
    (void)q;
    return 2.0 + 0.5 * p[0]; // varies across the surface; 2 per m^2 at x = 0
}

TEST(tilted_surface_divides_by_its_footprint)
{
    // A plane through the origin tilted 60 degrees about the y axis: normal
    // (sin 60, 0, cos 60), seen by the front camera at |N.view| = 1/2. A texel of
    // 0.25 m^2 covers 0.5 m^2 of it, so 1.0 of dirt is 2 per m^2.
    double s60 = sqrt(3.0) / 2.0;
    quad plane = make_quad(0, 0, 0, 10 * 0.5, 0, -10 * s60, 0, 10, 0, s60, 0, 0.5);
    test_maps in = render(front_camera(), &plane, 1, NULL);
    test_maps out = render(front_camera(), &plane, 1, NULL);
    in.dirt[1 * 8 + 5] = 1.0f;
    float *mask = run_gather(&out, &in, 1, 0.0f, WX_SECOND_PASS_MEAN, WX_GATHER_NEAREST, 1);
    ENSURE(mask != NULL);
    ENSURE_NEAR(mask[1 * 8 + 5], 2.0, 1e-5);
    ENSURE_NEAR(mask[1 * 8 + 4], 0.0, 1e-9);
    free(mask);
    maps_free(&in);
    maps_free(&out);
    // Nearly edge-on, |N.view| = 0.05: a texel covers 0.25 / 0.05 = 5 m^2, so
    // 1.0 of dirt is 0.2 per m^2 (the footprint is not clamped at 0.1).
    double c = 0.05, s = sqrt(1.0 - c * c);
    plane = make_quad(0, 0, 0, 100 * c, 0, -100 * s, 0, 10, 0, s, 0, c); // depth 10 - 20 x
    in = render(front_camera(), &plane, 1, NULL);
    out = render(front_camera(), &plane, 1, NULL);
    in.dirt[1 * 8 + 4] = 1.0f; // x = 0.25, depth 15
    mask = run_gather(&out, &in, 1, 0.0f, WX_SECOND_PASS_MEAN, WX_GATHER_NEAREST, 1);
    ENSURE(mask != NULL);
    ENSURE_NEAR(mask[1 * 8 + 4], 0.2, 1e-5);
    free(mask);
    maps_free(&in);
    maps_free(&out);
}

TEST(oblique_input_camera_recovers_density)
{
    // Dirt of density 2 + x/2 per m^2 baked by a camera 40 degrees off the
    // wall's normal; the front output camera reads the density back at each
    // texel centre (linear density, bilinear taps: exact up to rounding).
    quad wall = big_wall();
    float a = 40.0f * (float)PI / 180.0f;
    test_maps in =
        render(make_camera(10 * sinf(a), 0, 10 * cosf(a), 0, 0, 0, 0, 1, 0, 8, 6, 64, 48), &wall, 1,
               slope_density);
    test_maps out = render(make_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 4, 2, 16, 8), &wall, 1, NULL);
    float *mask = run_gather(&out, &in, 1, 0.0f, WX_SECOND_PASS_MEAN, WX_GATHER_BILINEAR, 1);
    ENSURE(mask != NULL);
    for (int j = 0; j < 8; ++j) {
        for (int i = 0; i < 16; ++i) {
            double x = -2.0 + (i + 0.5) * 0.25;
            ENSURE_NEAR(mask[j * 16 + i], 2.0 + 0.5 * x, 1e-4);
        }
    }
    free(mask);
    maps_free(&in);
    maps_free(&out);
}

// ---------------------------------------------------------------------------
// Visibility.

static double unit_density(const double p[3], int q)
{
    (void)p;
    (void)q;
    return 1.0;
}

static quad box_faces[6];

static int make_box(double hx, double hy, double hz)
{
    box_faces[0] = make_quad(0, 0, hz, hx, 0, 0, 0, hy, 0, 0, 0, 1);   // front
    box_faces[1] = make_quad(0, 0, -hz, hx, 0, 0, 0, hy, 0, 0, 0, -1); // back
    box_faces[2] = make_quad(hx, 0, 0, 0, 0, hz, 0, hy, 0, 1, 0, 0);
    box_faces[3] = make_quad(-hx, 0, 0, 0, 0, hz, 0, hy, 0, -1, 0, 0);
    box_faces[4] = make_quad(0, hy, 0, hx, 0, 0, 0, 0, hz, 0, 1, 0);
    box_faces[5] = make_quad(0, -hy, 0, hx, 0, 0, 0, 0, hz, 0, -1, 0);
    return 6;
}

TEST(dirt_on_the_back_of_a_box_does_not_show_from_the_front)
{
    for (int thin = 0; thin < 2; ++thin) {
        // A 2 x 2 x 2 box, then a 2 x 2 x 0.1 slab (thinner than a texel of 0.25 m).
        int count = make_box(1, 1, thin ? 0.05 : 1);
        wx_camera front = make_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 4, 4, 16, 16);
        wx_camera back = make_camera(0, 0, -10, 0, 0, 0, 0, 1, 0, 4, 4, 16, 16);
        test_maps inputs[2] = { render(front, box_faces, count, NULL),
                                render(back, box_faces, count, unit_density) };
        test_maps out = render(front, box_faces, count, NULL);
        float *mask = run_gather(&out, inputs, 2, 0.0f, WX_SECOND_PASS_MEAN, WX_GATHER_BILINEAR, 1);
        ENSURE(mask != NULL);
        int front_texels = 0, dirty = 0;
        for (int t = 0; t < 256; ++t) {
            front_texels += !wx_depth_is_empty(out.depth[t]);
            dirty += mask[t] != 0.0f;
        }
        free(mask);
        ENSURE(front_texels == 64); // the 2 x 2 m front face: 8 x 8 texels
        ENSURE(dirty == 0);
        // Control: seen from the back, the same dirt is there, 1 per m^2.
        test_maps back_out = render(back, box_faces, count, NULL);
        mask = run_gather(&back_out, inputs, 2, 0.0f, WX_SECOND_PASS_MEAN, WX_GATHER_BILINEAR, 1);
        ENSURE(mask != NULL);
        ENSURE_NEAR(mask[8 * 16 + 8], 1.0, 1e-5);
        free(mask);
        maps_free(&back_out);
        maps_free(&inputs[0]);
        maps_free(&inputs[1]);
        maps_free(&out);
    }
}

static double plate_only(const double p[3], int q)
{
    (void)p;
    return q == 0 ? 1.0 : 0.0;
}

TEST(occluder_with_the_same_normal_does_not_bleed)
{
    // A plate z = 1, x, y in [-1, 1] in front of the wall z = 0, both facing +z,
    // dirt on the plate only. The input camera looks along (-1, 0, -1)/sqrt 2:
    // the plate hides the wall for x in [-2, 0]. The front camera sees the wall
    // at x in [-2, -1), whose points the input camera sees as plate: the depths
    // differ by sqrt 2 along its ray, so nothing is taken there.
    quad scene[2] = { make_quad(0, 0, 1, 1, 0, 0, 0, 1, 0, 0, 0, 1), big_wall() };
    test_maps in = render(make_camera(10, 0, 10, 0, 0, 0, 0, 1, 0, 8, 4, 64, 32), scene, 2,
                          plate_only);
    test_maps out = render(make_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 6, 2, 24, 8), scene, 2, NULL);
    float *mask = run_gather(&out, &in, 1, 0.0f, WX_SECOND_PASS_MEAN, WX_GATHER_BILINEAR, 1);
    ENSURE(mask != NULL);
    // Texel width 0.25 m: column i covers x in [-3 + i/4, -3 + (i+1)/4].
    for (int j = 1; j < 7; ++j) {
        for (int i = 0; i < 24; ++i) {
            double x = -3.0 + (i + 0.5) * 0.25;
            if (x > -0.8 && x < 0.8) {
                ENSURE_NEAR(mask[j * 24 + i], 1.0, 1e-5); // on the plate, away from its edges
            } else if (x < -1.0) {
                ENSURE(mask[j * 24 + i] == 0.0f); // wall, behind the plate for the input
            }
        }
    }
    free(mask);
    maps_free(&in);
    maps_free(&out);
}

// ---------------------------------------------------------------------------
// Second pass.

static double left_face(const double p[3], int q)
{
    (void)p;
    return q == 0 ? 3.0 : 0.0;
}

TEST(crease_is_not_blurred_across)
{
    // A ridge along y seen from +z, faces at angle a to the image plane: face 0
    // for x <= 0 with normal (-sin a, 0, cos a), face 1 for x >= 0 with normal
    // (sin a, 0, cos a); Nq.Np = cos 2a: 0 for a = 45 degrees (a right-angled
    // crease), -1/2 for a = 60. Dirt of 3 per m^2 on face 0 only, radius 0.4 m
    // (4 texels across the image): face 1 stays 0 and face 0 keeps exactly 3 (its
    // weighted mean takes nothing from face 1).
    const double angles[2] = { 45.0, 60.0 };
    for (int k = 0; k < 2; ++k) {
        double a = angles[k] * PI / 180.0, c = 2.0 * cos(a), s = 2.0 * sin(a);
        quad ridge[2] = { make_quad(-c, 0, -s, c, 0, s, 0, 5, 0, -sin(a), 0, cos(a)),
                          make_quad(c, 0, -s, c, 0, -s, 0, 5, 0, sin(a), 0, cos(a)) };
        wx_camera cam = make_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 3.2f, 1.6f, 32, 16);
        test_maps in = render(cam, ridge, 2, left_face);
        test_maps out = render(cam, ridge, 2, NULL);
        float *mask = run_gather(&out, &in, 1, 0.4f, WX_SECOND_PASS_MEAN, WX_GATHER_BILINEAR, 2);
        ENSURE(mask != NULL);
        double worst_left = 0.0, worst_right = 0.0;
        for (int j = 0; j < 16; ++j) {
            for (int i = 0; i < 32; ++i) {
                float value = mask[j * 32 + i];
                if (i < 16) {
                    worst_left = fmax(worst_left, fabs(value - 3.0));
                } else {
                    worst_right = fmax(worst_right, fabs(value));
                }
            }
        }
        free(mask);
        maps_free(&in);
        maps_free(&out);
        ENSURE(worst_left <= 3e-5);
        ENSURE(worst_right == 0.0);
    }
}

TEST(depth_jump_is_not_blurred_across)
{
    // A plate z = 1 (x in [-1, 1]) in front of the wall, both facing +z; dirt
    // 1 per m^2 on the wall only. With a 0.6 m radius the wall texels next to the
    // plate are 1 m away in depth: the plate stays 0.
    quad scene[2] = { make_quad(0, 0, 1, 1, 0, 0, 0, 5, 0, 0, 0, 1), big_wall() };
    wx_camera cam = make_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 4, 2, 16, 8);
    test_maps in = render(cam, scene, 2, NULL);
    for (int t = 0; t < 128; ++t) {
        in.dirt[t] = in.depth[t] > 9.5f ? 0.0625f : 0.0f; // wall: 1 per m^2 x 0.0625 m^2
    }
    test_maps out = render(cam, scene, 2, NULL);
    float *mask = run_gather(&out, &in, 1, 0.6f, WX_SECOND_PASS_MEAN, WX_GATHER_NEAREST, 1);
    ENSURE(mask != NULL);
    for (int t = 0; t < 128; ++t) {
        ENSURE_NEAR(mask[t], out.depth[t] > 9.5f ? 1.0 : 0.0, 1e-6);
    }
    free(mask);
    maps_free(&in);
    maps_free(&out);
}

static double density_five(const double p[3], int q)
{
    (void)p;
    (void)q;
    return 5.0;
}

TEST(constant_field_stays_constant)
{
    // A plane through the origin with normal (0, sin 25, cos 25) (its depth
    // varies across the frame), constant density 5, seen by an input camera 35
    // degrees off-axis whose frame covers the output's. Radius 3.5 texels.
    double a = 25.0 * PI / 180.0;
    quad plane = make_quad(0, 0, 0, 30, 0, 0, 0, 30 * cos(a), -30 * sin(a), 0, sin(a), cos(a));
    float b = 35.0f * (float)PI / 180.0f;
    test_maps in =
        render(make_camera(0, 10 * sinf(b), 10 * cosf(b), 0, 0, 0, 0, 1, 0, 12, 12, 96, 96), &plane,
               1, density_five);
    test_maps out =
        render(make_camera(1, 0.5f, 10, 1, 0.5f, 0, 0, 1, 0, 4, 3, 40, 30), &plane, 1, NULL);
    for (int mode = 0; mode < 2; ++mode) {
        wx_gather_sampling sampling = mode == 0 ? WX_GATHER_BILINEAR : WX_GATHER_NEAREST;
        float *mask = run_gather(&out, &in, 1, 0.35f, WX_SECOND_PASS_MEAN, sampling, 2);
        ENSURE(mask != NULL);
        double worst = 0.0;
        for (int t = 0; t < 40 * 30; ++t) {
            worst = fmax(worst, fabs(mask[t] - 5.0));
        }
        free(mask);
        ENSURE(worst <= 5e-5); // 1e-5 relative, edges of the frame included
    }
    maps_free(&in);
    maps_free(&out);
}

TEST(thesis_sum_and_mean_of_a_spike)
{
    // Flat wall, front camera 8 x 4 texels of 0.5 m; texel (3, 1) holds 0.25, a
    // density of 1 per m^2; radius 1.25 m = 2.5 texels. Weights 1 - r/1.25:
    //   r = 0.5 (1 texel): 0.6     r = 0.7071 (diagonal): 0.434315
    //   r = 1.0 (2 texels): 0.2    r = 1.1180 (2, 1):     0.105573
    //   r = 1.4142 (2, 2): outside.
    quad wall = big_wall();
    test_maps in = render(front_camera(), &wall, 1, NULL);
    test_maps out = render(front_camera(), &wall, 1, NULL);
    in.dirt[1 * 8 + 3] = 0.25f;
    float *sum = run_gather(&out, &in, 1, 1.25f, WX_SECOND_PASS_SUM, WX_GATHER_NEAREST, 1);
    float *mean = run_gather(&out, &in, 1, 1.25f, WX_SECOND_PASS_MEAN, WX_GATHER_NEAREST, 1);
    ENSURE(sum != NULL && mean != NULL);
    ENSURE_NEAR(sum[1 * 8 + 3], 1.0, 1e-6);
    ENSURE_NEAR(sum[1 * 8 + 4], 0.6, 1e-6);
    ENSURE_NEAR(sum[2 * 8 + 4], 1.0 - sqrt(0.5) / 1.25, 1e-6);
    ENSURE_NEAR(sum[1 * 8 + 5], 0.2, 1e-6);
    ENSURE_NEAR(sum[3 * 8 + 4], 1.0 - sqrt(1.25) / 1.25, 1e-6); // (1, 2) away
    ENSURE_NEAR(sum[3 * 8 + 5], 0.0, 1e-9);                     // (2, 2) away
    // Mean at texel (5, 1), 2 texels right of the spike (weight 0.2, value 1).
    // Its neighbours within 2.5 texels, columns 3..7 and rows 0..3 in frame (row
    // -1 is not): self 1; (+-1, 0), (0, +-1): 4 x 0.6; diagonals 4 x 0.434315;
    // (+-2, 0), (0, +2): 3 x 0.2; (+-2, +-1), (+-1, +2): 6 x 0.105573.
    double w_sum =
        1 + 1.2 + 1.2 + 4 * (1 - sqrt(0.5) / 1.25) + 0.4 + 0.2 + 6 * (1 - sqrt(1.25) / 1.25);
    ENSURE_NEAR(mean[1 * 8 + 5], 0.2 / w_sum, 1e-6);
    free(sum);
    free(mean);
    maps_free(&in);
    maps_free(&out);
}

TEST(normalize_scales_the_maximum_to_one)
{
    quad wall = big_wall();
    test_maps in = render(front_camera(), &wall, 1, NULL);
    test_maps out = render(front_camera(), &wall, 1, NULL);
    in.dirt[1 * 8 + 3] = 0.5f; // 2 per m^2
    in.dirt[2 * 8 + 1] = 0.1f; // 0.4 per m^2
    wx_gather_view input = view_of(&in);
    wx_gather_def def = wx_default_gather_def();
    def.target = target_of(&out);
    def.inputs = &input;
    def.input_count = 1;
    def.normalize = true;
    def.sampling = WX_GATHER_NEAREST;
    float mask[32];
    wx_gather_stats stats;
    ENSURE(wx_gather_compute(&def, mask, &stats, NULL) == WX_OK);
    ENSURE_NEAR(stats.max_value, 2.0, 1e-6);
    ENSURE(stats.surface_texels == 32 && stats.dirty_texels == 2);
    ENSURE_NEAR(mask[1 * 8 + 3], 1.0, 1e-7);
    ENSURE_NEAR(mask[2 * 8 + 1], 0.2, 1e-7);
    maps_free(&in);
    maps_free(&out);
}

TEST(thread_count_does_not_change_the_mask)
{
    quad scene[2] = { make_quad(0, 0, 1, 1, 0, 0, 0, 1, 0, 0, 0, 1), big_wall() };
    test_maps in = render(make_camera(3, 4, 10, 0, 0, 0, 0, 1, 0, 8, 8, 50, 50), scene, 2,
                          slope_density);
    for (int t = 0; t < 2500; t += 7) {
        in.dirt[t] *= 3.0f; // some texture
    }
    test_maps out = render(make_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 6, 5, 61, 47), scene, 2, NULL);
    float *one = run_gather(&out, &in, 1, 0.3f, WX_SECOND_PASS_MEAN, WX_GATHER_BILINEAR, 1);
    float *three = run_gather(&out, &in, 1, 0.3f, WX_SECOND_PASS_MEAN, WX_GATHER_BILINEAR, 3);
    ENSURE(one != NULL && three != NULL);
    bool same = memcmp(one, three, 61 * 47 * sizeof(float)) == 0;
    free(one);
    free(three);
    ENSURE(same);
    maps_free(&in);
    maps_free(&out);
}

TEST(bad_definitions_are_refused)
{
    quad wall = big_wall();
    test_maps out = render(front_camera(), &wall, 1, NULL);
    wx_gather_def def = wx_default_gather_def();
    def.target = target_of(&out);
    float mask[32];
    wx_error err;
    def.radius = -1.0f;
    ENSURE(wx_gather_compute(&def, mask, NULL, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_VALUE);
    def.radius = 1e6f; // two million texels across
    ENSURE(wx_gather_compute(&def, mask, NULL, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_VALUE);
    ENSURE(ensure_contains(err.message, "radius"));
    def.radius = 0.0f;
    wx_camera persp = out.cam;
    persp.wtc[11] = 1.0f; // w depends on z: not orthographic
    def.target.camera = &persp;
    ENSURE(wx_gather_compute(&def, mask, NULL, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_CAMERA);
    ENSURE(ensure_contains(err.message, "orthographic"));
    def.target.camera = &out.cam;
    def.target.width = 9; // camera is 8 x 4
    wx_result r = wx_gather_compute(&def, mask, NULL, &err);
    maps_free(&out);
    ENSURE(r == WX_BAD_INPUT);
    ENSURE_CAUSE(err, MAP_SIZE);
}

// The neighbourhood a scene is checked against before any work: texels of 0.5 m,
// radius 1.2 m = 2.4 texels, so the offsets (di, dj) != 0 with di^2 + dj^2 < 5.76:
// 4 at distance 1, 4 at sqrt 2, 4 at 2 and 8 at sqrt 5, 20 in all.
TEST(radius_check_counts_the_neighbourhood)
{
    wx_camera cam = front_camera(); // 4 x 2 m at 8 x 4 texels
    wx_target target = { .kind = WX_TARGET_CAMERA, .camera = &cam, .width = 8, .height = 4 };
    int texels = -1;
    wx_error err = { 0 };
    ENSURE(wx_gather_check_radius(&target, 1.2f, &texels, &err) == WX_OK);
    ENSURE(texels == 20);
    ENSURE(wx_gather_check_radius(&target, 0.0f, &texels, &err) == WX_OK && texels == 0);
    // pi r^2 / 0.25 > 100000 from r = 89.2 m on.
    ENSURE(wx_gather_check_radius(&target, 100.0f, &texels, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_VALUE);
    ENSURE(ensure_contains(err.message, "radius 100 covers more than 100000 output texels"));
    ENSURE(wx_gather_check_radius(&target, 85.0f, &texels, &err) == WX_OK);
    ENSURE(texels > 90000 && texels <= 100000);
}

// ---------------------------------------------------------------------------
// Adaptive smoothing (no radius: gather/adaptive.h, docs/mask.md).

// A reproducible Poisson count of mean `mean` (Knuth's product of uniforms).
static int poisson(uint64_t *state, double mean)
{
    double limit = exp(-mean), product = 1.0;
    int k = -1;
    do {
        *state += 0x9e3779b97f4a7c15ull;
        uint64_t z = *state;
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        z ^= z >> 31;
        product *= (double)(z >> 11) * (1.0 / 9007199254740992.0);
        k++;
    } while (product > limit);
    return k;
}

// Impacts of one unit of dirt each: a Poisson count per texel of mean
// lambda(i, j) on the texels with a surface; dirt = initial + count, hits = count.
typedef double (*rate_fn)(int i, int j);

typedef struct simulated {
    float *initial, *hits;
} simulated;

static simulated simulate_hits(test_maps *in, rate_fn lambda, float initial, uint64_t seed)
{
    size_t n = (size_t)in->w * in->h;
    simulated sim = { calloc(n, sizeof(float)), calloc(n, sizeof(float)) };
    for (int j = 0; j < in->h; ++j) {
        for (int i = 0; i < in->w; ++i) {
            size_t t = (size_t)j * in->w + i;
            if (!isfinite(in->depth[t])) {
                continue;
            }
            int k = poisson(&seed, lambda(i, j));
            sim.initial[t] = initial;
            sim.hits[t] = (float)k;
            in->dirt[t] = initial + (float)k;
        }
    }
    return sim;
}

static float *run_adaptive(const test_maps *out, const test_maps *in, const simulated *sim,
                           float noise, float max_radius, int threads, wx_gather_stats *stats)
{
    wx_gather_view view = view_of(in);
    view.initial = sim != NULL ? sim->initial : NULL;
    view.hits = sim != NULL ? sim->hits : NULL;
    wx_gather_def def = wx_default_gather_def();
    def.target = target_of(out);
    def.inputs = &view;
    def.input_count = 1;
    def.adaptive = true;
    def.noise = noise;
    def.max_radius = max_radius;
    def.threads = threads;
    float *mask = malloc((size_t)out->w * out->h * sizeof(float));
    wx_error err;
    if (wx_gather_compute(&def, mask, stats, &err) != WX_OK) {
        fprintf(stderr, "gather failed: %s\n", err.message);
        free(mask);
        return NULL;
    }
    return mask;
}

// A 12.8 m wall seen head-on by a 128-texel camera: texels of 0.1 m (0.01 m^2).
static wx_camera wall_camera(void)
{
    return make_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 12.8f, 12.8f, 128, 128);
}

static double four_per_texel(int i, int j)
{
    (void)i;
    (void)j;
    return 4.0;
}

// With lambda impacts per texel the radius holds K = 1.5 / noise^2 impacts:
// h = sqrt(K / (pi lambda)) texels (noise 0.04: K = 937.5, h = 8.64 texels for
// lambda 4). The mean density (lambda / 0.01 m^2 = 400 per m^2) is kept, and
// the texel-to-texel scatter drops from 1/sqrt(lambda) = 50% to about the noise
// aimed at (the estimate's own: 1/sqrt(2/3 K) = 4.0%).
TEST(adaptive_noise_follows_the_impacts)
{
    quad wall = big_wall();
    test_maps in = render(wall_camera(), &wall, 1, NULL);
    test_maps out = render(wall_camera(), &wall, 1, NULL);
    simulated sim = simulate_hits(&in, four_per_texel, 0.0f, 7);
    wx_gather_stats st;
    float *mask = run_adaptive(&out, &in, &sim, 0.04f, 3.0f, 2, &st);
    ENSURE(mask != NULL);
    double sum = 0.0, sum2 = 0.0;
    int n = 0;
    for (int j = 16; j < 112; ++j) {
        for (int i = 16; i < 112; ++i) {
            sum += mask[j * 128 + i];
            sum2 += (double)mask[j * 128 + i] * mask[j * 128 + i];
            n++;
        }
    }
    double mean = sum / n, sd = sqrt(sum2 / n - mean * mean);
    free(mask);
    free(sim.initial);
    free(sim.hits);
    maps_free(&in);
    maps_free(&out);
    ENSURE_NEAR(st.target_hits, 937.5, 1e-3);
    ENSURE_NEAR(st.median_radius, 0.864, 0.04);
    ENSURE(st.capped_texels == 0);
    ENSURE_NEAR(mean, 400.0, 400.0 * 0.01);
    ENSURE(sd / mean > 0.025 && sd / mean < 0.055);
}

static double one_per_texel(int i, int j)
{
    (void)i;
    (void)j;
    return 1.0;
}

// Four times fewer impacts: twice the radius (sqrt(937.5 / pi) = 17.3 texels,
// 1.73 m), the same noise; with max_radius below the radius needed, the radius
// stops there and the texels are counted as capped.
TEST(adaptive_radius_doubles_for_a_quarter_of_the_impacts)
{
    quad wall = big_wall();
    test_maps in = render(wall_camera(), &wall, 1, NULL);
    test_maps out = render(wall_camera(), &wall, 1, NULL);
    simulated sim = simulate_hits(&in, one_per_texel, 0.0f, 8);
    wx_gather_stats wide, capped;
    float *a = run_adaptive(&out, &in, &sim, 0.04f, 3.0f, 2, &wide);
    float *b = run_adaptive(&out, &in, &sim, 0.04f, 1.0f, 2, &capped);
    ENSURE(a != NULL && b != NULL);
    double sum = 0.0, sum2 = 0.0;
    int n = 0;
    for (int j = 32; j < 96; ++j) {
        for (int i = 32; i < 96; ++i) {
            sum += a[j * 128 + i];
            sum2 += (double)a[j * 128 + i] * a[j * 128 + i];
            n++;
        }
    }
    double mean = sum / n, sd = sqrt(sum2 / n - mean * mean);
    free(a);
    free(b);
    free(sim.initial);
    free(sim.hits);
    maps_free(&in);
    maps_free(&out);
    ENSURE(wide.capped_texels < 128 * 128 / 50); // near the corners only
    ENSURE_NEAR(wide.median_radius, 1.727, 0.08);
    ENSURE_NEAR(mean, 100.0, 100.0 * 0.02);
    ENSURE(sd / mean > 0.025 && sd / mean < 0.055);
    ENSURE(capped.largest_radius <= 1.0 + 1e-6);
    ENSURE(capped.capped_texels > 128 * 128 / 2);
}

static double one_on_the_left_half(int i, int j)
{
    (void)j;
    return i < 64 ? 1.0 : 0.0;
}

// Capped means noisier than aimed at: a texel whose radius stops at max_radius
// with some impact inside it. The same wall with one impact per texel on its
// left half and none on the right, max_radius 1 m (10 texels): every texel of
// the left half is capped (sqrt(937.5 / pi) = 17.3 texels would be needed).
// The right half is not: beside the edge its texels are clean (an empty
// half-rectangle where their density would have put 12 impacts), and beyond
// 1 m no impact comes near them. Beyond 2 m (the reach of a capped kernel
// from the lit side) it is exactly 0. (Between the clean band and 2 m, the
// lit side's capped kernels leave a faint trace: docs/mask.md, "Adaptive
// smoothing", notes it.)
TEST(adaptive_counts_as_capped_only_what_impacts_reach)
{
    quad wall = big_wall();
    test_maps in = render(wall_camera(), &wall, 1, NULL);
    test_maps out = render(wall_camera(), &wall, 1, NULL);
    simulated sim = simulate_hits(&in, one_on_the_left_half, 0.0f, 9);
    wx_gather_stats st;
    float *mask = run_adaptive(&out, &in, &sim, 0.04f, 1.0f, 2, &st);
    ENSURE(mask != NULL);
    double far = 0.0, near = 0.0, lit = 0.0;
    for (int j = 0; mask != NULL && j < 128; ++j) {
        for (int i = 0; i < 128; ++i) {
            double v = fabs(mask[j * 128 + i]);
            if (i >= 64 + 20) {
                far = fmax(far, v); // beyond twice max_radius: no kernel reaches
            } else if (i >= 64 + 2) {
                near = fmax(near, v);
            } else if (i < 54 && j >= 10 && j < 118) {
                lit += v / (54.0 * 108.0);
            }
        }
    }
    printf("        lit half %.1f per texel; 2-20 texels right of the edge at most %.1f\n", lit,
           near);
    printf("        capped %lld of %lld texels (the left half: %d), far right at most %g\n",
           (long long)st.capped_texels, (long long)st.surface_texels, 128 * 64, far);
    ENSURE(st.capped_texels >= 128 * 64 && st.capped_texels <= 128 * 66);
    ENSURE(far == 0.0);
    free(mask);
    free(sim.initial);
    free(sim.hits);
    maps_free(&in);
    maps_free(&out);
}

// The dirt the bake gave (initial) is exact and is never smoothed: a map with
// a sharp pattern of initial dirt and no impacts comes out as the first pass,
// whatever the smoothing; and a map no simulation wrote (no initial, no hits
// planes) is exact the same way.
TEST(adaptive_keeps_the_initial_dirt_exact)
{
    quad wall = big_wall();
    test_maps in = render(wall_camera(), &wall, 1, NULL);
    test_maps out = render(wall_camera(), &wall, 1, NULL);
    simulated sim = { calloc(128 * 128, sizeof(float)), calloc(128 * 128, sizeof(float)) };
    for (size_t t = 0; t < 128 * 128; ++t) {
        in.dirt[t] = sim.initial[t] = (t / 128 + t % 128) % 7 == 0 ? 0.05f : 0.0f;
    }
    float *first = run_gather(&out, &in, 1, 0.0f, WX_SECOND_PASS_MEAN, WX_GATHER_BILINEAR, 1);
    float *a = run_adaptive(&out, &in, &sim, 0.04f, 3.0f, 2, NULL);
    float *b = run_adaptive(&out, &in, NULL, 0.04f, 3.0f, 2, NULL);
    ENSURE(first != NULL && a != NULL && b != NULL);
    bool same = memcmp(first, a, 128 * 128 * sizeof(float)) == 0 &&
                memcmp(first, b, 128 * 128 * sizeof(float)) == 0;
    free(first);
    free(a);
    free(b);
    free(sim.initial);
    free(sim.hits);
    maps_free(&in);
    maps_free(&out);
    ENSURE(same);
}

static double left_half_only(int i, int j)
{
    (void)j;
    return i < 64 ? 4.0 : 0.0;
}

// A shadow edge (rain on the left half of the wall only): the clean half stays
// clean beyond a texel or two of the edge, the lit half keeps its density up
// to the edge, and the rise takes a few texels, not the radius (8.6 texels).
TEST(adaptive_does_not_cross_a_shadow_edge)
{
    quad wall = big_wall();
    test_maps in = render(wall_camera(), &wall, 1, NULL);
    test_maps out = render(wall_camera(), &wall, 1, NULL);
    simulated sim = simulate_hits(&in, left_half_only, 0.0f, 9);
    float *mask = run_adaptive(&out, &in, &sim, 0.04f, 3.0f, 2, NULL);
    ENSURE(mask != NULL);
    double column[128] = { 0 };
    for (int j = 8; j < 120; ++j) {
        for (int i = 0; i < 128; ++i) {
            column[i] += mask[j * 128 + i] / 112.0;
        }
    }
    double clean_max = 0.0, lit = 0.0;
    for (int j = 0; j < 128; ++j) {
        for (int i = 67; i < 128; ++i) {
            clean_max = fmax(clean_max, mask[j * 128 + i]);
        }
    }
    for (int i = 16; i < 60; ++i) {
        lit += column[i] / 44.0;
    }
    int i10 = -1, i90 = -1; // the columns where the profile falls below 90% and 10%
    for (int i = 40; i < 90; ++i) {
        if (i90 < 0 && column[i] < 0.9 * lit) {
            i90 = i;
        }
        if (i10 < 0 && column[i] < 0.1 * lit) {
            i10 = i;
        }
    }
    free(mask);
    free(sim.initial);
    free(sim.hits);
    maps_free(&in);
    maps_free(&out);
    for (int i = 50; i < 70; ++i) {
        fprintf(stderr, " %d:%.0f", i, column[i]);
    }
    fprintf(stderr, "\n");
    ENSURE(clean_max == 0.0);
    ENSURE_NEAR(lit, 400.0, 400.0 * 0.02);
    ENSURE_NEAR(column[62], 400.0, 400.0 * 0.05); // two texels from the edge
    ENSURE(i90 >= 62 && i10 <= 66);
}

// What the particles left is kept: the mask integrates to the dirt (here over a
// density that rises across the wall) within 1%, and 1 or 2 threads give the
// same bytes.
static double rising(int i, int j)
{
    (void)j;
    return 0.5 + 6.0 * i / 127.0;
}

TEST(adaptive_keeps_the_dirt_and_its_bytes)
{
    quad wall = big_wall();
    test_maps in = render(wall_camera(), &wall, 1, NULL);
    test_maps out = render(wall_camera(), &wall, 1, NULL);
    simulated sim = simulate_hits(&in, rising, 0.0f, 10);
    double dirt = 0.0;
    for (size_t t = 0; t < 128 * 128; ++t) {
        dirt += in.dirt[t];
    }
    float *one = run_adaptive(&out, &in, &sim, 0.04f, 3.0f, 1, NULL);
    float *two = run_adaptive(&out, &in, &sim, 0.04f, 3.0f, 2, NULL);
    ENSURE(one != NULL && two != NULL);
    double integral = 0.0;
    for (size_t t = 0; t < 128 * 128; ++t) {
        integral += one[t] * 0.01; // per square metre times the texel's 0.01 m^2
    }
    bool same = memcmp(one, two, 128 * 128 * sizeof(float)) == 0;
    free(one);
    free(two);
    free(sim.initial);
    free(sim.hits);
    maps_free(&in);
    maps_free(&out);
    ENSURE(same);
    ENSURE_NEAR(integral / dirt, 1.0, 0.01);
}

static double everywhere(int i, int j)
{
    (void)i;
    (void)j;
    return 3.0;
}

// A right-angled ridge (normals at 90 degrees) with impacts on its left face
// only, and a plate 1 m in front of a wall with impacts on the wall only:
// neither the other face nor the plate gets anything.
TEST(adaptive_does_not_cross_creases_or_depth_jumps)
{
    double a = 45.0 * PI / 180.0, c = 2.0 * cos(a), s = 2.0 * sin(a);
    quad ridge[2] = { make_quad(-c, 0, -s, c, 0, s, 0, 5, 0, -sin(a), 0, cos(a)),
                      make_quad(c, 0, -s, c, 0, -s, 0, 5, 0, sin(a), 0, cos(a)) };
    quad plate[2] = { make_quad(0, 0, 1, 1, 0, 0, 0, 5, 0, 0, 0, 1), big_wall() };
    wx_camera cam = make_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 3.2f, 3.2f, 64, 64);
    for (int k = 0; k < 2; ++k) {
        test_maps in = render(cam, k == 0 ? ridge : plate, 2, NULL);
        test_maps out = render(cam, k == 0 ? ridge : plate, 2, NULL);
        simulated sim = simulate_hits(&in, everywhere, 0.0f, 11 + (uint64_t)k);
        for (int t = 0; t < 64 * 64; ++t) {
            // Keep the impacts on the left face, or on the wall (behind the plate).
            bool keep = k == 0 ? t % 64 < 32 : in.depth[t] > 9.5f;
            if (!keep) {
                in.dirt[t] = sim.hits[t] = 0.0f;
            }
        }
        float *mask = run_adaptive(&out, &in, &sim, 0.04f, 1.0f, 2, NULL);
        ENSURE(mask != NULL);
        double leak = 0.0;
        for (int t = 0; t < 64 * 64; ++t) {
            bool other = k == 0 ? t % 64 >= 32 : out.depth[t] < 9.5f;
            leak = other ? fmax(leak, mask[t]) : leak;
        }
        free(mask);
        free(sim.initial);
        free(sim.hits);
        maps_free(&in);
        maps_free(&out);
        ENSURE(leak == 0.0);
    }
}

// ---------------------------------------------------------------------------
// Header matrices.

TEST(world_to_camera_and_ndc)
{
    // Eye (3, 4, 5) looking at (-1, 0.5, 2): forward = (-4, -3.5, -3)/|.|.
    wx_view view = { .eye = { 3, 4, 5 }, .target = { -1, 0.5f, 2 }, .up = { 0, 1, 0 },
                     .width_ws = 6, .height_ws = 3, .width_px = 60, .height_px = 30 };
    wx_camera cam;
    ENSURE(wx_camera_from_view(&view, &cam, NULL) == WX_OK);
    float m[16], c[3];
    wx_mask_world_to_camera(&cam, m);
    ENSURE(wx_transform_point(m, view.eye, c));
    ENSURE_NEAR(c[0], 0.0, 1e-5);
    ENSURE_NEAR(c[1], 0.0, 1e-5);
    ENSURE_NEAR(c[2], 0.0, 1e-5);
    double len = sqrt(16 + 3.5 * 3.5 + 9);
    float ahead[3] = { (float)(3 - 4 / len), (float)(4 - 3.5 / len), (float)(5 - 3 / len) };
    ENSURE(wx_transform_point(m, ahead, c));
    ENSURE_NEAR(c[0], 0.0, 1e-5);
    ENSURE_NEAR(c[1], 0.0, 1e-5);
    ENSURE_NEAR(c[2], 1.0, 1e-5);
    // One metre to the image's right and half a metre up: x = 1, y = 0.5; NDC
    // x = u = 0.5 + 1/6, y = 1 - v = 0.5 - 0.5/3 (y points down).
    float dir[3];
    wx_camera_view_dir(&cam, dir);
    double right[3] = { dir[1] * 0 - dir[2] * 1, dir[2] * 0 - dir[0] * 0, dir[0] * 1 - dir[1] * 0 };
    double rl = sqrt(dot3(right, right));
    double fwd[3] = { dir[0], dir[1], dir[2] };
    double up[3] = { right[1] * fwd[2] - right[2] * fwd[1], right[2] * fwd[0] - right[0] * fwd[2],
                     right[0] * fwd[1] - right[1] * fwd[0] };
    float p[3];
    for (int k = 0; k < 3; ++k) {
        p[k] = (float)(view.eye[k] + right[k] / rl + 0.5 * up[k] / rl + 2.0 * fwd[k]);
    }
    ENSURE(wx_transform_point(m, p, c));
    ENSURE_NEAR(c[0], 1.0, 1e-5);
    ENSURE_NEAR(c[1], 0.5, 1e-5);
    ENSURE_NEAR(c[2], 2.0, 1e-5);
    wx_mask_world_to_ndc(&cam, m);
    ENSURE(wx_transform_point(m, p, c));
    ENSURE_NEAR(c[0], 0.5 + 1.0 / 6.0, 1e-6);
    ENSURE_NEAR(c[1], 0.5 - 0.5 / 3.0, 1e-6);
    ENSURE_NEAR(c[2], 2.0, 1e-5);
}

// ---------------------------------------------------------------------------
// The gather phase on files.

static wx_result write_maps(const char *dir, const char *name, const test_maps *m, bool dirt)
{
    char path[WX_PATH_MAX];
    wx_image img;
    wx_error err;
    size_t n = (size_t)m->w * m->h;
    static const char *const depth_names[] = { "R" };
    static const char *const rgb[] = { "R", "G", "B" };
    wx_result r = wx_image_alloc(&img, m->w, m->h, 1, depth_names, &err);
    if (r != WX_OK) {
        return r;
    }
    memcpy(img.channels[0], m->depth, n * sizeof(float));
    snprintf(path, sizeof path, "%s/%s_depth.exr", dir, name);
    r = wx_exr_write(path, &img, &err);
    wx_image_free(&img);
    if (r == WX_OK) {
        r = wx_image_alloc(&img, m->w, m->h, 3, rgb, &err);
    }
    if (r == WX_OK) {
        for (size_t t = 0; t < n; ++t) {
            for (int k = 0; k < 3; ++k) {
                img.channels[k][t] = m->normal[3 * t + k];
            }
        }
        snprintf(path, sizeof path, "%s/%s_normal.exr", dir, name);
        r = wx_exr_write(path, &img, &err);
        wx_image_free(&img);
    }
    if (r == WX_OK && dirt) {
        r = wx_image_alloc(&img, m->w, m->h, 3, rgb, &err);
        if (r == WX_OK) {
            memcpy(img.channels[0], m->dirt, n * sizeof(float));
            snprintf(path, sizeof path, "%s/%s_dirt.exr", dir, name);
            r = wx_exr_write(path, &img, &err);
            wx_image_free(&img);
        }
    }
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    return r;
}

static double patch_density(const double p[3], int q)
{
    (void)q;
    // 4 per m^2 in the rectangle x in [0.5, 1.5], y in [0, 0.8] of the wall.
    return p[0] > 0.5 && p[0] < 1.5 && p[1] > 0.0 && p[1] < 0.8 ? 4.0 : 0.0;
}

typedef struct file_scene {
    wx_scene scene;
    wx_scene_camera cams[2];
    wx_run_def opts;
    test_maps in, out;
    char dir[2048];
    char paths[6][WX_PATH_MAX]; ///< the maps' and the scene's paths the structs point at
} file_scene;

// Input camera "front" (maps in dir/maps, simulated dirt in dir/out unless
// `no_simulated`), output camera "out" looking 30 degrees from the side.
static bool make_file_scene(file_scene *fs, const char *tag, bool no_simulated)
{
    memset(fs, 0, sizeof *fs);
    snprintf(fs->dir, sizeof fs->dir, "%s/%s", ensure_tmpdir(), tag);
    char maps_dir[2100], out_dir[2100];
    snprintf(maps_dir, sizeof maps_dir, "%s/maps", fs->dir);
    snprintf(out_dir, sizeof out_dir, "%s/out", fs->dir);
    mkdir(fs->dir, 0777);
    mkdir(maps_dir, 0777);
    mkdir(out_dir, 0777);
    quad wall = big_wall();
    fs->in = render(make_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 6, 4, 60, 40), &wall, 1, patch_density);
    float a = 30.0f * (float)PI / 180.0f;
    fs->out = render(make_camera(-10 * sinf(a), 0, 10 * cosf(a), 0, 0, 0, 0, 1, 0, 4, 3, 40, 30),
                     &wall, 1, NULL);
    // The scene's own dirt map: clean when simulate's is there, so that reading
    // the wrong one shows.
    test_maps clean = fs->in;
    size_t n = (size_t)clean.w * clean.h;
    clean.dirt = calloc(n, sizeof(float));
    wx_result written = write_maps(maps_dir, "front", no_simulated ? &fs->in : &clean, true);
    free(clean.dirt);
    if (written != WX_OK || write_maps(maps_dir, "out", &fs->out, false) != WX_OK) {
        return false;
    }
    if (!no_simulated) {
        // `simulate` left a dirt map: the same dirt, in the output folder.
        if (write_maps(out_dir, "front", &fs->in, true) != WX_OK) {
            return false;
        }
        char path[WX_PATH_MAX];
        snprintf(path, sizeof path, "%s/front_depth.exr", out_dir);
        remove(path);
        snprintf(path, sizeof path, "%s/front_normal.exr", out_dir);
        remove(path);
    }
    wx_scene_camera *in = &fs->cams[0], *out = &fs->cams[1];
    snprintf(in->name, sizeof in->name, "front");
    in->camera = fs->in.cam;
    snprintf(fs->paths[0], WX_PATH_MAX, "%s/front_depth.exr", maps_dir);
    snprintf(fs->paths[1], WX_PATH_MAX, "%s/front_normal.exr", maps_dir);
    snprintf(fs->paths[2], WX_PATH_MAX, "%s/front_dirt.exr", maps_dir);
    in->depth_path = fs->paths[0];
    in->normal_path = fs->paths[1];
    in->dirt_path = fs->paths[2];
    snprintf(out->name, sizeof out->name, "out");
    out->is_output = true;
    out->camera = fs->out.cam;
    snprintf(fs->paths[3], WX_PATH_MAX, "%s/out_depth.exr", maps_dir);
    snprintf(fs->paths[4], WX_PATH_MAX, "%s/out_normal.exr", maps_dir);
    out->depth_path = fs->paths[3];
    out->normal_path = fs->paths[4];
    snprintf(out->output_file, sizeof out->output_file, "mask.exr");
    out->output_width = 40;
    out->output_height = 30;
    out->radius = 0.0f;
    snprintf(fs->paths[5], WX_PATH_MAX, "%s/scene.xml", fs->dir);
    fs->scene.path = fs->paths[5];
    fs->scene.cameras = fs->cams;
    fs->scene.camera_count = 2;
    fs->scene.input_count = 1;
    fs->scene.output_index = 1;
    snprintf(fs->opts.out_dir, WX_PATH_MAX, "%s", out_dir);
    fs->opts.threads = 2;
    fs->opts.quiet = true;
    return true;
}

static void free_file_scene(file_scene *fs)
{
    maps_free(&fs->in);
    maps_free(&fs->out);
}

TEST(mask_file_projects_world_points_onto_their_texel)
{
    file_scene fs;
    ENSURE(make_file_scene(&fs, "project", false));
    wx_error err;
    wx_result r = wx_gather_scene(&fs.scene, &fs.opts, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    char path[WX_PATH_MAX];
    snprintf(path, sizeof path, "%s/out/mask.exr", fs.dir);
    static const char *const y[] = { "Y" };
    wx_image img;
    ENSURE(wx_exr_read(path, y, 1, &img, &err) == WX_OK);
    ENSURE(img.width == 40 && img.height == 30);
    const wx_attr *ndc = wx_image_find_attr(&img, "worldToNDC");
    const wx_attr *wtc = wx_image_find_attr(&img, "WTCMatrix");
    const wx_attr *ctw = wx_image_find_attr(&img, "CTWMatrix");
    const wx_attr *w2c = wx_image_find_attr(&img, "worldToCamera");
    const wx_attr *name = wx_image_find_attr(&img, "cameraName");
    bool header_ok = ndc != NULL && ndc->type == WX_ATTR_M44F && wtc != NULL && ctw != NULL &&
                     w2c != NULL && name != NULL && strcmp(name->string, "out") == 0;
    bool wtc_ok = header_ok && memcmp(wtc->m44f, fs.out.cam.wtc, sizeof wtc->m44f) == 0 &&
                  memcmp(ctw->m44f, fs.out.cam.ctw, sizeof ctw->m44f) == 0;
    // World points on the wall: inside the dirty patch (1, 0.4, 0), (0.7, 0.55, 0)
    // and outside it (1, -0.4, 0) (its mirror image), (-1, 0.5, 0), (0.2, 0.4, 0).
    // An output texel spans 0.115 x 0.1 m of wall and bilinear taps reach one
    // input texel (0.1 m) further: each point is at least 0.2 m from an edge.
    const float points[5][3] = { { 1, 0.4f, 0 }, { 0.7f, 0.55f, 0 }, { 1, -0.4f, 0 },
                                 { -1, 0.5f, 0 }, { 0.2f, 0.4f, 0 } };
    const float expected[5] = { 4.0f, 4.0f, 0.0f, 0.0f, 0.0f };
    bool values_ok = header_ok;
    for (int k = 0; k < 5 && values_ok; ++k) {
        float ndc_p[3];
        values_ok = wx_transform_point(ndc->m44f, points[k], ndc_p);
        int i = (int)floorf(ndc_p[0] * 40.0f), j = (int)floorf(ndc_p[1] * 30.0f);
        values_ok = values_ok && i >= 0 && i < 40 && j >= 0 && j < 30;
        if (values_ok) {
            float value = img.channels[0][j * 40 + i];
            values_ok = fabsf(value - expected[k]) <= 1e-4f;
            if (!values_ok) {
                fprintf(stderr, "point %d: texel (%d, %d) holds %g, expected %g\n", k, i, j,
                        value, expected[k]);
            }
        }
    }
    wx_image_free(&img);
    free_file_scene(&fs);
    ENSURE(header_ok);
    ENSURE(wtc_ok);
    ENSURE(values_ok);
}

TEST(preview_png_decodes_with_the_mask_size)
{
    file_scene fs;
    ENSURE(make_file_scene(&fs, "preview", true)); // no simulated dirt: scene dirt map
    wx_error err;
    ENSURE(wx_gather_scene(&fs.scene, &fs.opts, &err) == WX_OK);
    char path[WX_PATH_MAX];
    snprintf(path, sizeof path, "%s/out/mask.png", fs.dir);
    png_image image;
    memset(&image, 0, sizeof image);
    image.version = PNG_IMAGE_VERSION;
    ENSURE(png_image_begin_read_from_file(&image, path) != 0);
    ENSURE(image.width == 40 && image.height == 30);
    image.format = PNG_FORMAT_GA;
    unsigned char *pixels = malloc(PNG_IMAGE_SIZE(image));
    ENSURE(png_image_finish_read(&image, NULL, pixels, 0, NULL) != 0);
    // Every texel sees the wall (opaque); the dirty patch is white (its value 4 is
    // the 99th percentile of the positive values), clean wall black.
    int white = 0, black = 0, transparent = 0;
    for (int t = 0; t < 40 * 30; ++t) {
        white += pixels[2 * t] == 255;
        black += pixels[2 * t] == 0;
        transparent += pixels[2 * t + 1] != 255;
    }
    free(pixels);
    free_file_scene(&fs);
    ENSURE(transparent == 0);
    ENSURE(white > 50 && black > 500);
}

TEST(preview_scale_is_the_99th_percentile)
{
    // 200 positive values 1..200 and zeros: element floor(0.99 * 199) = 197 of
    // the sorted values, i.e. 198.
    float values[300];
    for (int k = 0; k < 300; ++k) {
        values[k] = k < 100 ? 0.0f : (float)((k * 37) % 200 + 1);
    }
    float scale;
    ENSURE(wx_preview_scale(values, 300, &scale, NULL) == WX_OK);
    ENSURE(scale == 198.0f);
    ENSURE(wx_preview_scale(values, 100, &scale, NULL) == WX_OK);
    ENSURE(scale == 0.0f);
    // Preview of no surface anywhere: written, fully transparent.
    char path[WX_PATH_MAX];
    snprintf(path, sizeof path, "%s/empty.png", ensure_tmpdir());
    float depth[4] = { INFINITY, INFINITY, INFINITY, INFINITY };
    ENSURE(wx_preview_write_png(path, values, depth, 2, 2, NULL) == WX_OK);
    png_image image;
    memset(&image, 0, sizeof image);
    image.version = PNG_IMAGE_VERSION;
    ENSURE(png_image_begin_read_from_file(&image, path) != 0);
    image.format = PNG_FORMAT_GA;
    unsigned char pixels[8];
    ENSURE(png_image_finish_read(&image, NULL, pixels, 0, NULL) != 0);
    ENSURE(pixels[1] == 0 && pixels[3] == 0 && pixels[5] == 0 && pixels[7] == 0);
}

// Issue 24: a constant mask (0.144 everywhere) had a pure white preview, as if
// it were at its most. The white point is the larger of 1 and the 99th
// percentile: a mask within [0, 1] shows its values, grey =
// round(255 * v^(1/2.2)); a larger one is stretched to its 99th percentile.
static bool preview_grey(const char *name, const float *values, int count, unsigned char *grey)
{
    char path[WX_PATH_MAX];
    snprintf(path, sizeof path, "%s/%s", ensure_tmpdir(), name);
    if (wx_preview_write_png(path, values, NULL, count, 1, NULL) != WX_OK) {
        return false;
    }
    png_image image;
    memset(&image, 0, sizeof image);
    image.version = PNG_IMAGE_VERSION;
    if (png_image_begin_read_from_file(&image, path) == 0) {
        return false;
    }
    image.format = PNG_FORMAT_GRAY;
    return png_image_finish_read(&image, NULL, grey, 0, NULL) != 0;
}

TEST(constant_mask_preview_shows_its_value)
{
    float constant[16], ramp[16], large[16];
    for (int k = 0; k < 16; ++k) {
        constant[k] = 0.144f;
        ramp[k] = (float)k / 30.0f; // 0 to 0.5
        large[k] = 5.0f * (float)(k + 1);
    }
    unsigned char grey[16];
    ENSURE(preview_grey("constant.png", constant, 16, grey));
    // 255 * 0.144^(1/2.2) = 105.7
    printf("        constant 0.144: grey %d (was 255)\n", grey[0]);
    for (int k = 0; k < 16; ++k) {
        ENSURE(grey[k] == 106);
    }
    ENSURE(preview_grey("ramp.png", ramp, 16, grey));
    ENSURE(grey[0] == 0);
    ENSURE(grey[15] == 186); // 255 * 0.5^(1/2.2) = 186.1
    ENSURE(grey[3] == 90);   // 255 * 0.1^(1/2.2) = 89.5
    // Above 1: stretched as before, the 99th percentile (element 14 of 16: 75) white.
    ENSURE(preview_grey("large.png", large, 16, grey));
    ENSURE(grey[14] == 255 && grey[15] == 255);
    ENSURE(grey[0] == 74); // 255 * (5/75)^(1/2.2) = 74.5
    ENSURE(wx_preview_white(0.144f) == 1.0f && wx_preview_white(75.0f) == 75.0f);
}

TEST(missing_output_camera_is_an_error)
{
    file_scene fs;
    ENSURE(make_file_scene(&fs, "nooutput", false));
    fs.scene.output_index = -1;
    wx_error err;
    wx_result r = wx_gather_scene(&fs.scene, &fs.opts, &err);
    free_file_scene(&fs);
    ENSURE(r == WX_BAD_INPUT);
    ENSURE(ensure_contains(err.message, "output camera"));
    ENSURE_CAUSE(err, MISSING);
}

int main(void)
{
    RUN(same_camera_gives_dirt_over_texel_area);
    RUN(tilted_surface_divides_by_its_footprint);
    RUN(oblique_input_camera_recovers_density);
    RUN(dirt_on_the_back_of_a_box_does_not_show_from_the_front);
    RUN(occluder_with_the_same_normal_does_not_bleed);
    RUN(crease_is_not_blurred_across);
    RUN(depth_jump_is_not_blurred_across);
    RUN(constant_field_stays_constant);
    RUN(thesis_sum_and_mean_of_a_spike);
    RUN(normalize_scales_the_maximum_to_one);
    RUN(thread_count_does_not_change_the_mask);
    RUN(bad_definitions_are_refused);
    RUN(radius_check_counts_the_neighbourhood);
    RUN(adaptive_noise_follows_the_impacts);
    RUN(adaptive_radius_doubles_for_a_quarter_of_the_impacts);
    RUN(adaptive_counts_as_capped_only_what_impacts_reach);
    RUN(adaptive_keeps_the_initial_dirt_exact);
    RUN(adaptive_does_not_cross_a_shadow_edge);
    RUN(adaptive_keeps_the_dirt_and_its_bytes);
    RUN(adaptive_does_not_cross_creases_or_depth_jumps);
    RUN(world_to_camera_and_ndc);
    RUN(mask_file_projects_world_points_onto_their_texel);
    RUN(preview_png_decodes_with_the_mask_size);
    RUN(preview_scale_is_the_99th_percentile);
    RUN(constant_mask_preview_shows_its_value);
    RUN(missing_output_camera_is_an_error);
    return ensure_summary();
}
