// test_camera.c: map-space conventions of docs/design.md section 2, worked out by hand.
#include <math.h>
#include <string.h>

#include "model/camera.h"
#include "ensure.h"
#include "core/matrix.h"

static wx_view front_view(void)
{
    // Eye at z = 10 looking at the origin, 4 x 2 m frame, 8 x 4 texels.
    wx_view v = { .eye = { 0, 0, 10 }, .target = { 0, 0, 0 }, .up = { 0, 1, 0 },
                  .width_ws = 4, .height_ws = 2, .width_px = 8, .height_px = 4 };
    return v;
}

TEST(view_point_lands_on_hand_computed_texel)
{
    wx_view view = front_view();
    wx_camera cam;
    ENSURE(wx_camera_from_view(&view, &cam, NULL) == WX_OK);
    ENSURE(cam.width == 8 && cam.height == 4);
    // (1, 0.5, 3): u = 1/4 + 1/2, v = 0.5/2 + 1/2, d = 10 - 3.
    const float p[3] = { 1.0f, 0.5f, 3.0f };
    float uvd[3];
    wx_camera_world_to_map(&cam, p, uvd);
    ENSURE_NEAR(uvd[0], 0.75, 1e-6);
    ENSURE_NEAR(uvd[1], 0.75, 1e-6);
    ENSURE_NEAR(uvd[2], 7.0, 1e-5);
    int i, j;
    ENSURE(wx_map_texel(cam.width, cam.height, uvd[0], uvd[1], &i, &j));
    ENSURE(i == 6); // floor(0.75 * 8)
    ENSURE(j == 1); // floor((1 - 0.75) * 4): second row from the top
}

TEST(top_view_axes)
{
    // Looking down -Y with image-up along -Z: u grows with x, v grows towards -z.
    wx_view view = { .eye = { 0, 10, 0 }, .target = { 0, 0, 0 }, .up = { 0, 0, -1 },
                     .width_ws = 10, .height_ws = 10, .width_px = 100, .height_px = 100 };
    wx_camera cam;
    ENSURE(wx_camera_from_view(&view, &cam, NULL) == WX_OK);
    const float p[3] = { 2.0f, 1.0f, -3.0f };
    float uvd[3];
    wx_camera_world_to_map(&cam, p, uvd);
    ENSURE_NEAR(uvd[0], 0.7, 1e-6);
    ENSURE_NEAR(uvd[1], 0.8, 1e-6);
    ENSURE_NEAR(uvd[2], 9.0, 1e-5);
    float dir[3];
    wx_camera_view_dir(&cam, dir);
    ENSURE_NEAR(dir[1], -1.0, 1e-6);
}

TEST(view_matrices_invert)
{
    wx_view view = { .eye = { 3, 4, 5 }, .target = { -1, 0.5f, 2 }, .up = { 0.1f, 1, 0 },
                     .width_ws = 7, .height_ws = 3, .width_px = 64, .height_px = 32 };
    wx_camera cam;
    ENSURE(wx_camera_from_view(&view, &cam, NULL) == WX_OK);
    ENSURE(wx_matrix_inverse_error(cam.wtc, cam.ctw) < 1e-5f);
    float inverted[16];
    ENSURE(wx_matrix_invert(cam.wtc, inverted));
    for (int k = 0; k < 16; ++k) {
        ENSURE_NEAR(inverted[k], cam.ctw[k], 1e-4);
    }
    // Round trip of a world point.
    const float p[3] = { 0.3f, -2.0f, 1.5f };
    float uvd[3], back[3];
    wx_camera_world_to_map(&cam, p, uvd);
    wx_camera_map_to_world(&cam, uvd, back);
    for (int k = 0; k < 3; ++k) {
        ENSURE_NEAR(back[k], p[k], 1e-5);
    }
    // The eye maps to the centre of the map at d = 0.
    wx_camera_world_to_map(&cam, view.eye, uvd);
    ENSURE_NEAR(uvd[0], 0.5, 1e-6);
    ENSURE_NEAR(uvd[1], 0.5, 1e-6);
    ENSURE_NEAR(uvd[2], 0.0, 1e-5);
}

TEST(frame_size_and_centre)
{
    wx_view view = front_view();
    wx_camera cam;
    ENSURE(wx_camera_from_view(&view, &cam, NULL) == WX_OK);
    float w, h;
    wx_camera_frame_size(&cam, &w, &h);
    ENSURE_NEAR(w, 4.0, 1e-6);
    ENSURE_NEAR(h, 2.0, 1e-6);
    // Bottom-left corner of the frame on the eye plane: u = v = 0.
    const float corner[3] = { 0, 0, 0 };
    float p[3];
    wx_camera_map_to_world(&cam, corner, p);
    ENSURE_NEAR(p[0], -2.0, 1e-6);
    ENSURE_NEAR(p[1], -1.0, 1e-6);
    ENSURE_NEAR(p[2], 10.0, 1e-6);
}

TEST(texel_edges_follow_the_pinned_rule)
{
    int i, j;
    // Inside when 0 <= u < 1 and 0 < v <= 1.
    ENSURE(wx_map_texel(8, 4, 0.0f, 1.0f, &i, &j) && i == 0 && j == 0);
    ENSURE(!wx_map_texel(8, 4, 1.0f, 0.5f, &i, &j));
    ENSURE(!wx_map_texel(8, 4, 0.5f, 0.0f, &i, &j));
    ENSURE(!wx_map_texel(8, 4, -0.001f, 0.5f, &i, &j));
    ENSURE(!wx_map_texel(8, 4, 0.5f, 1.001f, &i, &j));
    ENSURE(!wx_map_texel(8, 4, NAN, 0.5f, &i, &j));
    // v just above 0 is the bottom row; u just below 1 the last column.
    ENSURE(wx_map_texel(8, 4, 0.9999999f, 1e-7f, &i, &j) && i == 7 && j == 3);
    // Texel centres round-trip to their texel.
    for (int jj = 0; jj < 4; ++jj) {
        for (int ii = 0; ii < 8; ++ii) {
            float u, v;
            wx_map_texel_center(8, 4, ii, jj, &u, &v);
            ENSURE(wx_map_texel(8, 4, u, v, &i, &j) && i == ii && j == jj);
        }
    }
    float u, v;
    wx_map_texel_center(8, 4, 6, 1, &u, &v);
    ENSURE_NEAR(u, 6.5 / 8.0, 1e-7);
    ENSURE_NEAR(v, 1.0 - 1.5 / 4.0, 1e-7);
}

TEST(thesis_identity_matrix)
{
    // The thesis' example uses identity matrices: u = x, v = y, d = z.
    float identity[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };
    wx_camera cam;
    memcpy(cam.wtc, identity, sizeof identity);
    ENSURE(wx_matrix_invert(cam.wtc, cam.ctw));
    const float p[3] = { 0.25f, 0.5f, 2.0f };
    float uvd[3];
    wx_camera_world_to_map(&cam, p, uvd);
    ENSURE(uvd[0] == 0.25f && uvd[1] == 0.5f && uvd[2] == 2.0f);
}

TEST(row_vector_translation_is_the_last_row)
{
    // [x y z 1] * M puts the translation in the fourth row (elements 12..14).
    float m[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 5, 6, 7, 1 };
    const float p[3] = { 1, 2, 3 };
    float out[3];
    ENSURE(wx_transform_point(m, p, out));
    ENSURE(out[0] == 6.0f && out[1] == 8.0f && out[2] == 10.0f);
    float inv[16];
    ENSURE(wx_matrix_invert(m, inv));
    ENSURE_NEAR(inv[12], -5.0, 1e-6);
    ENSURE_NEAR(inv[13], -6.0, 1e-6);
    ENSURE_NEAR(inv[14], -7.0, 1e-6);
}

TEST(singular_and_bad_views_are_refused)
{
    float singular[16] = { 1, 0, 0, 0, 2, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };
    float inv[16];
    ENSURE(!wx_matrix_invert(singular, inv));
    float with_nan[16] = { NAN, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };
    ENSURE(!wx_matrix_invert(with_nan, inv));
    wx_camera cam;
    wx_error err;
    wx_view same = { .eye = { 1, 1, 1 }, .target = { 1, 1, 1 }, .up = { 0, 1, 0 },
                     .width_ws = 1, .height_ws = 1, .width_px = 4, .height_px = 4 };
    ENSURE(wx_camera_from_view(&same, &cam, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_CAMERA);
    ENSURE(ensure_contains(err.message, "same point"));
    wx_view parallel = { .eye = { 0, 5, 0 }, .target = { 0, 0, 0 }, .up = { 0, 1, 0 },
                         .width_ws = 1, .height_ws = 1, .width_px = 4, .height_px = 4 };
    ENSURE(wx_camera_from_view(&parallel, &cam, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_CAMERA);
    ENSURE(ensure_contains(err.message, "parallel"));
}

TEST(inverse_error_detects_a_wrong_inverse)
{
    wx_view view = front_view();
    wx_camera cam;
    ENSURE(wx_camera_from_view(&view, &cam, NULL) == WX_OK);
    ENSURE(wx_matrix_inverse_error(cam.wtc, cam.ctw) < 1e-6f);
    cam.ctw[12] += 0.5f;
    ENSURE(wx_matrix_inverse_error(cam.wtc, cam.ctw) > 0.01f);
}

int main(void)
{
    RUN(view_point_lands_on_hand_computed_texel);
    RUN(top_view_axes);
    RUN(view_matrices_invert);
    RUN(frame_size_and_centre);
    RUN(texel_edges_follow_the_pinned_rule);
    RUN(thesis_identity_matrix);
    RUN(row_vector_translation_is_the_last_row);
    RUN(singular_and_bad_views_are_refused);
    RUN(inverse_error_detects_a_wrong_inverse);
    return ensure_summary();
}
