// test_collider.c: the projected-maps collider against analytic scenes whose
// answers are worked out by hand (tests/sim_fixture.h ray-casts the maps).
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/matrix.h"
#include "model/ownership.h"
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

// n uniform numbers in [0, 1) from the test's own sequence.
static void uniforms(uint64_t *state, float *r, int n)
{
    for (int q = 0; q < n; ++q) {
        *state = wx_mix64(*state + 1);
        r[q] = (float)((*state >> 11) * (1.0 / 9007199254740992.0));
    }
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

// A camera w x h world units around (cx, cy, cz), px texels a unit, looking
// down -y (down) or along -z.
static wx_camera window_camera(float cx, float cy, float cz, bool down, float w, float h, int px)
{
    wx_view view;
    memset(&view, 0, sizeof view);
    view.eye[0] = cx;
    view.eye[1] = down ? 10.0f : cy;
    view.eye[2] = down ? cz : 10.0f;
    view.target[0] = cx;
    view.target[1] = down ? 0.0f : cy;
    view.target[2] = cz;
    view.up[1] = down ? 0.0f : 1.0f;
    view.up[2] = down ? -1.0f : 0.0f;
    view.width_ws = w;
    view.height_ws = h;
    view.width_px = (int)(w * (float)px);
    view.height_px = (int)(h * (float)px);
    wx_camera cam;
    wx_error err;
    if (wx_camera_from_view(&view, &cam, &err) != WX_OK) {
        abort();
    }
    return cam;
}

// A tile's cameras are the whole cameras cut to its box (weathering tiles):
// the cut ones hold the slab on their cut sides, which alone would make them
// say "no information" outside their frames, and the top camera would then
// catch a drop below the slab, outside the front camera's frame, which the
// whole front camera (framing the slab) calls free space. With the tile's box
// the cut sides do not count (beyond them lies only space outside the box):
// free, as in the whole run (docs/tiles.md; the city's slab edges).
TEST(a_tile_keeps_its_whole_cameras_framing)
{
    fx_world world = { 0 };
    fx_box(&world, -1.0f, -0.2f, -1.0f, 1.0f, 0.0f, 1.0f);
    // The whole front camera: 4 x 4 around the slab, framing it.
    wx_camera whole = window_camera(0, 0, 0, false, 4, 4, 16);
    // The tile x in [-0.5, 0.5] (halo included), y and z unbounded (to 10).
    wx_camera cams[2] = { window_camera(0, 0, 0, false, 1, 4, 16),
                          window_camera(0, 0, 0, true, 1, 4, 16) };
    const double lo[3] = { -0.5, -10.0, -10.0 }, hi[3] = { 0.5, 10.0, 10.0 };
    float below[3] = { 0.0f, -3.0f, 0.5f };
    float p0[3] = { 0.0f, -3.0f, 0.6f }, p1[3] = { 0.0f, -3.0f, 0.4f };
    wx_maps maps[2], whole_maps;
    wx_collider col, whole_col;
    ENSURE(build(&whole_col, &whole, &whole_maps, 1, &world, false));
    ENSURE(whole_col.cameras[0].frames_model);
    release(&whole_col, &whole_maps, 1);
    ENSURE(build(&col, cams, maps, 2, &world, false));
    ENSURE(!col.cameras[0].frames_model && !col.cameras[1].frames_model);
    ENSURE(wx_collider_point_collides(&col, below)); // caught under the slab
    wx_collider_frame_box(&col, lo, hi);
    ENSURE(col.cameras[0].frames_model && col.cameras[1].frames_model);
    ENSURE(!wx_collider_point_collides(&col, below));
    wx_hit hit;
    ENSURE(!wx_collider_sweep(&col, p0, p1, &hit));
    // A box reaching beyond the slab's cut sides: the surface on them counts.
    const double wide_lo[3] = { -2.0, -10.0, -10.0 }, wide_hi[3] = { 2.0, 10.0, 10.0 };
    wx_collider_frame_box(&col, wide_lo, wide_hi);
    ENSURE(!col.cameras[0].frames_model && !col.cameras[1].frames_model);
    release(&col, maps, 2);
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
            uniforms(&state, r, 6);
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

// --- layered maps (docs/design.md section 14) ------------------------------------

// A world for layered maps: closed solids (each ray crossing enters and leaves
// them, normals out) and one-sided sheets (a zero-thick solid of which a ray
// records one crossing, with the sheet's own normal whichever side it comes from).
typedef struct lay_world {
    fx_world solids;
    fx_world sheets;
    float sheet_normal[FX_MAX_SOLIDS][3];
} lay_world;

typedef struct crossing {
    double t;
    float n[3];
} crossing;

// Entry and exit of a ray through a convex solid, with the planes' outward normals.
static bool cross_solid(const fx_solid *s, const double o[3], const double d[3], crossing *in,
                        crossing *out)
{
    double t0, t1;
    int p0, p1;
    if (!fx_cross_solid(s, o, d, &t0, &p0, &t1, &p1) || p1 < 0) {
        return false;
    }
    in->t = t0;
    out->t = t1;
    memcpy(in->n, s->n[p0], sizeof in->n);
    memcpy(out->n, s->n[p1], sizeof out->n);
    return true;
}

static bool before(const crossing *a, const crossing *b, const double view[3])
{
    if (a->t != b->t) {
        return a->t < b->t;
    }
    double fa = a->n[0] * view[0] + a->n[1] * view[1] + a->n[2] * view[2];
    double fb = b->n[0] * view[0] + b->n[1] * view[1] + b->n[2] * view[2];
    return fa > 0.0 && !(fb > 0.0); // leaving (n . view > 0) first
}

// Sorts a ray's crossings nearest first (insertion sort: a few per ray).
static void sort_crossings(crossing *list, int count, const double view[3])
{
    for (int a = 1; a < count; ++a) {
        for (int b = a; b > 0 && before(&list[b], &list[b - 1], view); --b) {
            crossing x = list[b];
            list[b] = list[b - 1];
            list[b - 1] = x;
        }
    }
}

// Where texel (i, j)'s view ray leaves the camera's d = 0 plane.
static void texel_origin(const wx_camera *cam, int i, int j, float o[3])
{
    float uvd[3];
    wx_map_texel_center(cam->width, cam->height, i, j, &uvd[0], &uvd[1]);
    uvd[2] = 0.0f;
    wx_camera_map_to_world(cam, uvd, o);
}

// Renders the first `layers` crossings of every texel's view ray (fx_render's
// depth convention: distance from the camera's d = 0 plane), layer k's block
// at k*W*H in each plane.
// Empty maps of `layers` layers for camera `cam` (normals and impact zero).
static void layered_maps(const wx_camera *cam, int layers, wx_maps *maps)
{
    size_t n = (size_t)cam->width * (size_t)cam->height;
    memset(maps, 0, sizeof *maps);
    maps->width = cam->width;
    maps->height = cam->height;
    maps->layers = layers;
    maps->depth = malloc((size_t)layers * n * sizeof(float));
    maps->normal = calloc(3 * (size_t)layers * n, sizeof(float));
    maps->impact = calloc(2 * (size_t)layers * n, sizeof(float));
}

static void render_layers(const wx_camera *cam, const lay_world *world, int layers, wx_maps *maps)
{
    int W = cam->width, H = cam->height;
    size_t n = (size_t)W * (size_t)H;
    layered_maps(cam, layers, maps);
    float dir[3];
    wx_camera_view_dir(cam, dir);
    double d[3] = { dir[0], dir[1], dir[2] };
    for (int j = 0; j < H; ++j) {
        for (int i = 0; i < W; ++i) {
            size_t t = (size_t)j * (size_t)W + (size_t)i;
            float eye[3];
            texel_origin(cam, i, j, eye);
            double o[3] = { eye[0], eye[1], eye[2] };
            crossing list[2 * 2 * FX_MAX_SOLIDS];
            int count = 0;
            for (int s = 0; s < world->solids.solid_count; ++s) {
                if (cross_solid(&world->solids.solids[s], o, d, &list[count],
                                &list[count + 1])) {
                    count += 2;
                }
            }
            for (int s = 0; s < world->sheets.solid_count; ++s) {
                crossing out;
                if (cross_solid(&world->sheets.solids[s], o, d, &list[count], &out)) {
                    memcpy(list[count].n, world->sheet_normal[s], sizeof list[count].n);
                    count++;
                }
            }
            // Nearest first; where two solids touch (a post on a floor), the
            // leaving crossing before the entering one at the same depth, as
            // the collider needs (docs/physics.md, "Layered maps").
            sort_crossings(list, count, d);
            for (int k = 0; k < layers; ++k) {
                size_t at = (size_t)k * n + t;
                maps->depth[at] = k < count ? (float)list[k].t : INFINITY;
                if (k < count) {
                    memcpy(&maps->normal[3 * at], list[k].n, sizeof list[k].n);
                }
                maps->impact[2 * at] = 0.1f * (float)k; // tells the layers apart
                maps->impact[2 * at + 1] = 0.5f;
            }
        }
    }
}

static bool build_layers(wx_collider *col, const wx_camera *cams, wx_maps *maps, int count,
                         const lay_world *world, int layers)
{
    for (int c = 0; c < count; ++c) {
        render_layers(&cams[c], world, layers, &maps[c]);
    }
    wx_error err;
    return wx_collider_init(col, cams, maps, count, false, &err) == WX_OK;
}

static fx_solid *sheet(lay_world *w, float x0, float y0, float z0, float x1, float y1, float z1,
                       float nx, float ny, float nz)
{
    int k = w->sheets.solid_count;
    w->sheet_normal[k][0] = nx;
    w->sheet_normal[k][1] = ny;
    w->sheet_normal[k][2] = nz;
    return fx_box(&w->sheets, x0, y0, z0, x1, y1, z1);
}

// A railing on a floor slab: a wide handrail (y 1.0 to 1.1, z 0.6 to 1.0) and a
// low bar in its front plane (y 0.4 to 0.5, z 0.9 to 1.0), seen by a front and a
// top camera. Behind the bar and under the handrail both one-layer maps say
// "behind": a drop falling there stops at the bar's top (y = 0.5), in mid-air.
// With four layers it falls through the free space and lands on the floor.
TEST(railing_layers_let_a_drop_fall_behind_the_bars)
{
    lay_world world = { 0 };
    fx_box(&world.solids, -3, -1, -3, 3, 0, 3);        // floor
    fx_box(&world.solids, -2, 1.0f, 0.6f, 2, 1.1f, 1); // handrail
    fx_box(&world.solids, -2, 0.4f, 0.9f, 2, 0.5f, 1); // low bar
    wx_camera cams[2] = { fx_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 6.4f, 64), top_camera(6.4f, 64) };
    float p0[3] = { 0.33f, 0.8f, 0.77f }, p1[3] = { 0.33f, -0.4f, 0.77f };
    // Between the bars, through the railing's plane, under the handrail.
    float q0[3] = { -0.47f, 0.75f, 1.5f }, q1[3] = { -0.47f, 0.7f, 0.7f };
    wx_hit hit[2], through[2];
    bool hits[2], crosses[2], start[2];
    for (int mode = 0; mode < 2; ++mode) {
        int layers = mode == 0 ? 1 : 4;
        wx_maps maps[2];
        wx_collider col;
        ENSURE(build_layers(&col, cams, maps, 2, &world, layers));
        start[mode] = wx_collider_point_collides(&col, p0);
        hits[mode] = wx_collider_sweep(&col, p0, p1, &hit[mode]);
        crosses[mode] = wx_collider_sweep(&col, q0, q1, &through[mode]);
        release(&col, maps, 2);
    }
    ENSURE(!start[0] && !start[1]);
    ENSURE(hits[0] && hits[1]);
    // One layer: stopped at the bar's top, behind it, under the handrail.
    ENSURE_NEAR(hit[0].point[1], 0.5, 1e-5);
    ENSURE(hit[0].layer == 0);
    // Four layers: on the floor, as the top camera sees it through the
    // handrail's two crossings (layer 2, normal up).
    ENSURE_NEAR(hit[1].s, 0.8 / 1.2, 1e-5 * (0.8 / 1.2));
    ENSURE_NEAR(hit[1].point[1], 0.0, 1e-5);
    ENSURE(hit[1].camera == 1);
    ENSURE(hit[1].layer == 2);
    ENSURE_NEAR(hit[1].normal[1], 1.0, 1e-6);
    ENSURE(hit[1].absorption == 0.2f);
    ENSURE(hit[1].front[1] > 0.0f && hit[1].front[1] < 0.002f);
    ENSURE(!crosses[1]);
}

// A roof slab (y 2.0 to 2.2) over a floor, seen from above and from the front
// with four layers: under the roof is free space; a drop through the roof hits
// its top; a particle rising under it hits its underside (layer 1, normal down)
// and is put back below it.
TEST(overhang_layers_free_under_the_roof_and_hit_its_underside)
{
    lay_world world = { 0 };
    fx_box(&world.solids, -3, -1, -3, 3, 0, 3);        // floor
    fx_box(&world.solids, -1, 2.0f, -1, 1, 2.2f, 1);   // roof
    wx_camera cams[2] = { fx_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 6.4f, 64), top_camera(6.4f, 64) };
    wx_maps maps[2];
    wx_collider col;
    ENSURE(build_layers(&col, cams, maps, 2, &world, 4));
    float a0[3] = { -1.5f, 1.23f, 0.27f }, a1[3] = { 1.5f, 1.23f, 0.31f };   // under the roof
    float b0[3] = { 0.33f, 3.0f, 0.27f }, b1[3] = { 0.33f, 1.0f, 0.27f };    // falls on it
    float c0[3] = { 0.33f, 1.0f, 0.27f }, c1[3] = { 0.33f, 2.1f, 0.27f };    // rises under it
    float under[3] = { 0.1f, 1.5f, 0.1f }, inside[3] = { 0.1f, 2.1f, 0.1f };
    wx_hit side, top, below;
    bool hs = wx_collider_sweep(&col, a0, a1, &side);
    bool ht = wx_collider_sweep(&col, b0, b1, &top);
    bool hb = wx_collider_sweep(&col, c0, c1, &below);
    bool pu = wx_collider_point_collides(&col, under), pi = wx_collider_point_collides(&col, inside);
    bool front_out = hb && !wx_collider_point_collides(&col, below.front);
    release(&col, maps, 2);
    ENSURE(!hs);
    ENSURE(!pu && pi);
    ENSURE(ht && hb);
    ENSURE_NEAR(top.s, 0.4, 1e-5 * 0.4);
    ENSURE_NEAR(top.point[1], 2.2, 1e-5);
    ENSURE(top.layer == 0 && top.camera == 1);
    ENSURE_NEAR(top.normal[1], 1.0, 1e-6);
    ENSURE_NEAR(below.s, 1.0 / 1.1, 1e-5 / 1.1);
    ENSURE_NEAR(below.point[1], 2.0, 1e-5);
    ENSURE(below.camera == 1 && below.layer == 1);
    ENSURE_NEAR(below.normal[1], -1.0, 1e-6);
    ENSURE(below.absorption == 0.1f);
    ENSURE(below.front[1] < 2.0f && below.front[1] > 1.998f); // put back below it
    ENSURE(front_out);
}

// The underside of a tilted roof (y = 2 + 0.2 x): the layer's bilinear depth is
// exact on a plane, so a rising particle hits the underside where the plane is.
TEST(tilted_underside_hit_is_exact)
{
    lay_world world = { 0 };
    fx_box(&world.solids, -3, -1, -3, 3, 0, 3);
    fx_solid *roof = fx_box(&world.solids, -1.5f, 1.0f, -1, 1.5f, 3.5f, 1);
    fx_plane(roof, -0.2f, 1.0f, 0.0f, 2.2f);   // y - 0.2 x <= 2.2
    fx_plane(roof, 0.2f, -1.0f, 0.0f, -2.0f);  // y - 0.2 x >= 2.0
    wx_camera cam = top_camera(6.4f, 64);
    wx_maps maps;
    wx_collider col;
    ENSURE(build_layers(&col, &cam, &maps, 1, &world, 4));
    double worst = 0.0;
    int hits = 0, layer1 = 0;
    for (int i = 0; i < 200; ++i) {
        float x = -1.2f + 2.4f * (float)i / 200.0f, z = -0.8f + 1.6f * (float)((i * 37) % 200) / 200.0f;
        float p0[3] = { x, 1.0f, z }, p1[3] = { x, 3.0f, z };
        wx_hit hit;
        if (!wx_collider_sweep(&col, p0, p1, &hit)) {
            continue;
        }
        hits++;
        layer1 += hit.layer == 1 && hit.normal[1] < 0.0f;
        double s = ((2.0 + 0.2 * x) - 1.0) / 2.0; // analytic crossing of the underside
        worst = fmax(worst, fabs(hit.s - s) / s);
    }
    release(&col, &maps, 1);
    ENSURE(hits == 200);
    ENSURE(layer1 == 200);
    ENSURE(worst < 1e-5);
}

// A one-sided pane (z = 1, normal +z) in front of a wall (z -1 to 0), seen
// from the front and from behind with four layers. A segment crossing the pane
// from the front hits it there; one from behind, between pane and wall, hits
// its back a quarter texel (the sheet's slab) behind it, with the normal turned
// towards the particle; the space between pane and wall is free.
TEST(pane_is_a_thin_sheet_hit_from_either_side)
{
    lay_world world = { 0 };
    fx_box(&world.solids, -2, 0, -1, 2, 3, 0);              // wall
    sheet(&world, -1, 0.5f, 1, 1, 2.5f, 1, 0.0f, 0.0f, 1.0f); // pane
    wx_camera cams[2] = { fx_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 6.4f, 64),
                          fx_camera(0, 0, -10, 0, 0, 0, 0, 1, 0, 6.4f, 64) };
    wx_maps maps[2];
    wx_collider col;
    ENSURE(build_layers(&col, cams, maps, 2, &world, 4));
    float t = 0.25f * col.cameras[0].texel_ws; // the sheet's thickness
    float f0[3] = { 0.33f, 1.27f, 2.0f }, f1[3] = { 0.33f, 1.27f, 0.5f };
    float b0[3] = { 0.33f, 1.27f, 0.5f }, b1[3] = { 0.33f, 1.27f, 2.0f };
    float g0[3] = { -0.8f, 1.27f, 0.5f }, g1[3] = { 0.8f, 1.6f, 0.3f }; // between pane and wall
    float w0[3] = { 0.33f, 1.27f, 0.5f }, w1[3] = { 0.33f, 1.27f, -0.5f }; // onto the wall
    float gap[3] = { 0.1f, 1.5f, 0.5f };
    wx_hit front, back, free_hit, wall;
    bool hf = wx_collider_sweep(&col, f0, f1, &front);
    bool hb = wx_collider_sweep(&col, b0, b1, &back);
    bool hg = wx_collider_sweep(&col, g0, g1, &free_hit);
    bool hw = wx_collider_sweep(&col, w0, w1, &wall);
    bool pg = wx_collider_point_collides(&col, gap);
    bool out_f = hf && !wx_collider_point_collides(&col, front.front);
    bool out_b = hb && !wx_collider_point_collides(&col, back.front);
    release(&col, maps, 2);
    ENSURE(!hg && !pg);
    ENSURE(hf && hb && hw);
    ENSURE_NEAR(front.s, 1.0 / 1.5, 1e-5);
    ENSURE_NEAR(front.point[2], 1.0, 1e-5);
    ENSURE_NEAR(front.normal[2], 1.0, 1e-6);
    ENSURE(front.front[2] > 1.0f && front.front[2] < 1.002f);
    double sb = (1.0 - t - 0.5) / 1.5; // where z = 1 - t, from z = 0.5
    ENSURE_NEAR(back.s, sb, 1e-5 * sb);
    ENSURE_NEAR(back.normal[2], -1.0, 1e-6); // flipped towards the particle
    ENSURE(back.front[2] < 1.0f - t && back.front[2] > 1.0f - t - 0.002f);
    ENSURE(out_f && out_b);
    ENSURE_NEAR(wall.point[2], 0.0, 1e-5); // the wall's front, as before
    ENSURE(wall.layer == 1 && wall.camera == 0);
}

// Random segments through a layered scene (an overhang on posts over a floor, a
// pane) seen by three cameras with four layers: the coarse test never clears a
// segment that hits; the sweep agrees with the point rule (no point before the
// hit collides, and without a hit none along the segment does); every put-back
// point is outside.
// A porch: a floor, a roof on a post, a block under the roof and a pane in
// front, seen by a front, a side and a top camera of 128 px (and, when asked,
// a back camera, which sees the pane from behind).
static void porch(lay_world *world, wx_camera cams[4])
{
    fx_box(&world->solids, -3, -1, -3, 3, 0, 3);                         // floor
    fx_box(&world->solids, -1.5f, 1.5f, -1.5f, 1.5f, 1.8f, 1.5f);        // roof
    fx_box(&world->solids, -1.5f, 0, -1.5f, -1.2f, 1.5f, -1.2f);         // a post
    fx_box(&world->solids, 0.3f, 0.3f, -0.4f, 0.7f, 0.6f, 0.2f);         // a block under the roof
    sheet(world, -2.0f, 0.2f, 2.2f, 2.0f, 1.2f, 2.2f, 0.0f, 0.0f, 1.0f); // pane
    cams[0] = fx_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 7, 128);
    cams[1] = fx_camera(10, 0, 0, 0, 0, 0, 0, 1, 0, 7, 128);
    cams[2] = top_camera(7, 128);
    cams[3] = fx_camera(0, 0, -10, 0, 0, 0, 0, 1, 0, 7, 128);
}

TEST(layered_sweep_agrees_with_the_point_rule)
{
    lay_world world = { 0 };
    wx_camera cams[4];
    porch(&world, cams);
    wx_maps maps[3];
    wx_collider col;
    ENSURE(build_layers(&col, cams, maps, 3, &world, 4));
    uint64_t state = 7;
    int hits = 0, cleared = 0, contradictions = 0, early = 0, missed = 0, bad_front = 0;
    int phantom = 0;
    for (int i = 0; i < 40000; ++i) {
        float r[6];
        uniforms(&state, r, 6);
        float len = (i % 4 == 0) ? 2.0f : 0.3f;
        float p0[3] = { -3.2f + 6.4f * r[0], -0.5f + 3.0f * r[1], -3.2f + 6.4f * r[2] };
        float p1[3] = { p0[0] + len * (r[3] - 0.5f), p0[1] + len * (r[4] - 0.5f),
                        p0[2] + len * (r[5] - 0.5f) };
        if (wx_collider_point_collides(&col, p0)) {
            continue;
        }
        wx_hit hit;
        bool h = wx_collider_sweep(&col, p0, p1, &hit);
        bool clear = wx_collider_coarse_clear(&col, p0, p1);
        cleared += clear;
        contradictions += clear && h;
        double end = h ? hit.s - 1e-4 : 1.0;
        for (int k = 0; k <= 64; ++k) {
            double s = end * k / 64.0;
            float q[3];
            for (int a = 0; a < 3; ++a) {
                q[a] = (float)(p0[a] + s * ((double)p1[a] - p0[a]));
            }
            if (wx_collider_point_collides(&col, q)) {
                early += h;
                missed += !h;
                break;
            }
        }
        if (h) {
            hits++;
            bad_front += wx_collider_point_collides(&col, hit.front);
            // Just after the hit (a hundredth of a texel on) the segment is inside.
            bool inside = false;
            double seg = sqrt(((double)p1[0] - p0[0]) * ((double)p1[0] - p0[0]) +
                              ((double)p1[1] - p0[1]) * ((double)p1[1] - p0[1]) +
                              ((double)p1[2] - p0[2]) * ((double)p1[2] - p0[2]));
            for (int k = 1; k <= 4 && !inside; ++k) {
                double s = fmin(1.0, hit.s + k * 0.0025 * col.cameras[0].texel_ws / seg);
                float q[3];
                for (int a = 0; a < 3; ++a) {
                    q[a] = (float)(p0[a] + s * ((double)p1[a] - p0[a]));
                }
                inside = wx_collider_point_collides(&col, q);
            }
            // A hit a thousandth of a texel from a texel's border may round
            // into the texel on the other side (a slab's corner clipped at a
            // sheet's edge): not a phantom.
            bool on_border = false;
            for (int c = 0; c < 3; ++c) {
                const wx_collider_camera *cm = &col.cameras[c];
                const float *q = hit.point;
                double X = q[0] * cm->mx[0] + q[1] * cm->mx[1] + q[2] * cm->mx[2] + cm->mx[3];
                double Y = q[0] * cm->my[0] + q[1] * cm->my[1] + q[2] * cm->my[2] + cm->my[3];
                on_border |= fabs(X - round(X)) < 1e-3 || fabs(Y - round(Y)) < 1e-3;
            }
            phantom += !inside && !on_border;
        }
    }
    release(&col, maps, 3);
    ENSURE(contradictions == 0);
    ENSURE(early == 0);
    ENSURE(missed == 0);
    ENSURE(bad_front == 0);
    ENSURE(phantom == 0);
    ENSURE(hits > 1500);
    ENSURE(cleared > 20000);
}

// The fine test (wx_collider_fine_clear, which accessibility's rays ask before
// the swept test) never clears a segment the swept test stops, with one layer
// and with four (the pane seen from behind: a sheet's slab starts in front of
// its crossing): random segments, and segments leaving a hit's put-back point
// in every direction, where it is tightest. And it clears most of those that
// leave the surface.
TEST(fine_test_never_clears_what_the_sweep_stops)
{
    lay_world world = { 0 };
    wx_camera cams[4];
    porch(&world, cams);
    // The porch's cameras, and three that see every face at an angle (where
    // a texel's neighbours lie nearer than itself).
    wx_camera oblique[4] = { fx_camera(8, 6, 5, 0, 0.5f, 0, 0, 1, 0, 9, 128),
                             fx_camera(-6, 7, 8, 0, 0.5f, 0, 0, 1, 0, 9, 128),
                             fx_camera(5, 6, -8, 0, 0.5f, 0, 0, 1, 0, 9, 128), cams[3] };
    for (int run = 0; run < 4; ++run) {
        int layers = run % 2 == 0 ? 1 : 4;
        wx_camera *set = run < 2 ? cams : oblique;
        wx_maps maps[4];
        wx_collider col;
        ENSURE(build_layers(&col, set, maps, 4, &world, layers));
        uint64_t state = 11;
        int contradictions = 0, cleared = 0, near = 0, near_cleared = 0, near_free = 0;
        for (int i = 0; i < 50000; ++i) {
            float r[9];
            uniforms(&state, r, 9);
            float len = (i % 4 == 0) ? 2.0f : 0.3f;
            float p0[3] = { -3.2f + 6.4f * r[0], -0.5f + 3.0f * r[1], -3.2f + 6.4f * r[2] };
            if (i % 5 == 0) {
                // Just behind the pane (z 2.2), towards it: its slab seen from
                // behind starts a sheet in front of the back camera's crossing.
                p0[0] = -1.8f + 3.6f * r[0];
                p0[1] = 0.3f + 0.8f * r[1];
                p0[2] = 2.2f - 0.05f * r[2];
                len = 0.1f;
            }
            float p1[3] = { p0[0] + len * (r[3] - 0.5f), p0[1] + len * (r[4] - 0.5f),
                            p0[2] + len * (r[5] - 0.5f) };
            if (wx_collider_point_collides(&col, p0)) {
                continue;
            }
            wx_hit hit, again;
            bool h = wx_collider_sweep(&col, p0, p1, &hit);
            bool fine = wx_collider_fine_clear(&col, p0, p1);
            cleared += fine;
            contradictions += fine && h;
            if (!h) {
                continue;
            }
            // From the put-back point, up to 10 texels in any direction.
            float q1[3];
            for (int a = 0; a < 3; ++a) {
                q1[a] = hit.front[a] + 0.6f * (r[6 + a] - 0.5f);
            }
            bool stops = wx_collider_sweep(&col, hit.front, q1, &again);
            bool clears = wx_collider_fine_clear(&col, hit.front, q1);
            near++;
            near_free += !stops;
            near_cleared += clears;
            contradictions += clears && stops;
        }
        fprintf(stderr,
                "        %s, %d layer%s: random segments cleared %d; from a surface %d, %d free, "
                "%d of them cleared\n",
                run < 2 ? "axes" : "oblique", layers, layers > 1 ? "s" : "", cleared, near,
                near_free, near_cleared);
        release(&col, maps, 4);
        ENSURE(contradictions == 0);
        ENSURE(near > 1500);
        ENSURE(near_cleared > near_free / (run < 2 ? 4 : 8)); // (oblique: fewer)
    }
    // The pane alone between a front and a back camera, which agree on its
    // slab: segments inside the slab, in front of the back camera's crossing,
    // are stopped, and the fine test must not clear them.
    lay_world pane = { 0 };
    sheet(&pane, -2.0f, 0.2f, 2.2f, 2.0f, 1.2f, 2.2f, 0.0f, 0.0f, 1.0f);
    wx_camera two[2] = { cams[0], cams[3] };
    wx_maps maps[2];
    wx_collider col;
    ENSURE(build_layers(&col, two, maps, 2, &pane, 4));
    double slab = col.cameras[1].sheet; // d units are world units here
    int stopped = 0, contradictions = 0;
    for (int i = 0; i < 200; ++i) {
        float x = -1.5f + 0.015f * (float)i, y = 0.7f;
        float z = (float)(2.2 - slab * (0.1 + 0.8 * (i % 10) / 10.0));
        float p0[3] = { x, y, z }, p1[3] = { x + 0.01f, y, z };
        wx_hit hit;
        bool stops = wx_collider_sweep(&col, p0, p1, &hit);
        stopped += stops;
        contradictions += stops && wx_collider_fine_clear(&col, p0, p1);
    }
    release(&col, maps, 2);
    fprintf(stderr, "        in the pane's slab: %d of 200 stopped\n", stopped);
    ENSURE(stopped > 100);
    ENSURE(contradictions == 0);
}

// A map whose only layer is given as layers = 1 works exactly as one with
// layers = 0 (version 2's maps), bit for bit.
TEST(one_layer_is_todays_collider)
{
    lay_world world = { 0 };
    fx_box(&world.solids, -1, -1, -1, 1, 1, 1);
    fx_box(&world.solids, -3, -2, -3, 3, -1.5f, 3);
    wx_camera cams[2] = { fx_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 7, 64), top_camera(7, 64) };
    wx_hit h[2][200];
    bool r[2][200];
    for (int mode = 0; mode < 2; ++mode) {
        wx_maps maps[2];
        wx_collider col;
        ENSURE(build_layers(&col, cams, maps, 2, &world, 1));
        for (int c = 0; c < 2; ++c) {
            maps[c].layers = mode; // 0 or 1: one layer
        }
        wx_collider_free(&col);
        wx_error err;
        ENSURE(wx_collider_init(&col, cams, maps, 2, false, &err) == WX_OK);
        uint64_t state = 11;
        for (int i = 0; i < 200; ++i) {
            float v[6];
            for (int q = 0; q < 6; ++q) {
                state = wx_mix64(state + 1);
                v[q] = -3.0f + 6.0f * (float)((state >> 11) * (1.0 / 9007199254740992.0));
            }
            memset(&h[mode][i], 0, sizeof h[mode][i]);
            r[mode][i] = wx_collider_sweep(&col, v, v + 3, &h[mode][i]);
        }
        release(&col, maps, 2);
    }
    int hits = 0;
    for (int i = 0; i < 200; ++i) {
        ENSURE(r[0][i] == r[1][i]);
        ENSURE(memcmp(&h[0][i], &h[1][i], sizeof h[0][i]) == 0);
        hits += r[0][i];
    }
    ENSURE(hits > 20);
}

// A block seen by two cameras facing each other, both with layers: each sees
// its near face from outside (layer 0) and the far face through the block
// (layer 1), equally head-on. A drop flying into the front face is recorded by
// the camera outside it (ownership's tie rule), though the back camera is
// listed first: else a surface's deposits follow where its layer index
// changes, which turning the model moves (docs/physics.md, "Layered maps").
// The block (x -1..1, y 0..1, z -0.5..0.5) and its back and front cameras.
static void facing_block(lay_world *world, wx_camera cams[2])
{
    memset(world, 0, sizeof *world);
    fx_box(&world->solids, -1, 0, -0.5f, 1, 1, 0.5f);
    cams[0] = fx_camera(0, 0, -10, 0, 0, 0, 0, 1, 0, 6.4f, 64);
    cams[1] = fx_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 6.4f, 64);
}

TEST(facing_cameras_tie_to_the_one_outside_the_surface)
{
    lay_world world;
    wx_camera cams[2];
    facing_block(&world, cams);
    wx_maps maps[2];
    wx_collider col;
    ENSURE(build_layers(&col, cams, maps, 2, &world, 4));
    float f0[3] = { 0.13f, 0.47f, 2.0f }, f1[3] = { 0.13f, 0.47f, 0.0f };
    float b0[3] = { -0.21f, 0.53f, -2.0f }, b1[3] = { -0.21f, 0.53f, 0.0f };
    wx_hit front, back;
    bool hf = wx_collider_sweep(&col, f0, f1, &front);
    bool hb = wx_collider_sweep(&col, b0, b1, &back);
    release(&col, maps, 2);
    ENSURE(hf && hb);
    ENSURE_NEAR(front.point[2], 0.5, 1e-5);
    ENSURE(front.camera == 1 && front.layer == 0);
    ENSURE_NEAR(back.point[2], -0.5, 1e-5);
    ENSURE(back.camera == 0 && back.layer == 0);
}

// A block seen from above and from the front (texels of 0.1 m). A drop falling
// 3 cm behind the front edge lands on the top; a drop flying level into the
// front face 3 cm below the edge lands on the front. Each time the other
// camera's surface lies within its precision of the hit (half a texel, and
// with layers a texel more) and sees its own face as head-on, so the most
// head-on rule alone gave the top's hit to the front camera, which put the
// drop back in front of the wall: off the roof it had landed on (collider.c,
// pick_camera: the surface the segment enters decides).
TEST(a_drop_by_an_edge_is_recorded_on_the_face_it_lands_on)
{
    // Both orders of the cameras: ties of |N.view| go to the one listed first.
    for (int run = 0; run < 4; ++run) {
        int layers = run < 2 ? 1 : 4, top = run & 1, front = 1 - top;
        lay_world world;
        memset(&world, 0, sizeof world);
        fx_box(&world.solids, -1, 0, -0.5f, 1, 1, 0.5f);
        wx_camera cams[2];
        cams[top] = top_camera(6.4f, 64);
        cams[front] = fx_camera(0, 0.5f, 10, 0, 0.5f, 0, 0, 1, 0, 6.4f, 64);
        wx_maps maps[2];
        wx_collider col;
        ENSURE(build_layers(&col, cams, maps, 2, &world, layers));
        float a0[3] = { 0.13f, 2.0f, 0.47f }, a1[3] = { 0.13f, 0.5f, 0.47f };
        float b0[3] = { 0.13f, 0.97f, 2.0f }, b1[3] = { 0.13f, 0.97f, 0.0f };
        wx_hit down, level;
        bool hd = wx_collider_sweep(&col, a0, a1, &down);
        bool hl = wx_collider_sweep(&col, b0, b1, &level);
        release(&col, maps, 2);
        ENSURE(hd && hl);
        fprintf(stderr, "        %d layer(s), %s first: falling on the %s, level on the %s\n", layers,
                top == 0 ? "top" : "front", down.camera == top ? "top" : "front",
                level.camera == top ? "top" : "front");
        ENSURE(down.camera == top);
        ENSURE_NEAR(down.point[1], 1.0, 1e-4);
        ENSURE(down.front[1] >= 1.0f && down.front[2] < 0.5f); // back on the top
        ENSURE(level.camera == front);
        ENSURE_NEAR(level.point[2], 0.5, 1e-4);
        ENSURE(level.front[2] >= 0.5f);
    }
}

// The same block: its front face is owned by the front camera's first layer,
// not by the back camera's second, which is listed first (model/ownership.h).
TEST(ownership_ties_go_to_the_view_outside_the_surface)
{
    lay_world world;
    wx_camera cams[2];
    facing_block(&world, cams);
    wx_maps maps[2];
    for (int c = 0; c < 2; ++c) {
        render_layers(&cams[c], &world, 4, &maps[c]);
    }
    wx_owner_view views[4];
    size_t texels = (size_t)maps[0].width * (size_t)maps[0].height;
    for (int c = 0; c < 2; ++c) {
        for (int k = 0; k < 2; ++k) {
            wx_owner_view *v = &views[2 * c + k];
            wx_owner_view_init(v, &cams[c], maps[c].depth + (size_t)k * texels, maps[c].width,
                               maps[c].height);
            v->normal = maps[c].normal + 3 * (size_t)k * texels;
        }
    }
    const double on_front[3] = { 0.13, 0.47, 0.5 }, on_back[3] = { -0.21, 0.53, -0.5 };
    const float out_front[3] = { 0, 0, 1 }, out_back[3] = { 0, 0, -1 };
    int owner_front = wx_owner_of(views, 4, on_front, out_front, -1);
    int owner_back = wx_owner_of(views, 4, on_back, out_back, -1);
    bool back_sees_front = wx_owner_sees(&views[1], on_front, out_front);
    wx_maps_free(&maps[0]);
    wx_maps_free(&maps[1]);
    ENSURE(back_sees_front); // the tie is real: the back camera's layer 1 holds it
    ENSURE(owner_front == 2);
    ENSURE(owner_back == 0);
}

// A camera's depth and normal maps of the cylinder x^2 + y^2 = 1 and, behind
// it as the side camera sees it, the block 1.5 <= x <= 2, -1 <= y <= 1.2 (both
// along z): the first `layers` crossings of each texel's ray (layer k's block
// at k*W*H), outward normals.
static void render_cylinder(const wx_camera *cam, int layers, float *depth, float *normal)
{
    int W = cam->width, H = cam->height;
    size_t plane = (size_t)W * (size_t)H;
    float dir[3];
    wx_camera_view_dir(cam, dir);
    const double d[3] = { dir[0], dir[1], dir[2] };
    const double lo[2] = { 1.5, -1.0 }, hi[2] = { 2.0, 1.2 };
    for (int j = 0; j < H; ++j) {
        for (int i = 0; i < W; ++i) {
            size_t t = (size_t)j * (size_t)W + (size_t)i;
            float o[3];
            texel_origin(cam, i, j, o);
            crossing list[4];
            int count = 0;
            // |o + s d|^2 = 1 in x, y: both roots, normals out.
            double a = d[0] * d[0] + d[1] * d[1];
            double b = 2.0 * (o[0] * d[0] + o[1] * d[1]);
            double c = (double)o[0] * o[0] + (double)o[1] * o[1] - 1.0;
            double disc = b * b - 4.0 * a * c;
            for (int r = 0; r < 2 && a > 0.0 && disc > 0.0; ++r) {
                double s = (-b + (r == 0 ? -1.0 : 1.0) * sqrt(disc)) / (2.0 * a);
                crossing *x = &list[count++];
                x->t = s;
                x->n[0] = (float)(o[0] + s * d[0]);
                x->n[1] = (float)(o[1] + s * d[1]);
                x->n[2] = 0.0f;
            }
            // The block: the slabs in x and y (the cameras look along an axis).
            double enter = -INFINITY, leave = INFINITY;
            int in_axis = -1, out_axis = -1;
            for (int k = 0; k < 2; ++k) {
                if (d[k] == 0.0) {
                    if (o[k] < lo[k] || o[k] > hi[k]) {
                        leave = -INFINITY;
                    }
                    continue;
                }
                double s0 = (lo[k] - o[k]) / d[k], s1 = (hi[k] - o[k]) / d[k];
                if (fmin(s0, s1) > enter) {
                    enter = fmin(s0, s1);
                    in_axis = k;
                }
                if (fmax(s0, s1) < leave) {
                    leave = fmax(s0, s1);
                    out_axis = k;
                }
            }
            if (in_axis >= 0 && out_axis >= 0 && enter <= leave) {
                crossing in = { enter, { 0.0f, 0.0f, 0.0f } };
                crossing out = { leave, { 0.0f, 0.0f, 0.0f } };
                in.n[in_axis] = (float)-copysign(1.0, d[in_axis]);
                out.n[out_axis] = (float)copysign(1.0, d[out_axis]);
                list[count++] = in;
                list[count++] = out;
            }
            sort_crossings(list, count, d);
            for (int k = 0; k < layers; ++k) {
                size_t q = (size_t)k * plane + t;
                depth[q] = k < count ? (float)list[k].t : INFINITY;
                for (int e = 0; e < 3; ++e) {
                    normal[3 * q + e] = k < count ? list[k].n[e] : 0.0f;
                }
            }
        }
    }
}

// A cylinder lying along z under a top camera and a side camera (along +x)
// of two layers, which sees a block behind it above its silhouette. Along the
// side camera's silhouette (its top rows) the cylinder faces up: the top
// camera sees it head-on and owns it, and the collider gives it every deposit
// there. The side camera's texels there must own none of it, in either layer.
// Their points between texel centres lie centimetres to metres off the
// surface: between the cylinder's grazing depths and the block's in the first
// layer, between the cylinder's far side and the block's back in the second.
// Held to the top camera's tolerance of a millimetre they went to the side
// camera (a quarter to a third of each silhouette texel on Spot's back), so
// the gather divided the top camera's dirt by a share the side camera held
// empty: a dark streak along the silhouette that moved with the model in the
// camera grid (docs/mask.md, "One estimate from all cameras").
TEST(a_grazing_silhouette_owns_nothing_another_view_sees_head_on)
{
    enum { PX = 128, LAYERS = 2 };
    wx_camera cams[2] = { fx_camera(0, 10, 0, 0, 0, 0, 0, 0, -1, 2.56f, PX),
                          fx_camera(-10, 0, 0, 0, 0, 0, 0, 1, 0, 2.56f, PX) };
    size_t texels = (size_t)PX * PX;
    float *depth = malloc(2 * LAYERS * texels * sizeof *depth);
    float *normal = malloc(6 * LAYERS * texels * sizeof *normal);
    float *owned = malloc(texels * sizeof *owned);
    ENSURE(depth != NULL && normal != NULL && owned != NULL);
    wx_owner_view views[2 * LAYERS];
    for (int c = 0; c < 2; ++c) {
        float *dc = depth + (size_t)c * LAYERS * texels;
        float *nc = normal + 3 * (size_t)c * LAYERS * texels;
        render_cylinder(&cams[c], LAYERS, dc, nc);
        for (int k = 0; k < LAYERS; ++k) {
            wx_owner_view *v = &views[c * LAYERS + k];
            wx_owner_view_init(v, &cams[c], dc + k * texels, PX, PX);
            v->normal = nc + 3 * k * texels;
        }
    }
    wx_error err;
    int up = 0, wrong_up = 0, side = 0, wrong_side = 0;
    double worst = 0.0;
    for (int k = 0; k < LAYERS; ++k) {
        const int self = LAYERS + k; // the side camera's layer k
        const float *d = views[self].depth, *n = views[self].normal;
        ENSURE(wx_owned_fraction(views, 2 * LAYERS, self, n, n + 1, n + 2, 3, 1, owned, &err) ==
               WX_OK);
        for (size_t t = 0; t < texels; ++t) {
            float nx = fabsf(n[3 * t]), ny = n[3 * t + 1]; // the top camera sees ny > 0
            if (wx_depth_is_empty(d[t]) || d[t] > 11.1f) {
                continue; // no surface, or the block's (11.5 and 12 away)
            }
            if (ny > nx + 0.2f) { // the top camera sees it clearly more head-on
                up++;
                wrong_up += owned[t] > 0.0f;
                worst = fmax(worst, owned[t]);
            } else if (nx > fabsf(ny) + 0.2f) {
                side++;
                wrong_side += owned[t] < 1.0f;
            }
        }
    }
    printf("        side camera: %d texels facing up (%d owning some, worst %.3f), %d facing it "
           "(%d not wholly owned)\n",
           up, wrong_up, worst, side, wrong_side);
    free(depth);
    free(normal);
    free(owned);
    ENSURE(up > 2000 && side > 2000);
    ENSURE(wrong_up == 0);
    ENSURE(wrong_side == 0);
}

// The same cylinder under the top camera and the side camera, both of two
// layers: drops falling onto its upper left quarter, around where the two
// cameras see it equally head-on (the normal at 45 degrees). The collider
// gives each hit to the camera that sees it most head-on by that camera's own
// texel's normal; the gather divides what a texel holds by the share of its
// surface its camera owns (wx_owned_fraction). Both must draw the border
// between the cameras' parts in the same place: when the shares compared
// every view by the normal of the texel whose share was asked, a band of a
// fraction of a texel along the border went to one camera's hits and to the
// other's share, so the first read too much there and the second too little,
// wherever the texel grids put that band; on Spot, whose horns and ears meet
// the head in tight curves, that turned with the model in the camera grid
// (docs/performance.md, "One border for the collider and the gather").
TEST(a_hit_on_a_curve_lands_where_its_camera_owns_the_surface)
{
    enum { PX = 128, LAYERS = 2, DROPS = 4000 };
    wx_camera cams[2] = { fx_camera(0, 10, 0, 0, 0, 0, 0, 0, -1, 2.56f, PX),
                          fx_camera(-10, 0, 0, 0, 0, 0, 0, 1, 0, 2.56f, PX) };
    size_t texels = (size_t)PX * PX;
    wx_maps maps[2];
    wx_owner_view views[2 * LAYERS];
    float *owned = malloc(2 * LAYERS * texels * sizeof *owned);
    ENSURE(owned != NULL);
    for (int c = 0; c < 2; ++c) {
        layered_maps(&cams[c], LAYERS, &maps[c]);
        render_cylinder(&cams[c], LAYERS, maps[c].depth, maps[c].normal);
        for (size_t q = 0; q < LAYERS * texels; ++q) {
            maps[c].impact[2 * q + 1] = 0.5f;
        }
        for (int k = 0; k < LAYERS; ++k) {
            wx_owner_view *v = &views[c * LAYERS + k];
            wx_owner_view_init(v, &cams[c], maps[c].depth + k * texels, PX, PX);
            v->normal = maps[c].normal + 3 * k * texels;
        }
    }
    wx_error err;
    for (int v = 0; v < 2 * LAYERS; ++v) {
        const float *n = views[v].normal;
        ENSURE(wx_owned_fraction(views, 2 * LAYERS, v, n, n + 1, n + 2, 3, 1,
                                 owned + (size_t)v * texels, &err) == WX_OK);
    }
    wx_collider col;
    ENSURE(wx_collider_init(&col, cams, maps, 2, false, &err) == WX_OK);
    // x from -0.85 to -0.55 (the normal from 58 to 34 degrees above the
    // horizontal), z across the middle of the frames.
    uint64_t state = 25;
    int hits = 0, by_side = 0, unowned = 0;
    for (int q = 0; q < DROPS; ++q) {
        float r[2];
        uniforms(&state, r, 2);
        float x = -0.85f + 0.3f * ((float)q + r[0]) / DROPS, z = -0.8f + 1.6f * r[1];
        float a[3] = { x, 2.0f, z }, b[3] = { x, 0.0f, z };
        wx_hit hit;
        if (!wx_collider_sweep(&col, a, b, &hit)) {
            continue;
        }
        hits++;
        by_side += hit.camera == 1;
        int v = hit.camera * LAYERS + hit.layer;
        unowned += owned[(size_t)v * texels + hit.texel] == 0.0f;
    }
    printf("        %d drops: %d hits, %d recorded by the side camera, %d in a texel whose "
           "camera owns none of it\n",
           DROPS, hits, by_side, unowned);
    wx_collider_free(&col);
    wx_maps_free(&maps[0]);
    wx_maps_free(&maps[1]);
    free(owned);
    ENSURE(hits == DROPS);
    ENSURE(by_side > DROPS / 4 && by_side < 3 * DROPS / 4); // the border lies in the range
    ENSURE(unowned == 0);
}

// A wall seen at 40 degrees by a side camera of two layers, just below a roof
// sloping at 30 degrees that a top camera of two layers holds 15 cm (1.5 of
// its texels) above the wall's point. The top camera sees the roof more
// head-on than the side camera sees the wall, but it does not see the wall:
// its layer's precision is that of the roof it records there. Read with the
// wall's normal (nearly along the top camera's rays: a precision of tens of
// texels) the roof's layer took the wall under the eave, which the collider
// never gives it a hit on (the tank's walls under its roof and its ring went
// dark in the soot preset's mask).
TEST(a_wall_below_an_eave_is_not_owned_by_the_roof_above_it)
{
    enum { PX = 16, LAYERS = 2 };
    wx_camera cams[2] = { fx_camera(0, 10, 0, 0, 0, 0, 0, 0, -1, 1.6f, PX),
                          fx_camera(-10, 0, 0, 0, 0, 0, 0, 1, 0, 1.6f, PX) };
    const double p[3] = { 0.0, 0.0, 0.0 }, roof[3] = { 0.0, 0.15, 0.0 };
    const float wall_n[3] = { -0.766044f, 0.0f, 0.642788f };  // 40 degrees off the side's axis
    const float roof_n[3] = { -0.5f, 0.866025f, 0.0f };       // 30 degrees off the top's
    size_t texels = (size_t)PX * PX;
    float *depth = malloc(2 * LAYERS * texels * sizeof *depth);
    float *normal = malloc(6 * LAYERS * texels * sizeof *normal);
    ENSURE(depth != NULL && normal != NULL);
    wx_owner_view views[2 * LAYERS];
    for (int c = 0; c < 2; ++c) {
        double uvd[3];
        wx_matrix_apply_affine(cams[c].wtc, c == 0 ? roof : p, uvd);
        const float *n = c == 0 ? roof_n : wall_n;
        for (int k = 0; k < LAYERS; ++k) {
            size_t at = ((size_t)c * LAYERS + (size_t)k) * texels;
            for (size_t t = 0; t < texels; ++t) {
                depth[at + t] = k == 0 ? (float)uvd[2] : INFINITY;
                for (int e = 0; e < 3; ++e) {
                    normal[3 * (at + t) + (size_t)e] = k == 0 ? n[e] : 0.0f;
                }
            }
            wx_owner_view *v = &views[c * LAYERS + k];
            wx_owner_view_init(v, &cams[c], depth + at, PX, PX);
            v->normal = normal + 3 * at;
        }
    }
    int owner = wx_owner_of(views, 2 * LAYERS, p, wall_n, -1);
    bool side_sees = wx_owner_sees(&views[LAYERS], p, wall_n);
    bool top_sees = wx_owner_sees(&views[0], p, wall_n);
    free(depth);
    free(normal);
    ENSURE(side_sees);
    ENSURE(!top_sees);
    ENSURE(owner == LAYERS); // the side camera's first layer
}

// 40 drops falling straight down from height `top` to below the floor
// (y = 0), at x across -1.5..1.35 and z = z0 + dz * i: those that hit the
// floor, to within the front camera's texel (its ramp from the floor's front
// to the wall, as with one layer), and those stopped above it.
static void drop_onto_the_floor(const wx_collider *col, float top, float z0, float dz, int *landed,
                                int *stopped)
{
    for (int i = 0; i < 40; ++i) {
        float x = -1.5f + 0.0731f * (float)i, z = z0 + dz * (float)i;
        float a[3] = { x, top, z }, b[3] = { x, -0.4f, z };
        wx_hit hit;
        if (wx_collider_sweep(col, a, b, &hit)) {
            *landed += fabsf(hit.point[1]) <= 0.05f;
            *stopped += hit.point[1] > 0.05f;
        }
    }
}

// A handrail in front of a wall, under two slabs that use up the top camera's
// four layers (so below them it cannot tell free space: its tail). In the
// front camera's row where the handrail ends, layer 0 is the handrail in one
// texel and the wall in the next: a ramp between them was a thin solid slab
// through the free space, and a drop falling between the wall and the
// handrail stopped in mid air at the handrail's height (bench_embree's sill
// tops behind the balcony: 170 of 221 drops before, 216 after).
TEST(layer_ramp_does_not_jump_from_a_handrail_to_the_wall_behind)
{
    lay_world world = { 0 };
    fx_box(&world.solids, -3, -1, -3, 3, 0, 3);            // floor
    fx_box(&world.solids, -3, 0, -1, 3, 3.5f, 0);          // wall
    fx_box(&world.solids, -2, 1.0f, 1.3f, 2, 1.12f, 1.4f); // handrail
    fx_box(&world.solids, -2, 2.0f, 0, 2, 2.1f, 1.5f);     // two slabs above
    fx_box(&world.solids, -2, 3.0f, 0, 2, 3.1f, 1.5f);
    wx_camera cams[2] = { fx_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 6.4f, 128), top_camera(6.4f, 128) };
    wx_maps maps[2];
    wx_collider col;
    ENSURE(build_layers(&col, cams, maps, 2, &world, 4));
    int stopped = 0, landed = 0;
    drop_onto_the_floor(&col, 1.6f, 0.2f, 0.023f, &landed, &stopped);
    release(&col, maps, 2);
    ENSURE(stopped == 0);
    ENSURE(landed == 40);
}

// A one-sided sign in the plane z = 0, seen head-on by a front and a back camera
// and edge-on by a top and a side camera, whose texel centres miss its plane: their
// maps hold nothing there, and their "not behind" let every drop through it (an
// open pipe along a side camera's axis lost 97% of the rain so). The fills
// (docs/physics.md, "Surfaces a camera sees edge-on") make them abstain where the
// front camera sees the sign: drops through it hit the sign, given by the front or
// back camera, never by a fill; beside it, past its end and over it they fly on.
TEST(edge_on_sign_stops_the_drops_through_it)
{
    for (int layers = 2; layers <= 4; layers += 2) {
        lay_world world = { 0 };
        sheet(&world, -1, 0, 0, 1, 2, 0, 0.0f, 0.0f, 1.0f);
        wx_camera cams[4] = { fx_camera(0, 1, 10, 0, 1, 0, 0, 1, 0, 6.4f, 64),
                              fx_camera(0, 1, -10, 0, 1, 0, 0, 1, 0, 6.4f, 64),
                              top_camera(6.4f, 64),
                              fx_camera(10, 1, 0, 0, 1, 0, 0, 1, 0, 6.4f, 64) };
        wx_maps maps[4];
        wx_collider col;
        ENSURE(build_layers(&col, cams, maps, 4, &world, layers));
        ENSURE(col.cameras[2].fill_texels > 0 && col.cameras[3].fill_texels > 0);
        ENSURE(col.cameras[0].fill_texels == 0 && col.cameras[1].fill_texels == 0);
        double t = 0.25 * col.cameras[0].texel_ws; // the sheet's slab
        uint64_t state = 7;
        int hits = 0, off = 0, filled = 0, free_hits = 0;
        for (int q = 0; q < 200; ++q) {
            float r[2];
            uniforms(&state, r, 2);
            float x = -0.9f + 1.8f * r[0], y = 0.1f + 1.8f * r[1];
            float dir = q % 2 ? 1.0f : -1.0f;
            float p0[3] = { x, y, 0.4f * dir }, p1[3] = { x, y, -0.4f * dir };
            wx_hit hit;
            if (wx_collider_sweep(&col, p0, p1, &hit)) {
                hits++;
                off += !(hit.point[2] <= 1e-5 && hit.point[2] >= -t - 1e-5);
                filled += hit.camera > 1 || fabsf(hit.normal[2]) < 0.999f;
            }
            // Beside it (in the fills' band), past its end, over it: free.
            float b0[3] = { x, 2.5f, 0.04f * dir }, b1[3] = { x, -0.5f, 0.04f * dir };
            float e0[3] = { 1.2f, y, 0.4f }, e1[3] = { 1.2f, y, -0.4f };
            float o0[3] = { x, 2.15f, 0.4f }, o1[3] = { x, 2.15f, -0.4f };
            free_hits += wx_collider_sweep(&col, b0, b1, &hit) +
                         wx_collider_sweep(&col, e0, e1, &hit) +
                         wx_collider_sweep(&col, o0, o1, &hit);
        }
        release(&col, maps, 4);
        ENSURE(hits == 200);
        ENSURE(off == 0);
        ENSURE(filled == 0);
        ENSURE(free_hits == 0);
    }
}

// A box whose front face (z = 0.03) lies between two texel centres of the top
// camera, which sees it edge-on: the top camera's texel outside holds nothing,
// so it said "free" in the last 0.03 of the box, and drops flying at the face
// went 0.03 into it, to the top camera's next texel (a staircase along its
// grid wherever a surface lies on its silhouette: a cylinder lined up with the
// side cameras weathered 11% differently from one turned 30 degrees). Its fill
// (docs/physics.md, "Surfaces a camera sees edge-on") leaves the face to the
// front camera: every drop hits it at z = 0.03, with one layer and with four.
// (Within two texels of the box's top, and with layers of its bottom, the top
// camera records a surface, so it is trusted there and those 0.2 of the face
// stay cut: the drops fly between.)
TEST(a_face_on_a_silhouette_is_hit_where_it_is)
{
    for (int layers = 1; layers <= 4; layers += 3) {
        lay_world world = { 0 };
        fx_box(&world.solids, -1, 0, -1, 1, 1, 0.03f);
        wx_camera cams[2] = { fx_camera(0, 0.5f, 10, 0, 0.5f, 0, 0, 1, 0, 6.4f, 64),
                              top_camera(6.4f, 64) };
        wx_maps maps[2];
        wx_collider col;
        ENSURE(build_layers(&col, cams, maps, 2, &world, layers));
        uint64_t state = 11;
        int hits = 0, off = 0, front = 0;
        for (int q = 0; q < 200; ++q) {
            float r[2];
            uniforms(&state, r, 2);
            float x = -0.9f + 1.8f * r[0], y = 0.25f + 0.5f * r[1];
            float p0[3] = { x, y, 0.5f }, p1[3] = { x, y, -0.5f };
            wx_hit hit;
            if (wx_collider_sweep(&col, p0, p1, &hit)) {
                hits++;
                off += fabsf(hit.point[2] - 0.03f) > 1e-4f;
                front += hit.camera == 0 && hit.normal[2] > 0.999f;
            }
        }
        release(&col, maps, 2);
        ENSURE(hits == 200);
        ENSURE(off == 0);
        ENSURE(front == 200);
    }
}

// A slope of 60 degrees across a side camera's view: that camera sees it
// edge-on, and its map draws the slope's edge as a staircase of texels, each
// holding the solid when its centre lies inside. Where a texel's centre lies
// outside but the slope clips it, that camera said "free" in a sliver of the
// solid, and a drop falling there went up to half a texel deeper into the
// slope than where it lies, at the same place along the whole length the
// camera looks along (a tube lined up with the side cameras took twice its
// share of hits on one row of the front camera in four, and weathered 5% more
// on its flanks than turned 30 degrees). The fills (docs/physics.md,
// "Surfaces a camera sees edge-on") take every texel the slope clips: every
// drop hits the slope within a twentieth of a texel, with one layer and four.
// (Within two texels of the wedge's ends the side camera records a surface,
// the end's, so it is trusted there: physics.md's limit, as under a box's top.)
TEST(a_slope_seen_edge_on_is_hit_on_it_everywhere)
{
    for (int layers = 1; layers <= 4; layers += 3) {
        lay_world world = { 0 };
        fx_solid *wedge = fx_box(&world.solids, -1, 0, -1, 1, 2, 1);
        fx_plane(wedge, 0, 0.5f, 0.8660254f, 0.5f); // y = 1 - sqrt(3) z
        wx_camera cams[3] = { fx_camera(0, 1, 10, 0, 1, 0, 0, 1, 0, 6.4f, 64), top_camera(6.4f, 64),
                              fx_camera(-10, 1, 0, 0, 1, 0, 0, 1, 0, 6.4f, 64) };
        wx_maps maps[3];
        wx_collider col;
        ENSURE(build_layers(&col, cams, maps, 3, &world, layers));
        double texel = col.cameras[0].texel_ws, worst = 0.0;
        int hits = 0;
        for (int q = 0; q < 2000; ++q) {
            float x = -0.7f + 1.4f * (float)((q * 37) % 2000) / 2000.0f;
            float z = -0.4f + 0.8f * (float)q / 2000.0f;
            float p0[3] = { x, 2.5f, z }, p1[3] = { x, -0.5f, z };
            wx_hit hit;
            if (wx_collider_sweep(&col, p0, p1, &hit)) {
                hits++;
                worst = fmax(worst, fabs(hit.point[1] - (1.0 - 1.7320508 * z)) / texel);
            }
        }
        release(&col, maps, 3);
        printf("        %d layer(s): %d hits, worst %.3f texel off the slope\n", layers, hits,
               worst);
        ENSURE(hits == 2000);
        ENSURE(worst < 0.05);
    }
}

// A deep handrail block in front of a wall with a block behind it, its top
// (y = 1.02) just above a row boundary of the front camera (y = 1.0), which
// sees it edge-on, and two slabs over the gap between handrail and wall,
// under which the top camera's four layers are full (solid from the lower
// slab's underside on). The handrail's top clips the front camera's row
// above by 0.2 texel, a texel whose centre lies outside: its fill
// (docs/physics.md, "Surfaces a camera sees edge-on") is a thin slab where
// the texel has room for one, and nothing where its layers are full (the
// wall's and the block's four faces here). It was instead made solid from
// the handrail to the end of the texel's ray, the wall's crossings dropped:
// as the top camera says "solid" under the slabs, that row stopped every
// drop falling in the gap (the default house with four layers: rain held in
// the air at the handrail's height over the sills, whose tops took 181 drops
// of Embree's 221). Every drop lands on the floor.
TEST(a_clipped_texel_without_room_is_not_made_solid)
{
    lay_world world = { 0 };
    fx_box(&world.solids, -3, -1, -3, 3, 0, 3);        // floor
    fx_box(&world.solids, -3, 0, -1, 3, 3.5f, 0);      // wall
    fx_box(&world.solids, -3, 0, -3, 3, 3.5f, -2);     // a block behind it
    fx_box(&world.solids, -3, 2.0f, 0, 3, 2.1f, 1.0f); // two slabs over the gap
    fx_box(&world.solids, -3, 2.5f, 0, 3, 2.6f, 1.0f);
    fx_box(&world.solids, -2, 0, 1.3f, 2, 1.02f, 1.9f); // handrail block
    wx_camera cams[2] = { fx_camera(0, 1, 10, 0, 1, 0, 0, 1, 0, 6.4f, 64), top_camera(6.4f, 64) };
    wx_maps maps[2];
    wx_collider col;
    ENSURE(build_layers(&col, cams, maps, 2, &world, 4));
    int landed = 0, stopped = 0;
    drop_onto_the_floor(&col, 1.9f, 0.1f, 0.02f, &landed, &stopped);
    printf("        front camera fills %lld texels; %d drops landed, %d stopped above the floor\n",
           (long long)col.cameras[0].fill_texels, landed, stopped);
    release(&col, maps, 2);
    ENSURE(stopped == 0);
    ENSURE(landed == 40);
}

// --- curved surfaces (docs/physics.md, "Depth between texels") --------------------

// A sphere of radius R about c seen by `cam`: each texel's ray's crossings
// (entering, then leaving) with their outward normals, `layers` of them.
static void render_sphere(const wx_camera *cam, const double c[3], double R, int layers,
                          wx_maps *maps)
{
    int W = cam->width, H = cam->height;
    size_t n = (size_t)W * (size_t)H;
    layered_maps(cam, layers, maps);
    float dir[3];
    wx_camera_view_dir(cam, dir);
    for (int j = 0; j < H; ++j) {
        for (int i = 0; i < W; ++i) {
            size_t t = (size_t)j * (size_t)W + (size_t)i;
            float eye[3];
            texel_origin(cam, i, j, eye);
            double o[3] = { eye[0] - c[0], eye[1] - c[1], eye[2] - c[2] };
            double b = o[0] * dir[0] + o[1] * dir[1] + o[2] * dir[2];
            double disc = b * b - (o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - R * R);
            for (int k = 0; k < layers; ++k) {
                size_t at = (size_t)k * n + t;
                maps->depth[at] = INFINITY;
                if (k > 1 || !(disc > 0.0)) {
                    continue;
                }
                double s = -b + (k == 0 ? -1.0 : 1.0) * sqrt(disc);
                maps->depth[at] = (float)s;
                for (int e = 0; e < 3; ++e) {
                    maps->normal[3 * at + e] = (float)((o[e] + s * dir[e]) / R);
                }
            }
        }
    }
}

static bool build_sphere(wx_collider *col, const wx_camera *cams, wx_maps *maps, int count,
                         int layers)
{
    const double c[3] = { 0.0, 0.0, 0.0 };
    for (int k = 0; k < count; ++k) {
        render_sphere(&cams[k], c, 1.0, layers, &maps[k]);
    }
    wx_error err;
    return wx_collider_init(col, cams, maps, count, false, &err) == WX_OK;
}

// Between texel centres a bilinear cell is the chord of a curved surface,
// and its slope breaks at every row and column of centres: on a unit sphere
// under a camera of 2 cm texels, out to 58 degrees from the pole, vertical
// drops landed 146 um RMS and up to 425 um below the sphere. The cells'
// second-order terms, from the change of the normals' slopes across each
// cell, put the collision surface on the sphere to a few micrometres, with
// one layer and with four.
TEST(a_sphere_is_hit_on_its_surface_to_second_order)
{
    wx_camera cam = fx_camera(0, 10, 0, 0, 0, 0, 0, 0, -1, 2.56f, 128);
    for (int layers = 1; layers <= 4; layers += 3) {
        wx_maps maps;
        wx_collider col;
        ENSURE(build_sphere(&col, &cam, &maps, 1, layers));
        uint64_t state = 3;
        double worst = 0.0, sum = 0.0;
        int hits = 0;
        for (int i = 0; i < 4000; ++i) {
            float r[2];
            uniforms(&state, r, 2);
            double rho = 0.85 * sqrt(r[0]), phi = 6.283185307 * r[1];
            float x = (float)(rho * cos(phi)), z = (float)(rho * sin(phi));
            float p0[3] = { x, 1.5f, z }, p1[3] = { x, -0.5f, z };
            wx_hit hit;
            ENSURE(wx_collider_sweep(&col, p0, p1, &hit));
            double exact = sqrt(1.0 - (double)x * x - (double)z * z);
            double off = fabs(hit.point[1] - exact);
            worst = fmax(worst, off);
            sum += off * off;
            hits++;
        }
        printf("        %d layer%s: %d drops, %.2f um RMS and %.2f um at most off the sphere\n",
               layers, layers > 1 ? "s" : "", hits, 1e6 * sqrt(sum / hits), 1e6 * worst);
        release(&col, &maps, 1);
        ENSURE(worst < 3e-5); // the chords alone: 4.3e-4
    }
}

// The quick tests bound a cell by its corners' depths; a second-order cell
// dips in front of them, by a/8 + b/8 at most, and the bounds are lowered by
// each texel's largest dip (collider_build.c, build_coarse). Segments near a
// sphere under cameras along the axes and oblique ones, with one layer and
// four: neither the coarse test nor the fine test clears a segment the swept
// test stops, and from the put-back point of a hit most free segments are
// still cleared.
TEST(curved_cells_keep_the_quick_tests_conservative)
{
    wx_camera cams[3] = { fx_camera(0, 10, 0, 0, 0, 0, 0, 0, -1, 2.56f, 128),
                          fx_camera(10, 0, 0, 0, 0, 0, 0, 1, 0, 2.56f, 128),
                          fx_camera(6, 5, 7, 0, 0, 0, 0, 1, 0, 2.56f, 128) };
    for (int layers = 1; layers <= 4; layers += 3) {
        wx_maps maps[3];
        wx_collider col;
        ENSURE(build_sphere(&col, cams, maps, 3, layers));
        ENSURE(col.cameras[0].curve != NULL && col.cameras[2].bulge_most > 0.0);
        uint64_t state = 17;
        int contradictions = 0, hits = 0, near_free = 0, near_cleared = 0;
        for (int b = 0; b < 1500; ++b) {
            float x0[WX_PARTICLE_BLOCK], y0[WX_PARTICLE_BLOCK], z0[WX_PARTICLE_BLOCK];
            float x1[WX_PARTICLE_BLOCK], y1[WX_PARTICLE_BLOCK], z1[WX_PARTICLE_BLOCK];
            for (int k = 0; k < WX_PARTICLE_BLOCK; ++k) {
                float r[6];
                uniforms(&state, r, 6);
                // On a shell 0 to 3 texels outside the sphere, towards it or along it.
                double u = 2.0 * r[0] - 1.0, phi = 6.283185307 * r[1];
                double w = sqrt(1.0 - u * u), R = 1.0 + 0.06 * r[2];
                x0[k] = (float)(R * w * cos(phi));
                y0[k] = (float)(R * u);
                z0[k] = (float)(R * w * sin(phi));
                float len = k % 4 == 0 ? 0.5f : 0.06f;
                x1[k] = x0[k] + len * (r[3] - 0.5f);
                y1[k] = y0[k] + len * (r[4] - 0.5f);
                z1[k] = z0[k] + len * (r[5] - 0.5f);
            }
            int order[3] = { 0, 1, 2 };
            uint32_t out;
            uint32_t mask =
                wx_collider_coarse_block(&col, order, 3, NULL, x0, y0, z0, x1, y1, z1, &out);
            if (mask != 0xffffu) {
                mask |= out;
            }
            for (int k = 0; k < WX_PARTICLE_BLOCK; ++k) {
                float p0[3] = { x0[k], y0[k], z0[k] }, p1[3] = { x1[k], y1[k], z1[k] };
                if (wx_collider_point_collides(&col, p0)) {
                    continue;
                }
                wx_hit hit, again;
                bool h = wx_collider_sweep(&col, p0, p1, &hit);
                contradictions += h && (((mask >> k) & 1u) || wx_collider_fine_clear(&col, p0, p1));
                if (!h) {
                    continue;
                }
                hits++;
                float q1[3] = { hit.front[0] + 0.3f * (x1[k] - x0[k]),
                                hit.front[1] + 0.3f * fabsf(y1[k] - y0[k]),
                                hit.front[2] + 0.3f * (z1[k] - z0[k]) };
                bool stops = wx_collider_sweep(&col, hit.front, q1, &again);
                bool clears = wx_collider_fine_clear(&col, hit.front, q1);
                near_free += !stops;
                near_cleared += clears;
                contradictions += clears && stops;
            }
        }
        printf("        %d layer%s: %d hits; from their put-back points %d free, %d cleared\n",
               layers, layers > 1 ? "s" : "", hits, near_free, near_cleared);
        release(&col, maps, 3);
        ENSURE(contradictions == 0);
        ENSURE(hits > 2000);
        // Under the top camera alone, level segments around the pole between
        // the sphere and its chords (at most a/8 = 50 um below its top): the
        // sphere stops them where the corners' depths alone would clear them.
        ENSURE(build_sphere(&col, cams, maps, 1, layers));
        int stopped = 0;
        contradictions = 0;
        for (int i = 0; i < 2000; ++i) {
            float r[3];
            uniforms(&state, r, 3);
            float x = 0.06f * (r[0] - 0.5f), z = 0.06f * (r[1] - 0.5f);
            float y = 1.0f - 5e-5f * r[2];
            float p0[3] = { x - 0.03f, y, z }, p1[3] = { x + 0.03f, y, z };
            if (wx_collider_point_collides(&col, p0)) {
                continue;
            }
            wx_hit hit;
            bool h = wx_collider_sweep(&col, p0, p1, &hit);
            stopped += h;
            contradictions += h && wx_collider_fine_clear(&col, p0, p1);
        }
        printf(
            "        the top camera, %d layer%s: %d of 2000 level segments by the pole stopped\n",
            layers, layers > 1 ? "s" : "", stopped);
        release(&col, maps, 1);
        ENSURE(contradictions == 0);
        ENSURE(stopped > 200);
    }
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
    RUN(a_tile_keeps_its_whole_cameras_framing);
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
    RUN(railing_layers_let_a_drop_fall_behind_the_bars);
    RUN(overhang_layers_free_under_the_roof_and_hit_its_underside);
    RUN(tilted_underside_hit_is_exact);
    RUN(pane_is_a_thin_sheet_hit_from_either_side);
    RUN(layered_sweep_agrees_with_the_point_rule);
    RUN(fine_test_never_clears_what_the_sweep_stops);
    RUN(one_layer_is_todays_collider);
    RUN(facing_cameras_tie_to_the_one_outside_the_surface);
    RUN(a_drop_by_an_edge_is_recorded_on_the_face_it_lands_on);
    RUN(ownership_ties_go_to_the_view_outside_the_surface);
    RUN(a_grazing_silhouette_owns_nothing_another_view_sees_head_on);
    RUN(a_hit_on_a_curve_lands_where_its_camera_owns_the_surface);
    RUN(a_wall_below_an_eave_is_not_owned_by_the_roof_above_it);
    RUN(layer_ramp_does_not_jump_from_a_handrail_to_the_wall_behind);
    RUN(edge_on_sign_stops_the_drops_through_it);
    RUN(a_face_on_a_silhouette_is_hit_where_it_is);
    RUN(a_slope_seen_edge_on_is_hit_on_it_everywhere);
    RUN(a_clipped_texel_without_room_is_not_made_solid);
    RUN(a_sphere_is_hit_on_its_surface_to_second_order);
    RUN(curved_cells_keep_the_quick_tests_conservative);
    return ensure_summary();
}
