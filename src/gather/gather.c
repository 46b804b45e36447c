// gather.c: the output mask (docs/design.md section 5, thesis 4.8.4.4 with its visibility
// test added and its second pass made a weighted mean).
//
// Both passes run on the thread pool (core/parallel.h), whose workers take work
// items (first pass: 64 x 64 tiles, which keep the input maps' footprint in
// cache; second pass: bands of rows) from a shared counter. Every texel is computed from the inputs alone, so
// the result does not depend on the thread count. The second pass visits a
// precomputed list of neighbour offsets, x innermost over chunks of 64 texels of
// padded planes, in a loop the compiler vectorises. docs/mask.md has the details.
#include "gather/gather.h"
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/big_alloc.h"
#include "core/limits.h"
#include "gather/adaptive.h"
#include "model/ownership.h"
#include "gather/visibility.h"
#include "core/matrix.h"
#include "core/parallel.h"
#include "core/progress.h"

enum {
    TILE = 64,            // first pass: blocks of TILE x TILE output texels
    CHUNK = 64,           // second pass: texels per chunk (x innermost)
    ROWS_PER_ITEM = 2,    // second pass: rows a worker takes at a time
    MAX_OFFSETS = 100000, // second-pass neighbourhood limit (radius ~178 texels)
};

#define NORMAL_EPSILON WX_VISIBILITY_NORMAL_EPSILON
// The least share of a texel's surface its dirt is divided by (add_tap).
#define OWNED_MIN (1.0f / 16.0f)

// ---------------------------------------------------------------------------
// The mask's header matrices (core/matrix.h: row vectors, composed in double).

static void to_float16(const double m[16], float out[16])
{
    for (int k = 0; k < 16; ++k) {
        out[k] = (float)m[k];
    }
}

// worldToNDC = wtc * F with [u v d 1] * F = [u, 1 - v, d, 1].
void wx_mask_world_to_ndc(const wx_camera *camera, float m[16])
{
    double wtc[16], out[16];
    for (int k = 0; k < 16; ++k) {
        wtc[k] = camera->wtc[k];
    }
    const double f[16] = { 1, 0, 0, 0, //
                           0, -1, 0, 0, //
                           0, 0, 1, 0, //
                           0, 1, 0, 1 };
    wx_matrix_mul(wtc, f, out);
    to_float16(out, m);
}

// worldToCamera = wtc * G with [u v d 1] * G = [(u - 1/2) W, (v - 1/2) H, d, 1].
void wx_mask_world_to_camera(const wx_camera *camera, float m[16])
{
    double wtc[16], ctw[16], out[16], x[3], y[3];
    for (int k = 0; k < 16; ++k) {
        wtc[k] = camera->wtc[k];
        ctw[k] = camera->ctw[k];
    }
    wx_matrix_row3(ctw, 0, x); // world step for a step of 1 in u: the frame's width vector
    wx_matrix_row3(ctw, 1, y);
    double width = wx_length3(x), height = wx_length3(y);
    const double g[16] = { width, 0, 0, 0, //
                           0, height, 0, 0, //
                           0, 0, 1, 0, //
                           -0.5 * width, -0.5 * height, 0, 1 };
    wx_matrix_mul(wtc, g, out);
    to_float16(out, m);
}

// ---------------------------------------------------------------------------
// The job shared by the worker threads.

// An input camera prepared for the first pass.
typedef struct input_cam {
    // Output texel (i, j) at depth d lands at continuous texel coordinates
    // x = cx . (i, j, d, 1), y = cy . (...) of this camera (texel centres at
    // integers, row 0 at the top), at depth dp = cd . (...).
    double cx[4], cy[4], cd[4];
    int width, height;
    const float *depth;
    const float *normal;
    const float *dirt;
    // The adaptive pass also gathers the initial dirt (the dirt itself for a map
    // no simulation wrote) and the impacts (NULL: none).
    const float *initial;
    const float *hits;
    const float *owned;  // the share of each texel's surface this camera owns
    float ray[3];        // unit projection direction (ctw row 2)
    float tol_world;     // WX_GATHER_DEPTH_TOL_TEXELS * the texel's larger side
    float inv_head_area; // 1 / area of a texel seen head-on
} input_cam;

// A second-pass neighbour: texel (i + di, j + dj). With dd the depth difference,
// r^2 = a2 + dd * (az2 + dd * z2).
typedef struct offset {
    int di, dj;
    float a2, az2;
} offset;

typedef struct gather_job {
    int width, height;
    const float *depth;  // output depth
    const float *normal; // output normals, interleaved
    const input_cam *cams;
    int cam_count;
    bool bilinear;
    float *mask; // final values, width*height
    // Adaptive: the first pass also writes the initial dirt and the impacts per
    // unit area (unpadded, width*height).
    bool adaptive;
    float *first_initial, *first_hits;

    // First-pass values go to first[first_base + j*first_stride + i]: the mask
    // itself without a second pass, else the padded plane below.
    float *first;
    size_t first_base, first_stride;

    // Second pass: planes of stride `stride` with pad_x columns and pad_y rows of
    // margin around the map (and up to a whole CHUNK on the right), so that no
    // neighbour needs a bounds test. Margins and texels without a surface have
    // normal 0, which gives weight 0.
    bool second;
    float *pd, *pnx, *pny, *pnz; // depth and unit normal
    size_t stride, base;         // texel (i, j) at base + j*stride + i
    const offset *offsets;
    int offset_count;
    float z2, inv_radius;
    bool sum;

    int pass; // 1 or 2
    int tiles_x, tiles_y;
    int items; // work items of the current pass: tiles, then bands of rows
    wx_progress *progress;
    int64_t progress_base;
} gather_job;

// Unit normal of a texel, or false when it has none.
static bool unit_normal(const float *n, float out[3])
{
    float len2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if (!(len2 > 1e-12f && len2 < INFINITY)) {
        return false;
    }
    float inv = 1.0f / sqrtf(len2);
    out[0] = n[0] * inv;
    out[1] = n[1] * inv;
    out[2] = n[2] * inv;
    return true;
}

static float clean_dirt(float dirt)
{
    return dirt > 0.0f && dirt < INFINITY ? dirt : 0.0f; // negative or NaN counts as 0
}

// The sums of the taps of every camera: the weights of the taps that see the
// point (all) and of the share of them their cameras own (own), and the
// weighted dirt, initial dirt and impacts per unit area (the last two for the
// adaptive pass only).
typedef struct tap_sums {
    float all, own, dirt, initial, hits;
} tap_sums;

// One texel of an input camera: when it sees the surface point (at depth dp in
// this camera, unit normal n), adds w = weight * agreement to all, w times the
// share of the texel its camera owns to own, and w times the texel's values
// per unit area to the sums. Every deposit lies in the map of the camera that
// owns its point, so a texel's values per unit of the area it owns are the
// densities; divided by `own`, the taps of all cameras give one estimate, and
// a border between two cameras' parts leaves no seam (model/ownership.h).
static inline void add_tap(const input_cam *c, size_t t, float weight, float dp, const float n[3],
                           bool adaptive, tap_sums *s)
{
    float cos_view = 0.0f;
    float agree = wx_visible_agreement(c->depth[t], &c->normal[3 * t], c->ray, c->tol_world,
                                       WX_GATHER_TOL_MIN_COS, dp, n, &cos_view);
    if (agree == 0.0f) {
        return;
    }
    float w = weight * agree;
    // Dirt per unit of owned area: the texel covers head_area / |N.view| of
    // surface, of which it owns the share f. A share under OWNED_MIN (less
    // than one of the 16 points a border texel is cut into) counts as
    // OWNED_MIN, so that a few deposits the collider gave a texel the rule
    // barely gives it cannot make a spike.
    float f = c->owned[t];
    float cos_area = cos_view > WX_GATHER_AREA_MIN_COS ? cos_view : WX_GATHER_AREA_MIN_COS;
    float per_area = w * cos_area * c->inv_head_area * (f < OWNED_MIN ? f / OWNED_MIN : 1.0f);
    s->dirt += per_area * clean_dirt(c->dirt[t]);
    if (adaptive) {
        s->initial += per_area * clean_dirt(c->initial[t]);
        s->hits += c->hits != NULL ? per_area * clean_dirt(c->hits[t]) : 0.0f;
    }
    s->all += w;
    s->own += w * f;
}

// Whether texel t of camera c weighs in: it holds something to gather, or its
// camera owns part of it (a texel that holds 0 there counts as 0).
static inline bool holds_something(const input_cam *c, size_t t, bool adaptive)
{
    return c->owned[t] > 0.0f || c->dirt[t] > 0.0f ||
           (adaptive && c->hits != NULL && c->hits[t] > 0.0f);
}

// The four texels around continuous texel coordinates (x, y), each tested.
static void sample_bilinear(const input_cam *c, double x, double y, float dp, const float n[3],
                            bool adaptive, tap_sums *s)
{
    const int width = c->width, height = c->height;
    // x + 1 > 0, so truncation is floor.
    const int i0 = (int)(x + 1.0) - 1, j0 = (int)(y + 1.0) - 1;
    const float fx = (float)(x - i0), fy = (float)(y - j0);
    const float w00 = (1.0f - fx) * (1.0f - fy), w10 = fx * (1.0f - fy);
    const float w01 = (1.0f - fx) * fy, w11 = fx * fy;
    if (i0 >= 0 && j0 >= 0 && i0 + 1 < width && j0 + 1 < height) {
        const size_t t = (size_t)j0 * (size_t)width + (size_t)i0;
        // Nothing in any of them: nothing whatever the visibility.
        if (!(holds_something(c, t, adaptive) | holds_something(c, t + 1, adaptive) |
              holds_something(c, t + (size_t)width, adaptive) |
              holds_something(c, t + (size_t)width + 1, adaptive))) {
            return;
        }
        add_tap(c, t, w00, dp, n, adaptive, s);
        add_tap(c, t + 1, w10, dp, n, adaptive, s);
        add_tap(c, t + (size_t)width, w01, dp, n, adaptive, s);
        add_tap(c, t + (size_t)width + 1, w11, dp, n, adaptive, s);
    } else {
        // At the border of the map: only the taps inside it.
        const float weights[4] = { w00, w10, w01, w11 };
        for (int k = 0; k < 4; ++k) {
            int ti = i0 + (k & 1), tj = j0 + (k >> 1);
            if (ti >= 0 && ti < width && tj >= 0 && tj < height) {
                add_tap(c, (size_t)tj * (size_t)width + (size_t)ti, weights[k], dp, n, adaptive,
                        s);
            }
        }
    }
}

// The taps of camera `c` (dirt, and for the adaptive pass the initial dirt and
// the impacts, per unit area) for the surface point seen by output texel (i, j)
// at depth d with unit normal n, added to *out; nothing when the camera does
// not see it.
static void sample_camera(const input_cam *c, double i, double j, double d, const float n[3],
                          bool bilinear, bool adaptive, tap_sums *out)
{
    double x = c->cx[0] * i + c->cx[1] * j + c->cx[2] * d + c->cx[3];
    double y = c->cy[0] * i + c->cy[1] * j + c->cy[2] * d + c->cy[3];
    // In frame (0 <= u < 1, 0 < v <= 1) in texel coordinates.
    if (!(x >= -0.5 && x < (double)c->width - 0.5 && y >= -0.5 && y < (double)c->height - 0.5)) {
        return;
    }
    const float dp = (float)(c->cd[0] * i + c->cd[1] * j + c->cd[2] * d + c->cd[3]);
    if (!bilinear) {
        // x + 0.5 >= 0: truncation is floor.
        size_t t = (size_t)(int)(y + 0.5) * (size_t)c->width + (size_t)(int)(x + 0.5);
        if (holds_something(c, t, adaptive)) {
            add_tap(c, t, 1.0f, dp, n, adaptive, out);
        }
    } else {
        sample_bilinear(c, x, y, dp, n, adaptive, out);
    }
}
// First pass over one TILE x TILE block of output texels (tiles keep the input
// maps' footprint in cache when the cameras look from different directions).
static void first_pass_tile(const gather_job *job, int tile)
{
    const int i0 = (tile % job->tiles_x) * TILE, j0 = (tile / job->tiles_x) * TILE;
    const int i1 = i0 + TILE < job->width ? i0 + TILE : job->width;
    const int j1 = j0 + TILE < job->height ? j0 + TILE : job->height;
    for (int j = j0; j < j1; ++j) {
        for (int i = i0; i < i1; ++i) {
            size_t q = (size_t)j * (size_t)job->width + (size_t)i;
            float d = job->depth[q];
            float n[3] = { 0.0f, 0.0f, 0.0f };
            tap_sums sum = { 0.0f, 0.0f, 0.0f, 0.0f, 0.0f };
            if (!wx_depth_is_empty(d) && unit_normal(&job->normal[3 * q], n)) {
                for (int k = 0; k < job->cam_count; ++k) {
                    sample_camera(&job->cams[k], i, j, d, n, job->bilinear, job->adaptive, &sum);
                }
                // Per unit of owned area; where no camera owns what it sees
                // (a point the rule gives to a camera that does not see it
                // here), per unit of area seen.
                float den = sum.own > 0.0f ? sum.own : sum.all;
                if (den > 0.0f) {
                    sum.dirt /= den;
                    sum.initial /= den;
                    sum.hits /= den;
                }
            } else {
                d = 0.0f; // no surface: normal 0 (weight 0), depth finite
                n[0] = n[1] = n[2] = 0.0f;
            }
            job->first[job->first_base + (size_t)j * job->first_stride + (size_t)i] = sum.dirt;
            if (job->adaptive) {
                job->first_initial[q] = sum.initial;
                // -1 where no camera sees the surface point: unknown, not
                // clean (adaptive.h).
                job->first_hits[q] =
                    sum.all > 0.0f || wx_depth_is_empty(job->depth[q]) ? sum.hits : -1.0f;
            }
            if (job->second) {
                size_t p = job->base + (size_t)j * job->stride + (size_t)i;
                job->pd[p] = d;
                job->pnx[p] = n[0];
                job->pny[p] = n[1];
                job->pnz[p] = n[2];
            }
        }
    }
}

// v, or 0 when c is negative (sign bit set): a select without a comparison, so
// that the loop below vectorises under the default -ftrapping-math.
static inline float keep_if_positive(float v, float c)
{
    uint32_t vb, cb;
    memcpy(&vb, &v, sizeof vb);
    memcpy(&cb, &c, sizeof cb);
    vb &= ~(uint32_t)((int32_t)cb >> 31);
    memcpy(&v, &vb, sizeof v);
    return v;
}

// Adds the weights and weighted values of one neighbour offset to a chunk of
// CHUNK texels (p: the neighbours, q: the chunk's texels). Every input is finite
// (texels without a surface have depth 0 and normal 0), so r2 is finite or +inf
// and nothing here makes a NaN.
static void accumulate(const float *restrict dp, const float *restrict nxp,
                       const float *restrict nyp, const float *restrict nzp,
                       const float *restrict fp, const float *restrict dq,
                       const float *restrict nxq, const float *restrict nyq,
                       const float *restrict nzq, float a2, float az2, float z2,
                       float inv_radius, float *restrict acc_w, float *restrict acc_f)
{
    for (int x = 0; x < CHUNK; ++x) {
        float dd = dp[x] - dq[x];
        float r2 = a2 + dd * (az2 + dd * z2);
        float r = sqrtf(keep_if_positive(r2, r2)); // rounding can make r2 a hair < 0
        float cone = 1.0f - r * inv_radius;        // <= 0 from r = radius on
        float agree = nxp[x] * nxq[x] + nyp[x] * nyq[x] + nzp[x] * nzq[x];
        float w = keep_if_positive(keep_if_positive(agree * cone, cone), agree - NORMAL_EPSILON);
        acc_w[x] += w;
        acc_f[x] += w * fp[x];
    }
}

// Second pass over one row (docs/design.md section 5; thesis 4.8.4.4 reads the cone
// filter (1 - r_pq)/r as 1 - r_pq/r). The texel itself has weight 1.
static void second_pass_row(const gather_job *job, int j)
{
    const int width = job->width;
    const size_t row = job->base + (size_t)j * job->stride;
    for (int x0 = 0; x0 < width; x0 += CHUNK) {
        const size_t q = row + (size_t)x0;
        float acc_w[CHUNK], acc_f[CHUNK];
        for (int x = 0; x < CHUNK; ++x) {
            acc_w[x] = 1.0f;
            acc_f[x] = job->first[q + (size_t)x];
        }
        for (int o = 0; o < job->offset_count; ++o) {
            const offset off = job->offsets[o];
            const size_t p = (size_t)((ptrdiff_t)q + (ptrdiff_t)off.dj * (ptrdiff_t)job->stride +
                                      off.di);
            accumulate(job->pd + p, job->pnx + p, job->pny + p, job->pnz + p, job->first + p,
                       job->pd + q, job->pnx + q, job->pny + q, job->pnz + q, off.a2, off.az2,
                       job->z2, job->inv_radius, acc_w, acc_f);
        }
        const int x1 = x0 + CHUNK < width ? x0 + CHUNK : width;
        for (int x = x0; x < x1; ++x) {
            size_t t = (size_t)j * (size_t)width + (size_t)x;
            float value;
            if (wx_depth_is_empty(job->depth[t])) {
                value = 0.0f;
            } else if (job->sum) {
                value = acc_f[x - x0];
            } else {
                value = acc_f[x - x0] / acc_w[x - x0];
            }
            job->mask[t] = value;
        }
    }
}

static void do_item(const gather_job *job, int item)
{
    if (job->pass == 1) {
        first_pass_tile(job, item);
        return;
    }
    const int j0 = item * ROWS_PER_ITEM;
    const int j1 = j0 + ROWS_PER_ITEM < job->height ? j0 + ROWS_PER_ITEM : job->height;
    for (int j = j0; j < j1; ++j) {
        second_pass_row(job, j);
    }
}

// Items [begin, end) of the current pass; the calling thread (worker 0) also
// draws the progress bar.
static void do_items(int64_t begin, int64_t end, int worker, void *context)
{
    const gather_job *job = context;
    for (int64_t item = begin; item < end; ++item) {
        do_item(job, (int)item);
        if (worker == 0 && job->progress != NULL) {
            wx_progress_update(job->progress, job->progress_base + item + 1);
        }
    }
}

// Runs one pass on the pool: every item is computed from the inputs alone, so
// the result does not depend on which thread takes it.
static void run_pass(gather_job *job, int pass, int items, wx_pool *pool)
{
    job->pass = pass;
    job->items = items;
    wx_pool_for(pool, items, 1, do_items, job);
}

// ---------------------------------------------------------------------------
// Setup.

wx_gather_def wx_default_gather_def(void)
{
    wx_gather_def def;
    memset(&def, 0, sizeof def);
    def.second_pass = WX_SECOND_PASS_MEAN;
    def.sampling = WX_GATHER_BILINEAR;
    def.threads = 1;
    def.quiet = true;
    return def;
}

wx_gather_view wx_gather_view_from_maps(const wx_camera *camera, const wx_maps *maps)
{
    wx_gather_view view = { .camera = camera,
                            .width = maps->width,
                            .height = maps->height,
                            .depth = maps->depth,
                            .normal = maps->normal,
                            .dirt = maps->dirt,
                            .initial = maps->initial_dirt,
                            .hits = maps->hits,
                            .owned = maps->owned,
                            .outward = maps->outward,
                            .crossing_depth = maps->crossing_depth,
                            .crossing_normal = maps->crossing_normal,
                            .crossing_layers = maps->crossing_layers,
                            .crossing_layer = maps->crossing_layer };
    return view;
}

static wx_result check_view(const wx_gather_view *view, bool needs_dirt, const char *what,
                            int index, wx_error *err);

static wx_result check_target(const wx_target *target, wx_error *err)
{
    if (target->kind != WX_TARGET_CAMERA) {
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "gather: unknown target kind %d",
                       (int)target->kind);
    }
    wx_gather_view view = { .camera = target->camera, .width = target->width,
                            .height = target->height, .depth = target->depth,
                            .normal = target->normal };
    return check_view(&view, false, "output camera", 0, err);
}

static wx_result check_view(const wx_gather_view *view, bool needs_dirt, const char *what,
                            int index, wx_error *err)
{
    if (view->camera == NULL || view->depth == NULL || view->normal == NULL ||
        (needs_dirt && view->dirt == NULL)) {
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "gather: %s %d lacks its camera or a map", what,
                            index);
    }
    if (view->width < 1 || view->height < 1 || view->width > WX_MAP_MAX_SIDE ||
        view->height > WX_MAP_MAX_SIDE) {
        return wx_fail(err, WX_CAUSE_MAP_SIZE, "gather: %s %d has a bad map size %d x %d", what,
                            index, view->width, view->height);
    }
    if ((view->camera->width != 0 && view->camera->width != view->width) ||
        (view->camera->height != 0 && view->camera->height != view->height)) {
        return wx_fail(err, WX_CAUSE_MAP_SIZE,
                       "gather: %s %d: maps are %d x %d but the camera is %d x %d", what, index,
                       view->width, view->height, view->camera->width, view->camera->height);
    }
    return WX_OK;
}

// Matrices of an output texel (i, j, d) to input camera texel coordinates.
static wx_result prepare_input(const wx_target *out, const double out_ctw[16],
                               const wx_gather_view *in, int index, input_cam *cam, wx_error *err)
{
    double wtc[16], ctw[16];
    if (!wx_matrix_to_affine(in->camera->wtc, wtc) || !wx_matrix_to_affine(in->camera->ctw, ctw)) {
        return wx_fail(err, WX_CAUSE_BAD_CAMERA,
                       "gather: input camera %d is not orthographic (its matrices must "
                       "have the last column 0 0 0 1)",
                       index);
    }
    const double wo = out->width, ho = out->height;
    // [i j d 1] -> [u v d 1] of the output map: u = (i + 1/2)/W, v = 1 - (j + 1/2)/H.
    const double pre[16] = { 1.0 / wo, 0, 0, 0, //
                             0, -1.0 / ho, 0, 0, //
                             0, 0, 1, 0, //
                             0.5 / wo, 1.0 - 0.5 / ho, 0, 1 };
    double a[16];
    wx_matrix_mul(pre, out_ctw, a);
    wx_gather_view_rows(in, wtc, a, cam->cx, cam->cy, cam->cd);
    cam->width = in->width;
    cam->height = in->height;
    cam->depth = in->depth;
    cam->normal = in->normal;
    cam->dirt = in->dirt;
    // A map no simulation wrote is exact: its dirt counts as initial, unsmoothed.
    bool simulated = in->initial != NULL && in->hits != NULL;
    cam->initial = simulated ? in->initial : in->dirt;
    cam->hits = simulated ? in->hits : NULL;
    cam->owned = in->owned;

    double head_area = 0.0;
    if (!wx_gather_view_frame(in, cam->ray, &cam->tol_world, &head_area)) {
        return wx_fail(err, WX_CAUSE_BAD_CAMERA, "gather: input camera %d has a degenerate frame",
                            index);
    }
    cam->inv_head_area = (float)(1.0 / head_area);
    return WX_OK;
}

void wx_gather_view_rows(const wx_gather_view *view, const double wtc[16], const double from[16],
                         double cx[4], double cy[4], double cd[4])
{
    const double wi = view->width, hi = view->height;
    // [u v d 1] -> [x y d 1] of the input map: x = u W - 1/2, y = (1 - v) H - 1/2.
    const double post[16] = { wi, 0, 0, 0, //
                              0, -hi, 0, 0, //
                              0, 0, 1, 0, //
                              -0.5, hi - 0.5, 0, 1 };
    double b[16], full[16];
    if (from != NULL) {
        wx_matrix_mul(from, wtc, b);
    } else {
        memcpy(b, wtc, sizeof b);
    }
    wx_matrix_mul(b, post, full);
    for (int r = 0; r < 4; ++r) {
        cx[r] = full[r * 4 + 0];
        cy[r] = full[r * 4 + 1];
        cd[r] = full[r * 4 + 2];
    }
}

bool wx_gather_view_frame(const wx_gather_view *view, float ray_out[3], float *tol_world,
                          double *head_area_out)
{
    double ctw[16];
    if (!wx_matrix_to_affine(view->camera->ctw, ctw)) {
        return false;
    }
    const double wi = view->width, hi = view->height;
    double ex[3], ey[3], ray[3], cross[3];
    wx_matrix_row3(ctw, 0, ex);
    wx_matrix_row3(ctw, 1, ey);
    wx_matrix_row3(ctw, 2, ray);
    for (int k = 0; k < 3; ++k) {
        ex[k] /= wi;
        ey[k] /= hi;
    }
    double ray_len = wx_length3(ray);
    cross[0] = ex[1] * ey[2] - ex[2] * ey[1];
    cross[1] = ex[2] * ey[0] - ex[0] * ey[2];
    cross[2] = ex[0] * ey[1] - ex[1] * ey[0];
    double head_area = ray_len > 0.0 ? fabs(wx_dot3(cross, ray)) / ray_len : 0.0;
    if (!(head_area > 0.0) || !isfinite(head_area)) {
        return false;
    }
    for (int k = 0; k < 3; ++k) {
        ray_out[k] = (float)(ray[k] / ray_len);
    }
    *tol_world = (float)(WX_GATHER_DEPTH_TOL_TEXELS * fmax(wx_length3(ex), wx_length3(ey)));
    *head_area_out = head_area;
    return true;
}

// The second-pass neighbourhood of the output camera: every texel offset whose
// world distance can be below the radius for some depth difference.
static wx_result radius_too_large(float radius, wx_error *err)
{
    return wx_fail(err, WX_CAUSE_BAD_VALUE,
                   "the second-pass radius %g covers more than %d output texels around each "
                   "texel; use a smaller radius",
                   (double)radius, MAX_OFFSETS);
}

static wx_result build_offsets(const wx_target *out, const double ctw[16], float radius,
                               offset **out_offsets, int *out_count, float *out_z2,
                               wx_error *err)
{
    double ex[3], ey[3], z[3];
    wx_matrix_row3(ctw, 0, ex);
    wx_matrix_row3(ctw, 1, ey);
    wx_matrix_row3(ctw, 2, z);
    for (int k = 0; k < 3; ++k) {
        ex[k] /= out->width;
        ey[k] /= -out->height; // j grows downwards, v upwards
    }
    double z2 = wx_dot3(z, z);
    // Components of the texel steps perpendicular to the viewing ray: a depth
    // difference moves the point along z only.
    double exz = wx_dot3(ex, z) / z2, eyz = wx_dot3(ey, z) / z2;
    double px[3], py[3];
    for (int k = 0; k < 3; ++k) {
        px[k] = ex[k] - exz * z[k];
        py[k] = ey[k] - eyz * z[k];
    }
    double gxx = wx_dot3(px, px), gxy = wx_dot3(px, py), gyy = wx_dot3(py, py);
    double det = gxx * gyy - gxy * gxy;
    if (!(z2 > 0.0) || !(det > 0.0) || !isfinite(det)) {
        return wx_fail(err, WX_CAUSE_BAD_CAMERA,
                       "gather: the output camera has a degenerate frame");
    }
    double r2 = (double)radius * (double)radius;
    // Extent of the ellipse q(di, dj) < r^2 along each axis.
    double span_i = ceil((double)radius * sqrt(gyy / det));
    double span_j = ceil((double)radius * sqrt(gxx / det));
    if (!((2.0 * span_i + 1.0) * (2.0 * span_j + 1.0) <= 4.0 * MAX_OFFSETS)) {
        return radius_too_large(radius, err);
    }
    int si = (int)span_i, sj = (int)span_j;
    size_t cap = (size_t)(2 * si + 1) * (size_t)(2 * sj + 1);
    offset *offsets = malloc(cap * sizeof *offsets);
    if (offsets == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "gather: out of memory");
    }
    int count = 0;
    for (int dj = -sj; dj <= sj; ++dj) { // rows in memory order
        for (int di = -si; di <= si; ++di) {
            if (di == 0 && dj == 0) {
                continue; // the texel itself: weight 1, added separately
            }
            double a[3], perp[3];
            for (int k = 0; k < 3; ++k) {
                a[k] = di * ex[k] + dj * ey[k];
                perp[k] = di * px[k] + dj * py[k];
            }
            if (!(wx_dot3(perp, perp) < r2)) {
                continue;
            }
            offsets[count].di = di;
            offsets[count].dj = dj;
            offsets[count].a2 = (float)wx_dot3(a, a);
            offsets[count].az2 = (float)(2.0 * wx_dot3(a, z));
            count++;
        }
    }
    if (count > MAX_OFFSETS) {
        free(offsets);
        return radius_too_large(radius, err);
    }
    *out_offsets = offsets;
    *out_count = count;
    *out_z2 = (float)z2;
    return WX_OK;
}

wx_result wx_gather_check_radius(const wx_target *target, float radius, int *texels,
                                 wx_error *err)
{
    *texels = 0;
    if (!(radius >= 0.0f) || !isfinite(radius)) {
        return wx_fail(err, WX_CAUSE_BAD_VALUE, "the second-pass radius must be >= 0");
    }
    double ctw[16];
    if (radius > 0.0f && !wx_matrix_to_affine(target->camera->ctw, ctw)) {
        return wx_fail(err, WX_CAUSE_BAD_CAMERA, "the output camera is not orthographic");
    }
    offset *offsets = NULL;
    float z2 = 0.0f;
    wx_result r = radius > 0.0f ? build_offsets(target, ctw, radius, &offsets, texels, &z2, err)
                                : WX_OK;
    free(offsets);
    return r;
}

wx_result wx_gather_owned(const wx_gather_view *views, int count, int threads, float **owned,
                          wx_error *err)
{
    *owned = NULL;
    size_t total = 0;
    for (int k = 0; k < count; ++k) {
        total += views[k].owned == NULL ? (size_t)views[k].width * (size_t)views[k].height : 0;
    }
    if (total == 0) {
        return WX_OK;
    }
    wx_owner_view *owners = malloc((size_t)count * sizeof *owners);
    float *planes = wx_big_malloc(total * sizeof *planes);
    if (owners == NULL || planes == NULL) {
        free(owners);
        free(planes);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "gather: out of memory (ownership)");
    }
    for (int k = 0; k < count; ++k) {
        wx_owner_view_init(&owners[k], views[k].camera, views[k].depth, views[k].width,
                           views[k].height);
        owners[k].normal = views[k].outward ? views[k].normal : NULL;
    }
    wx_result r = WX_OK;
    size_t at = 0;
    for (int k = 0; k < count && r == WX_OK; ++k) {
        if (views[k].owned != NULL) {
            continue;
        }
        const float *n = views[k].normal;
        r = wx_owned_fraction(owners, count, k, n, n + 1, n + 2, 3, threads, planes + at, err);
        at += (size_t)views[k].width * (size_t)views[k].height;
    }
    free(owners);
    if (r != WX_OK) {
        free(planes);
        return r;
    }
    *owned = planes;
    return WX_OK;
}

wx_result wx_gather_compute(const wx_gather_def *def, float *mask_out, wx_gather_stats *stats,
                            wx_error *err)
{
    wx_result result = check_target(&def->target, err);
    for (int k = 0; k < def->input_count && result == WX_OK; ++k) {
        result = check_view(&def->inputs[k], true, "input camera", k, err);
    }
    if (result != WX_OK) {
        return result;
    }
    if (def->input_count < 0 || (def->input_count > 0 && def->inputs == NULL)) {
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "gather: bad input camera list");
    }
    if (!(def->radius >= 0.0f) || !isfinite(def->radius)) {
        return wx_fail(err, WX_CAUSE_BAD_VALUE, "gather: the second-pass radius must be >= 0");
    }
    const wx_target *out = &def->target;
    double out_ctw[16], out_wtc[16];
    if (!wx_matrix_to_affine(out->camera->ctw, out_ctw) ||
        !wx_matrix_to_affine(out->camera->wtc, out_wtc)) {
        return wx_fail(err, WX_CAUSE_BAD_CAMERA,
                       "gather: the output camera is not orthographic (its matrices must "
                       "have the last column 0 0 0 1)");
    }

    const size_t texels = (size_t)out->width * (size_t)out->height;
    const bool adaptive = def->adaptive;
    const bool second = !adaptive && def->radius > 0.0f;
    if (adaptive && (!(def->noise > 0.0f) || !(def->max_radius >= 0.0f))) {
        return wx_fail(err, WX_CAUSE_BAD_VALUE,
                       "gather: adaptive smoothing needs noise > 0 and max_radius >= 0");
    }
    float *adaptive_planes = NULL;
    if (adaptive) {
        adaptive_planes = wx_big_malloc(3 * texels * sizeof *adaptive_planes);
        if (adaptive_planes == NULL) {
            return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "gather: out of memory (%zu texels)",
                           texels);
        }
    }
    input_cam *cams = NULL;
    offset *offsets = NULL;
    float *scratch = NULL;
    int offset_count = 0;
    float z2 = 0.0f;
    if (def->input_count > 0) {
        cams = calloc((size_t)def->input_count, sizeof *cams);
        if (cams == NULL) {
            return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "gather: out of memory");
        }
    }
    for (int k = 0; k < def->input_count && result == WX_OK; ++k) {
        result = prepare_input(out, out_ctw, &def->inputs[k], k, &cams[k], err);
    }
    float *owned = NULL; // the shares the caller did not give
    if (result == WX_OK) {
        result = wx_gather_owned(def->inputs, def->input_count, def->threads, &owned, err);
        for (int k = 0, at = 0; k < def->input_count && owned != NULL; ++k) {
            if (def->inputs[k].owned == NULL) {
                cams[k].owned = owned + at;
                at += def->inputs[k].width * def->inputs[k].height;
            }
        }
    }
    int pad_x = 0, pad_y = 0;
    size_t stride = 0, plane = 0;
    if (result == WX_OK && second) {
        result = build_offsets(out, out_ctw, def->radius, &offsets, &offset_count, &z2, err);
        for (int o = 0; o < offset_count; ++o) {
            pad_x = abs(offsets[o].di) > pad_x ? abs(offsets[o].di) : pad_x;
            pad_y = abs(offsets[o].dj) > pad_y ? abs(offsets[o].dj) : pad_y;
        }
        // Columns: margin, the map rounded up to whole chunks, margin.
        stride = (size_t)pad_x * 2 + ((size_t)out->width + CHUNK - 1) / CHUNK * CHUNK;
        plane = stride * ((size_t)out->height + 2 * (size_t)pad_y);
        if (result == WX_OK) {
            // Zeroed: margins have normal 0 (weight 0) and value 0.
            scratch = wx_big_calloc(5 * plane, sizeof *scratch);
            if (scratch == NULL) {
                result = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "gather: out of memory (%zu texels)",
                                 texels);
            }
        }
    }
    if (result != WX_OK) {
        free(cams);
        free(offsets);
        free(adaptive_planes);
        free(owned);
        return result;
    }

    gather_job job;
    memset(&job, 0, sizeof job);
    job.width = out->width;
    job.height = out->height;
    job.depth = out->depth;
    job.normal = out->normal;
    job.cams = cams;
    job.cam_count = def->input_count;
    job.bilinear = def->sampling != WX_GATHER_NEAREST;
    job.mask = mask_out;
    job.first = mask_out;
    job.first_stride = (size_t)out->width;
    job.tiles_x = (out->width + TILE - 1) / TILE;
    job.tiles_y = (out->height + TILE - 1) / TILE;
    if (adaptive) {
        job.adaptive = true;
        job.first = adaptive_planes;
        job.first_initial = adaptive_planes + texels;
        job.first_hits = adaptive_planes + 2 * texels;
    }
    if (second) {
        job.second = true;
        job.stride = stride;
        job.base = (size_t)pad_y * stride + (size_t)pad_x;
        job.first = scratch;
        job.first_base = job.base;
        job.first_stride = stride;
        job.pd = scratch + plane;
        job.pnx = scratch + 2 * plane;
        job.pny = scratch + 3 * plane;
        job.pnz = scratch + 4 * plane;
        job.offsets = offsets;
        job.offset_count = offset_count;
        job.z2 = z2;
        job.inv_radius = 1.0f / def->radius;
        job.sum = def->second_pass == WX_SECOND_PASS_SUM;
    }
    // Out of memory for the pool: it stays NULL and the passes run serially.
    wx_pool *pool = NULL;
    if (def->threads > 1) {
        wx_pool_create(def->threads, &pool, NULL);
    }
    const int tiles = job.tiles_x * job.tiles_y;
    const int bands = (out->height + ROWS_PER_ITEM - 1) / ROWS_PER_ITEM;

    wx_progress progress;
    wx_progress_begin(&progress, "gather", tiles + (second ? bands : 0), def->quiet);
    job.progress = &progress;
    double t0 = wx_now_s();
    run_pass(&job, 1, tiles, pool);
    double t1 = wx_now_s();
    if (second) {
        job.progress_base = tiles;
        run_pass(&job, 2, bands, pool);
    }
    wx_adaptive_stats smoothing;
    memset(&smoothing, 0, sizeof smoothing);
    if (adaptive) {
        wx_adaptive_def ad;
        memset(&ad, 0, sizeof ad);
        ad.width = out->width;
        ad.height = out->height;
        ad.depth = out->depth;
        ad.normal = out->normal;
        ad.total = job.first;
        ad.initial = job.first_initial;
        ad.hits = job.first_hits;
        wx_matrix_row3(out_ctw, 0, ad.step_i);
        wx_matrix_row3(out_ctw, 1, ad.step_j);
        wx_matrix_row3(out_ctw, 2, ad.step_d);
        for (int k = 0; k < 3; ++k) {
            ad.step_i[k] /= out->width;
            ad.step_j[k] /= -out->height; // j grows downwards, v upwards
        }
        ad.noise = def->noise;
        ad.max_radius = def->max_radius;
        ad.pool = pool;
        // Its statistics (sorting the radii and the capped texels' noise) only
        // for a caller that reads them.
        result = wx_adaptive_smooth(&ad, mask_out, stats != NULL ? &smoothing : NULL, err);
        free(adaptive_planes);
        if (result != WX_OK) {
            wx_progress_end(&progress);
            wx_pool_destroy(pool);
            free(cams);
            free(owned);
            return result;
        }
    }
    double t2 = wx_now_s();
    wx_progress_end(&progress);

    float max_value = 0.0f;
    int64_t surface = 0, dirty = 0;
    for (size_t t = 0; t < texels; ++t) {
        surface += !wx_depth_is_empty(out->depth[t]);
        dirty += mask_out[t] > 0.0f;
        max_value = mask_out[t] > max_value ? mask_out[t] : max_value;
    }
    if (def->normalize && max_value > 0.0f) {
        float inv = 1.0f / max_value;
        for (size_t t = 0; t < texels; ++t) {
            mask_out[t] *= inv;
        }
    }
    if (stats != NULL) {
        stats->surface_texels = surface;
        stats->dirty_texels = dirty;
        stats->max_value = max_value;
        stats->first_pass_s = t1 - t0;
        stats->second_pass_s = t2 - t1;
        stats->target_hits = smoothing.target_hits;
        stats->median_radius = smoothing.median_radius;
        stats->largest_radius = smoothing.max_radius_used;
        stats->capped_texels = smoothing.capped;
        stats->capped_noise = smoothing.capped_noise;
        memcpy(stats->capped_noise_bins, smoothing.capped_noise_bins,
               sizeof stats->capped_noise_bins);
    }
    wx_pool_destroy(pool);
    free(scratch);
    free(offsets);
    free(cams);
    free(owned);
    return WX_OK;
}
