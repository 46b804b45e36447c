// test_gather.c: the gather (gather/gather.h, docs/design.md section 5) with a
// fixed radius: the first pass, occlusion, creases and depth jumps, the second
// pass, bad definitions, and the mask header's matrices, on scenes of flat quads
// (gather_fixture.h); expected values are worked out by hand in the comments.
// The adaptive radius is tested in test_adaptive.c, the gather phase on files in
// test_gather_phase.c.
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/matrix.h"
#include "ensure.h"
#include "gather/gather.h"
#include "gather_fixture.h"
#include "model/camera.h"

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
    RUN(world_to_camera_and_ndc);
    return ensure_summary();
}
