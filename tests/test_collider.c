// test_collider.c: the projected-maps collider against analytic scenes whose
// answers are worked out by hand (tests/sim_fixture.h ray-casts the maps).
#include <math.h>
#include <string.h>

#include "sim/collider.h"
#include "ensure.h"
#include "sim/particles.h"
#include "sim_fixture.h"

// A camera above the origin looking down: u grows with x, v with -z.
static wx_camera top_camera(float size, int px)
{
    return fx_camera(0, 10, 0, 0, 0, 0, 0, 0, -1, size, px);
}

static bool build(wx_collider *col, const wx_camera *cams, wx_maps *maps, int count,
                  const fx_world *world, bool nearest)
{
    for (int c = 0; c < count; ++c) {
        fx_render(&cams[c], world, &maps[c]);
    }
    wx_error err;
    return wx_collider_init(col, cams, maps, count, nearest, &err) == WX_OK;
}

static void release(wx_collider *col, wx_maps *maps, int count)
{
    wx_collider_free(col);
    for (int c = 0; c < count; ++c) {
        wx_maps_free(&maps[c]);
    }
}

// A drop falling through the floor's plane hits it at y = 0, in the texel below.
// A camera with no surface on its map's border holds the whole model in its
// frame, so outside that frame it sees free space (docs/physics.md, "Cameras
// that frame the model"); a camera that cuts the model gives no information
// there, as design.md section 4 says. The point below the box is outside the
// front camera's frame and behind the box for a narrow top camera.
TEST(a_camera_framing_the_model_vouches_outside_its_frame)
{
    fx_world world = { 0 };
    fx_box(&world, -1, -1, -1, 1, 1, 1);
    float below[3] = { 0.0f, -3.0f, 0.0f };
    float p0[3] = { 0.0f, -3.0f, 0.3f }, p1[3] = { 0.0f, -3.0f, -0.3f };
    for (int framing = 0; framing < 2; ++framing) {
        float size = framing ? 4.0f : 1.5f; // the front camera holds the box, or cuts it
        wx_camera cams[2] = { fx_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, size, 64),
                              top_camera(1.5f, 64) };
        wx_maps maps[2];
        wx_collider col;
        ENSURE(build(&col, cams, maps, 2, &world, false));
        ENSURE(col.cameras[0].frames_model == (framing != 0));
        ENSURE(!col.cameras[1].frames_model);
        bool collides = wx_collider_point_collides(&col, below);
        wx_hit hit;
        bool swept = wx_collider_sweep(&col, p0, p1, &hit);
        bool coarse = wx_collider_coarse_clear(&col, p0, p1);
        release(&col, maps, 2);
        ENSURE(collides == !framing);
        ENSURE(swept == !framing);
        ENSURE(!framing || coarse);
    }
}

TEST(drop_hits_the_texel_below)
{
    fx_world world = { 0 };
    fx_box(&world, -5, -1, -5, 5, 0, 5);
    wx_camera cam = top_camera(10, 100); // 0.1 m texels
    wx_maps maps;
    wx_collider col;
    ENSURE(build(&col, &cam, &maps, 1, &world, false));
    float p0[3] = { 1.23f, 0.5f, -2.37f }, p1[3] = { 1.23f, -0.5f, -2.37f };
    wx_hit hit;
    bool hits = wx_collider_sweep(&col, p0, p1, &hit);
    // i = floor((1.23 + 5) / 10 * 100) = 62, j = floor((1 - (2.37/10 + 0.5)) * 100) = 26.
    uint32_t texel = hit.texel;
    wx_hit copy = hit;
    release(&col, &maps, 1);
    ENSURE(hits);
    ENSURE(copy.camera == 0);
    ENSURE(texel == 26u * 100u + 62u);
    ENSURE_NEAR(copy.s, 0.5, 1e-5);
    ENSURE_NEAR(copy.point[0], 1.23, 1e-5);
    ENSURE_NEAR(copy.point[1], 0.0, 1e-5);
    ENSURE_NEAR(copy.normal[1], 1.0, 1e-6);
    // Put back a hair above the floor (a hundredth of a texel), straight up.
    ENSURE(copy.front[1] > 0.0f && copy.front[1] < 0.002f);
    ENSURE_NEAR(copy.front[0], 1.23, 1e-6);
    ENSURE_NEAR(copy.front[2], -2.37, 1e-6);
}

// The point rule with a box seen from the front, the back and the top.
TEST(box_from_three_sides_point_rule)
{
    fx_world world = { 0 };
    fx_box(&world, -1, -1, -1, 1, 1, 1);
    wx_camera cams[3] = { fx_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 4, 64),
                          fx_camera(0, 0, -10, 0, 0, 0, 0, 1, 0, 4, 64), top_camera(4, 64) };
    wx_maps maps[3];
    wx_collider col;
    ENSURE(build(&col, cams, maps, 3, &world, false));
    float inside[3] = { 0.2f, -0.3f, 0.5f };
    float beside[3] = { 1.5f, 0.0f, 0.0f };    // no surface there for any camera
    float above[3] = { 0.0f, 1.5f, 0.0f };     // top camera: in front of the top face
    float behind[3] = { 0.0f, 0.0f, -1.5f };   // behind for the front camera, not the back
    float in_front[3] = { 0.0f, 0.0f, 3.0f };  // seen by the front camera only
    float far_away[3] = { 50.0f, 0.0f, 0.0f }; // in no frame: no information
    bool r[6] = {
        wx_collider_point_collides(&col, inside),   wx_collider_point_collides(&col, beside),
        wx_collider_point_collides(&col, above),    wx_collider_point_collides(&col, behind),
        wx_collider_point_collides(&col, in_front), wx_collider_point_collides(&col, far_away)
    };
    release(&col, maps, 3);
    ENSURE(r[0]);
    ENSURE(!r[1]);
    ENSURE(!r[2]);
    ENSURE(!r[3]);
    ENSURE(!r[4]);
    ENSURE(!r[5]);
}

// 50 texels in one step through a wall one texel thick: the end points are
// both clear, the sweep still stops at the wall's face.
TEST(fast_particle_hits_one_texel_wall)
{
    fx_world world = { 0 };
    fx_box(&world, 0.0f, -1, -3, 0.1f, 1, 3); // texel 32 of 64 over 6.4 m
    wx_camera cam = top_camera(6.4f, 64);
    wx_maps maps;
    wx_collider col;
    ENSURE(build(&col, &cam, &maps, 1, &world, false));
    float p0[3] = { -2.5f, 0.0f, 0.05f }, p1[3] = { 2.5f, 0.0f, 0.05f };
    bool start = wx_collider_point_collides(&col, p0), end = wx_collider_point_collides(&col, p1);
    wx_hit hit;
    bool hits = wx_collider_sweep(&col, p0, p1, &hit);
    // And backwards, it stops at the other face.
    wx_hit back;
    bool hits_back = wx_collider_sweep(&col, p1, p0, &back);
    release(&col, &maps, 1);
    ENSURE(!start && !end);
    ENSURE(hits && hits_back);
    ENSURE_NEAR(hit.point[0], 0.0, 1e-4);
    ENSURE_NEAR(hit.s, 0.5, 1e-5);
    ENSURE(hit.texel % 64u == 32u);
    ENSURE_NEAR(back.point[0], 0.1, 1e-4);
}

// An incline y = x/2 seen from above: with bilinear depth the hit lies on the
// plane; with the thesis' nearest-texel depth it lies on terraces half a texel
// of slope away (the banding of thesis 5.1.2).
TEST(bilinear_depth_follows_an_incline)
{
    fx_world world = { 0 };
    fx_solid *wedge = fx_box(&world, -3, -3, -3, 3, 3, 3);
    fx_plane(wedge, -0.5f, 1.0f, 0.0f, 0.0f); // y - x/2 <= 0
    wx_camera cam = top_camera(6.4f, 64);     // 0.1 m texels
    double worst[2] = { 0, 0 };
    for (int mode = 0; mode < 2; ++mode) {
        wx_maps maps;
        wx_collider col;
        ENSURE(build(&col, &cam, &maps, 1, &world, mode == 1));
        for (int i = 0; i < 500; ++i) {
            float x = -2.4f + 4.8f * (float)i / 500.0f, z = 0.37f;
            float p0[3] = { x, 2.0f, z }, p1[3] = { x, -2.0f, z };
            wx_hit hit;
            if (!wx_collider_sweep(&col, p0, p1, &hit)) {
                worst[mode] = INFINITY;
                continue;
            }
            worst[mode] = fmax(worst[mode], fabs(hit.point[1] - 0.5 * x));
        }
        release(&col, &maps, 1);
    }
    ENSURE(worst[0] < 1e-4);  // bilinear: on the plane
    ENSURE(worst[1] > 0.02);  // nearest: up to 0.5 texel * slope 0.5 = 0.025 off
    ENSURE(worst[1] < 0.026);
}

// A steep face (70 degrees from horizontal, facing +X) seen at a grazing angle by
// a camera above and head-on by a camera at +X. Both record it exactly (bilinear
// depth of a plane), so d - depth is 0 for both up to rounding: every hit must
// go to the head-on camera, never to the grazing one, whose texel covers a long
// strip of the face (docs/physics.md, "Which camera gives the hit").
TEST(head_on_camera_gives_the_hit_on_a_steep_face)
{
    fx_world world = { 0 };
    fx_solid *wedge = fx_box(&world, -3, -3, -3, 3, 3, 3);
    fx_plane(wedge, 0.9397f, 0.3420f, 0.0f, 0.0f); // x cos 20 + y sin 20 <= 0
    wx_camera cams[2] = { top_camera(6.4f, 64), fx_camera(10, 0, 0, 0, 0, 0, 0, 1, 0, 6.4f, 64) };
    wx_maps maps[2];
    wx_collider col;
    ENSURE(build(&col, cams, maps, 2, &world, false));
    int hits = 0, side = 0;
    double worst = 0.0;
    for (int i = 0; i < 400; ++i) {
        float x = -0.9f + 1.8f * (float)i / 400.0f,
              z = -2.0f + 4.0f * (float)((i * 37) % 400) / 400.0f;
        float p0[3] = { x, 2.95f, z }, p1[3] = { x, -2.95f, z };
        wx_hit hit;
        if (!wx_collider_sweep(&col, p0, p1, &hit)) {
            continue;
        }
        hits++;
        side += hit.camera == 1;
        worst = fmax(worst, fabs(0.9397 * hit.point[0] + 0.3420 * hit.point[1]));
    }
    release(&col, maps, 2);
    ENSURE(hits == 400);
    ENSURE(side == 400);
    ENSURE(worst < 1e-3); // on the face
}

// Ground in front of a wall, seen by a camera in front and one above. In the
// front camera the rows at ground level show the slab's front edge (head-on,
// like the top camera sees the ground), and its bilinear depth between the wall
// and that edge passes through the ground between them: the hit there must
// still go to the top camera, which really sees the ground, not to the slab's
// edge 3 m away.
TEST(ground_between_wall_and_slab_edge_goes_to_the_camera_that_sees_it)
{
    fx_world world = { 0 };
    fx_box(&world, -2, 0, -1, 2, 3, 0);      // wall, front face at z = 0
    fx_box(&world, -3, -0.2f, -3, 3, 0, 3);  // ground slab, front edge at z = 3
    wx_camera cams[2] = { fx_camera(0, 1, 10, 0, 1, 0, 0, 1, 0, 6.4f, 64), top_camera(6.4f, 64) };
    wx_maps maps[2];
    wx_collider col;
    ENSURE(build(&col, cams, maps, 2, &world, false));
    int hits = 0, top = 0;
    double worst = 0.0;
    for (int i = 0; i < 200; ++i) {
        float x = -1.9f + 3.8f * (float)i / 200.0f,
              z = 0.3f + 2.4f * (float)((i * 53) % 200) / 200.0f;
        float p0[3] = { x, 0.5f, z }, p1[3] = { x, -0.1f, z };
        wx_hit hit;
        if (!wx_collider_sweep(&col, p0, p1, &hit)) {
            continue;
        }
        hits++;
        top += hit.camera == 1;
        worst = fmax(worst, fabs(hit.point[1]));
    }
    release(&col, maps, 2);
    ENSURE(hits == 200);
    ENSURE(top == 200);
    ENSURE(worst < 0.05); // on the ground (within half a front-camera texel)
}

// A segment that starts inside a solid collides at once; the particle is put
// back on the surface of the camera that sees it nearest.
TEST(start_inside_is_pushed_out)
{
    fx_world world = { 0 };
    fx_box(&world, -5, -1, -5, 5, 0, 5);
    wx_camera cam = top_camera(10, 100);
    wx_maps maps;
    wx_collider col;
    ENSURE(build(&col, &cam, &maps, 1, &world, false));
    float p0[3] = { 0.3f, -0.4f, 0.2f }, p1[3] = { 0.35f, -0.45f, 0.2f };
    wx_hit hit;
    bool hits = wx_collider_sweep(&col, p0, p1, &hit);
    bool out = wx_collider_point_collides(&col, hit.front);
    release(&col, &maps, 1);
    ENSURE(hits);
    ENSURE(hit.s == 0.0f);
    ENSURE(!out);
    ENSURE(hit.front[1] > 0.0f && hit.front[1] < 0.002f);
}

// Random segments around a box seen by three cameras: whenever the coarse test
// clears a segment the swept test agrees; every put-back point is clear of the
// surface and within a hundredth of a texel of the hit point plus the depth gap.
TEST(coarse_test_is_conservative_and_put_back_is_outside)
{
    fx_world world = { 0 };
    fx_box(&world, -1, -1, -1, 1, 1, 1);
    fx_box(&world, -3, -2, -3, 3, -1.5f, 3);
    wx_camera cams[3] = { fx_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 7, 128),
                          fx_camera(10, 0, 0, 0, 0, 0, 0, 1, 0, 7, 128), top_camera(7, 128) };
    wx_maps maps[3];
    wx_collider col;
    ENSURE(build(&col, cams, maps, 3, &world, false));
    uint64_t state = 5;
    int cleared = 0, contradictions = 0, hits = 0, bad_front = 0;
    for (int b = 0; b < 4000; ++b) {
        float x0[WX_PARTICLE_BLOCK], y0[WX_PARTICLE_BLOCK], z0[WX_PARTICLE_BLOCK];
        float x1[WX_PARTICLE_BLOCK], y1[WX_PARTICLE_BLOCK], z1[WX_PARTICLE_BLOCK];
        for (int k = 0; k < WX_PARTICLE_BLOCK; ++k) {
            float r[6];
            for (int q = 0; q < 6; ++q) {
                state = wx_mix64(state + 1);
                r[q] = (float)((state >> 11) * (1.0 / 9007199254740992.0));
            }
            float len = (k % 4 == 0) ? 2.0f : 0.2f; // a few long ones
            x0[k] = -3.4f + 6.8f * r[0];
            y0[k] = -2.4f + 5.0f * r[1];
            z0[k] = -3.4f + 6.8f * r[2];
            x1[k] = x0[k] + len * (r[3] - 0.5f);
            y1[k] = y0[k] + len * (r[4] - 0.5f);
            z1[k] = z0[k] + len * (r[5] - 0.5f);
        }
        int natural[3] = { 0, 1, 2 }, order[3] = { 2, 0, 1 };
        uint32_t out1, out2;
        uint32_t mask = wx_collider_coarse_block(&col, natural, 3, NULL, x0, y0, z0, x1, y1, z1,
                                                 &out1);
        uint32_t mask2 = wx_collider_coarse_block(&col, order, 3, NULL, x0, y0, z0, x1, y1, z1,
                                                  &out2);
        contradictions += mask != mask2; // any order, same answer
        if (mask != 0xffffu) {
            mask |= out1;
        }
        uint8_t clear[WX_PARTICLE_BLOCK];
        for (int k = 0; k < WX_PARTICLE_BLOCK; ++k) {
            clear[k] = (mask >> k) & 1u;
        }
        for (int k = 0; k < WX_PARTICLE_BLOCK; ++k) {
            float p0[3] = { x0[k], y0[k], z0[k] }, p1[3] = { x1[k], y1[k], z1[k] };
            if (wx_collider_point_collides(&col, p0)) {
                continue; // starts inside: not a segment a particle would fly
            }
            wx_hit hit;
            bool h = wx_collider_sweep(&col, p0, p1, &hit);
            cleared += clear[k];
            contradictions += clear[k] && h;
            if (h) {
                hits++;
                bad_front += wx_collider_point_collides(&col, hit.front);
                float d = 0;
                for (int q = 0; q < 3; ++q) {
                    d += (hit.front[q] - hit.point[q]) * (hit.front[q] - hit.point[q]);
                }
                bad_front += sqrtf(d) > 0.06f; // a hundredth of a 5.5 cm texel + rounding
            }
        }
    }
    release(&col, maps, 3);
    ENSURE(contradictions == 0);
    ENSURE(bad_front == 0);
    ENSURE(cleared > 20000); // the coarse test answers most steps
    ENSURE(hits > 1000);
}

TEST(projective_cameras_are_refused)
{
    fx_world world = { 0 };
    fx_box(&world, -1, -1, -1, 1, 1, 1);
    wx_camera cam = top_camera(4, 16);
    wx_maps maps;
    fx_render(&cam, &world, &maps);
    cam.wtc[11] = 0.5f; // w depends on z: a perspective matrix
    wx_collider col;
    wx_error err;
    wx_result r = wx_collider_init(&col, &cam, &maps, 1, false, &err);
    wx_maps_free(&maps);
    ENSURE(r == WX_BAD_INPUT);
    ENSURE(ensure_contains(err.message, "orthographic"));
    ENSURE_CAUSE(err, BAD_CAMERA);
}

int main(void)
{
    RUN(drop_hits_the_texel_below);
    RUN(box_from_three_sides_point_rule);
    RUN(a_camera_framing_the_model_vouches_outside_its_frame);
    RUN(fast_particle_hits_one_texel_wall);
    RUN(bilinear_depth_follows_an_incline);
    RUN(head_on_camera_gives_the_hit_on_a_steep_face);
    RUN(ground_between_wall_and_slab_edge_goes_to_the_camera_that_sees_it);
    RUN(start_inside_is_pushed_out);
    RUN(coarse_test_is_conservative_and_put_back_is_outside);
    RUN(projective_cameras_are_refused);
    return ensure_summary();
}
