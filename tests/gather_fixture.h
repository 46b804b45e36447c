// gather_fixture.h: scenes of flat quads for the gather tests (test_gather.c,
// test_adaptive.c, test_gather_phase.c), rendered into a camera's maps by a tiny
// orthographic ray caster: exact depth, normal and dirt at every texel centre,
// so that expected values can be worked out by hand.
#ifndef WX_GATHER_FIXTURE_H
#define WX_GATHER_FIXTURE_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gather/gather.h"
#include "gather/target.h"
#include "model/camera.h"
#include "model/maps.h"

#define PI 3.14159265358979323846

// ---------------------------------------------------------------------------
// Test scenes: quads c + s*a + t*b (|s|, |t| <= 1, a and b orthogonal) with an
// outward unit normal n.

typedef struct quad {
    double c[3], a[3], b[3], n[3];
} quad;

static inline double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// Maps of one camera, owned by the test.
typedef struct test_maps {
    wx_camera cam;
    int w, h;
    float *depth, *normal, *dirt;
} test_maps;

static inline void maps_free(test_maps *m)
{
    free(m->depth);
    free(m->normal);
    free(m->dirt);
    memset(m, 0, sizeof *m);
}

static inline wx_camera make_camera(float ex, float ey, float ez, float tx, float ty, float tz,
                                    float ux, float uy, float uz, float w_ws, float h_ws, int w_px,
                                    int h_px)
{
    wx_view view = { .eye = { ex, ey, ez },
                     .target = { tx, ty, tz },
                     .up = { ux, uy, uz },
                     .width_ws = w_ws,
                     .height_ws = h_ws,
                     .width_px = w_px,
                     .height_px = h_px };
    wx_camera cam;
    memset(&cam, 0, sizeof cam);
    if (wx_camera_from_view(&view, &cam, NULL) != WX_OK) {
        abort();
    }
    return cam;
}

// World point where texel (i, j)'s ray starts (d = 0) and the ray direction.
static inline void texel_ray(const wx_camera *cam, int i, int j, double o[3], double dir[3])
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

static inline test_maps render(wx_camera cam, const quad *quads, int count, density_fn density)
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

static inline wx_gather_view view_of(const test_maps *m)
{
    wx_gather_view v = { .camera = &m->cam,
                         .width = m->w,
                         .height = m->h,
                         .depth = m->depth,
                         .normal = m->normal,
                         .dirt = m->dirt };
    return v;
}

static inline wx_target target_of(const test_maps *m)
{
    wx_target t = { .kind = WX_TARGET_CAMERA,
                    .camera = &m->cam,
                    .width = m->w,
                    .height = m->h,
                    .depth = m->depth,
                    .normal = m->normal };
    return t;
}

static inline quad make_quad(double cx, double cy, double cz, double ax, double ay, double az,
                             double bx, double by, double bz, double nx, double ny, double nz)
{
    quad q = { { cx, cy, cz }, { ax, ay, az }, { bx, by, bz }, { nx, ny, nz } };
    return q;
}

// The front camera of several tests: eye at z = 10 looking at -z, 4 x 2 m,
// 8 x 4 texels of 0.5 x 0.5 m (area 0.25 m^2).
static inline wx_camera front_camera(void)
{
    return make_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 4, 2, 8, 4);
}

// A wall z = 0 facing +z, larger than every frame used with it.
static inline quad big_wall(void)
{
    return make_quad(0, 0, 0, 20, 0, 0, 0, 20, 0, 0, 0, 1);
}

// The gather of `inputs` into `out`'s texels with a fixed radius (NULL, with
// the error on stderr, when it fails).
static inline float *run_gather(const test_maps *out, const test_maps *inputs, int count,
                                float radius, wx_second_pass mode, wx_gather_sampling sampling,
                                int threads)
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

#endif
