// ownership.c: which input camera a surface point belongs to (ownership.h).
#include "model/ownership.h"
#include "core/big_alloc.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/matrix.h"
#include "core/parallel.h"
#include "model/maps.h"

// Ties between two views' |n . view| go to the view listed first.
#define TIE_COSINE 1e-4f
// Slopes steeper than this (|n . view|) count as this one (the collider's).
#define MIN_SLOPE_COS 0.05f
// A surface seen exactly edge-on (n . view = 0, up to rounding) still counts as
// facing the view.
#define FACING_SLACK 1e-4f
// Points a border texel is cut into, per side.
enum { SUB = 4 };

void wx_owner_view_init(wx_owner_view *view, const wx_camera *camera, const float *depth,
                        int width, int height)
{
    view->camera = camera;
    view->depth = depth;
    view->normal = NULL;
    view->width = width;
    view->height = height;
    wx_camera_view_dir(camera, view->view);
    float w, h;
    wx_camera_frame_size(camera, &w, &h);
    view->texel_ws = fmaxf(w / (float)width, h / (float)height);
}

// Depth at continuous texel coordinates (x, y) (centres at integers): bilinear
// when the four texels around hold a surface, else the texel's own; false when
// the texel holding (x, y) has none.
static bool depth_at(const float *depth, int width, int height, double x, double y, double *own,
                     double *between)
{
    int i = (int)floor(x + 0.5), j = (int)floor(y + 0.5);
    if (i < 0 || j < 0 || i >= width || j >= height) {
        return false;
    }
    float d = depth[(size_t)j * (size_t)width + (size_t)i];
    if (wx_depth_is_empty(d)) {
        return false;
    }
    *own = d;
    *between = d;
    int i0 = (int)floor(x), j0 = (int)floor(y);
    if (i0 < 0 || j0 < 0 || i0 + 1 >= width || j0 + 1 >= height) {
        return true;
    }
    const float *row0 = depth + (size_t)j0 * (size_t)width + (size_t)i0;
    const float *row1 = row0 + width;
    if (wx_depth_is_empty(row0[0]) || wx_depth_is_empty(row0[1]) || wx_depth_is_empty(row1[0]) ||
        wx_depth_is_empty(row1[1])) {
        return true;
    }
    double fx = x - i0, fy = y - j0;
    *between = (1.0 - fy) * ((1.0 - fx) * row0[0] + fx * row0[1]) +
               fy * ((1.0 - fx) * row1[0] + fx * row1[1]);
    return true;
}

// The depth tolerance of wx_owner_sees for a surface of unit normal n at
// depths d (the point's) and own (the texel's).
static double tolerance(const wx_owner_view *view, const float n[3], double d, double own)
{
    float c = fabsf(n[0] * view->view[0] + n[1] * view->view[1] + n[2] * view->view[2]);
    float cs = c > MIN_SLOPE_COS ? c : MIN_SLOPE_COS;
    double tan_view = sqrt(fmax(0.0, 1.0 - (double)c * c)) / cs;
    return view->texel_ws * (0.5 + tan_view) + 4e-6 * (fabs(d) + fabs(own));
}

// The texel of `view` that map-space point uvd falls in (false outside).
static bool texel_of(const wx_owner_view *view, const double uvd[3], size_t *t)
{
    int i = (int)floor(uvd[0] * view->width), j = (int)floor((1.0 - uvd[1]) * view->height);
    if (i < 0 || j < 0 || i >= view->width || j >= view->height) {
        return false;
    }
    *t = (size_t)j * (size_t)view->width + (size_t)i;
    return true;
}

// The length of a normal m a layer records, 0 where it records none usable.
static float normal_length(const float m[3])
{
    float len = sqrtf(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    return len > 1e-6f && isfinite(len) ? len : 0.0f;
}

// wx_owner_sees with p already in the view's map space (uvd), its depth known
// to within `slack` (world units; 0: exactly) besides the view's own tolerance.
static bool sees_projected(const wx_owner_view *view, const double uvd[3], const float n[3],
                           double slack)
{
    float mu[3];
    const float *slope = n; // the surface whose slope sets the precision
    if (view->normal != NULL) {
        // A layer's normals point out of the solid, either way along the view:
        // the point's surface must face the way the layer's texel does. Most
        // layers hold another surface at p's texel: the depth tells first.
        size_t t;
        if (!texel_of(view, uvd, &t)) {
            return false;
        }
        double own = view->depth[t];
        if (wx_depth_is_empty(view->depth[t]) ||
            !(fabs(uvd[2] - own) <= fmax(tolerance(view, n, uvd[2], own), slack))) {
            return false;
        }
        const float *m = view->normal + 3 * t;
        if (!(n[0] * m[0] + n[1] * m[1] + n[2] * m[2] > 0.0f)) {
            return false;
        }
        // The layer's precision is that of the surface it records there (the
        // collider's candidate test reads each camera's own normal): with the
        // point's, a wall just below a roof's eave lay within a top camera's
        // tolerance for a vertical surface (tens of texels) of the roof that
        // camera holds, and the roof's normal made it the most head-on.
        float len = normal_length(m);
        if (len > 0.0f) {
            for (int k = 0; k < 3; ++k) {
                mu[k] = m[k] / len;
            }
            if (!(fabs(uvd[2] - own) <= fmax(tolerance(view, mu, uvd[2], own), slack))) {
                return false;
            }
            slope = mu;
        }
    }
    double x = uvd[0] * view->width - 0.5, y = (1.0 - uvd[1]) * view->height - 0.5;
    double own, between;
    if (!depth_at(view->depth, view->width, view->height, x, y, &own, &between)) {
        return false;
    }
    double precision = fmax(tolerance(view, slope, uvd[2], own), slack);
    return fabs(uvd[2] - own) <= precision && fabs(uvd[2] - between) <= precision;
}

bool wx_owner_sees(const wx_owner_view *view, const double p[3], const float n[3])
{
    // The surface must face the view (a normal map's normals face its camera).
    float facing = n[0] * view->view[0] + n[1] * view->view[1] + n[2] * view->view[2];
    if (view->normal == NULL && !(facing < FACING_SLACK)) {
        return false;
    }
    double uvd[3];
    wx_matrix_apply_affine(view->camera->wtc, p, uvd);
    return sees_projected(view, uvd, n, 0.0);
}

// |d - depth| of p against the texel of `view` it falls in (+inf outside).
static double depth_error(const wx_owner_view *view, const double p[3])
{
    double uvd[3];
    wx_matrix_apply_affine(view->camera->wtc, p, uvd);
    size_t t;
    if (!texel_of(view, uvd, &t)) {
        return INFINITY;
    }
    float own = view->depth[t];
    return wx_depth_is_empty(own) ? INFINITY : fabs(uvd[2] - own);
}

// Two layers of one camera (docs/design.md section 14): the same matrices.
static bool same_camera(const wx_owner_view *a, const wx_owner_view *b)
{
    return a->camera == b->camera || memcmp(a->camera->wtc, b->camera->wtc, sizeof a->camera->wtc) == 0;
}

// p projected into the map space of the views of one camera: the layers of a
// camera share it (wx_owner_of tests each of them).
typedef struct projection {
    const wx_camera *camera;
    double uvd[3];
} projection;

// p in view's map space, projected once per camera.
static const double *projected(const wx_owner_view *view, const double p[3], projection *cache)
{
    if (cache->camera == NULL ||
        (cache->camera != view->camera &&
         memcmp(cache->camera->wtc, view->camera->wtc, sizeof view->camera->wtc) != 0)) {
        wx_matrix_apply_affine(view->camera->wtc, p, cache->uvd);
        cache->camera = view->camera;
    }
    return cache->uvd;
}

static bool sees_cached(const wx_owner_view *view, const double p[3], const float n[3],
                        double slack, projection *cache)
{
    float facing = n[0] * view->view[0] + n[1] * view->view[1] + n[2] * view->view[2];
    if (view->normal == NULL && !(facing < FACING_SLACK)) {
        return false;
    }
    return sees_projected(view, projected(view, p, cache), n, slack);
}

// How head-on view v sees p: N . view with the normal v itself records at p's
// texel when v is a layer holding a surface there on p's side (a layer's
// normals are its own), else with n. The collider's pick_camera compares the
// cameras that may take a hit each by its own texel's normal, so the border
// between two views' parts is drawn where the collider draws it: with one
// normal for every view, on a curved surface (the roots of Spot's horns and
// ears) the two borders parted by a fraction of a texel times the curvature,
// and the band between them was counted by one view's hits and the other's
// share (docs/cameras.md, "Initial dirt and ownership").
static float view_along(const wx_owner_view *v, const double p[3], const float n[3],
                        projection *cache)
{
    float along = n[0] * v->view[0] + n[1] * v->view[1] + n[2] * v->view[2];
    if (v->normal == NULL) {
        return along;
    }
    size_t t;
    if (!texel_of(v, projected(v, p, cache), &t)) {
        return along;
    }
    const float *m = v->normal + 3 * t;
    float len = normal_length(m);
    if (wx_depth_is_empty(v->depth[t]) || len == 0.0f ||
        !(n[0] * m[0] + n[1] * m[1] + n[2] * m[2] > 0.0f)) {
        return along; // another surface, or none: sees_projected rejects it
    }
    return (m[0] * v->view[0] + m[1] * v->view[1] + m[2] * v->view[2]) / len;
}

// wx_owner_of for a point known to within `slack` (sees_projected).
static int owner_within(const wx_owner_view *views, int count, const double p[3], const float n[3],
                        int known, double slack)
{
    int best = -1;
    float best_cos = -1.0f;
    bool best_outside = true;
    projection cache = { NULL, { 0.0, 0.0, 0.0 } };
    for (int k = 0; k < count; ++k) {
        const wx_owner_view *v = &views[k];
        float along = view_along(v, p, n, &cache);
        float c = fabsf(along);
        // Two cameras facing each other see every surface equally head-on;
        // with layers one sees it from outside (its normal towards the
        // camera), the other through the solid, in a layer whose index
        // changes wherever another part crosses its rays: the tie goes to the
        // one outside (the collider's pick_camera agrees).
        bool outside = v->normal == NULL || along < 0.0f;
        if (best >= 0 && outside != best_outside && c >= best_cos - TIE_COSINE &&
            c <= best_cos + TIE_COSINE) {
            if (outside && (k == known || sees_cached(v, p, n, slack, &cache))) {
                best = k;
                best_cos = c;
                best_outside = true;
            }
            continue;
        }
        if (!(c > best_cos + TIE_COSINE)) {
            // Ties go to the view listed first, but between two layers of one
            // camera that both see p (a pane 1 mm in front of a wall: within
            // the depth tolerance of each other) to the layer whose surface p
            // is on.
            if (best >= 0 && v->normal != NULL && c >= best_cos - TIE_COSINE &&
                same_camera(v, &views[best]) &&
                (k == known || sees_cached(v, p, n, slack, &cache)) &&
                (k == known || depth_error(v, p) < depth_error(&views[best], p))) {
                best = k;
            }
            continue;
        }
        if (k == known || sees_cached(v, p, n, slack, &cache)) {
            best = k;
            best_cos = c;
            best_outside = outside;
        }
    }
    return best;
}

int wx_owner_of(const wx_owner_view *views, int count, const double p[3], const float n[3],
                int known)
{
    return owner_within(views, count, p, n, known, 0.0);
}

typedef struct owned_job {
    const wx_owner_view *views;
    int count, c;
    const float *nx, *ny, *nz;
    size_t stride;
    float *out;
} owned_job;

// World point of view c at continuous texel coordinates (x, y), depth d.
static void world_point(const owned_job *job, double x, double y, double d, double p[3])
{
    const wx_owner_view *v = &job->views[job->c];
    const double uvd[3] = { (x + 0.5) / v->width, 1.0 - (y + 0.5) / v->height, d };
    wx_matrix_apply_affine(v->camera->ctw, uvd, p);
}

static bool texel_normal(const owned_job *job, size_t t, float n[3])
{
    n[0] = job->nx[t * job->stride];
    n[1] = job->ny[t * job->stride];
    n[2] = job->nz[t * job->stride];
    float len = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 1e-6f) || !isfinite(len)) {
        return false;
    }
    for (int k = 0; k < 3; ++k) {
        n[k] /= len;
    }
    return true;
}

// Pass 1: each texel's centre, 1 owned or 0 (also without a surface).
static void centres(int64_t begin, int64_t end, int worker, void *context)
{
    (void)worker;
    const owned_job *job = context;
    const wx_owner_view *v = &job->views[job->c];
    for (int64_t j = begin; j < end; ++j) {
        for (int i = 0; i < v->width; ++i) {
            size_t t = (size_t)j * (size_t)v->width + (size_t)i;
            float d = v->depth[t], n[3];
            job->out[t] = 0.0f;
            if (wx_depth_is_empty(d) || !texel_normal(job, t, n)) {
                continue;
            }
            double p[3];
            world_point(job, i, (double)j, d, p);
            job->out[t] = wx_owner_of(job->views, job->count, p, n, job->c) == job->c;
        }
    }
}

// Pass 2: texels whose surface neighbours were decided otherwise, cut into SUB x
// SUB points. Reads the centres' verdicts (copied) and writes fractions.
typedef struct border_job {
    const owned_job *owned;
    const float *centre; // pass 1's verdicts
} border_job;

static void borders(int64_t begin, int64_t end, int worker, void *context)
{
    (void)worker;
    const border_job *b = context;
    const owned_job *job = b->owned;
    const wx_owner_view *v = &job->views[job->c];
    const int W = v->width, H = v->height;
    for (int64_t j = begin; j < end; ++j) {
        for (int i = 0; i < W; ++i) {
            size_t t = (size_t)j * (size_t)W + (size_t)i;
            float d = v->depth[t], n[3];
            if (wx_depth_is_empty(d) || !texel_normal(job, t, n)) {
                continue;
            }
            bool mixed = false;
            for (int dj = -1; dj <= 1 && !mixed; ++dj) {
                for (int di = -1; di <= 1 && !mixed; ++di) {
                    int ni = i + di, nj = (int)j + dj;
                    if (ni < 0 || nj < 0 || ni >= W || nj >= H) {
                        continue;
                    }
                    size_t u = (size_t)nj * (size_t)W + (size_t)ni;
                    mixed = !wx_depth_is_empty(v->depth[u]) && b->centre[u] != b->centre[t];
                }
            }
            if (!mixed) {
                continue;
            }
            // A point between texel centres lies on the surface only to this
            // view's precision (half a texel plus the surface's slope across
            // one: the rule's tolerance), so another view whose surface lies
            // within that of it sees it. Seen at a grazing angle that
            // precision is many of another view's: held to its own tolerance,
            // a head-on view missed the points of a silhouette texel whose
            // centre it owns, and the texel owned a share of a surface whose
            // deposits the collider (deciding at the hit, exactly) never gave
            // it, which read as a dark streak along the silhouette (docs/mask.md).
            double slack = tolerance(v, n, d, d);
            int owned = 0;
            for (int sy = 0; sy < SUB; ++sy) {
                for (int sx = 0; sx < SUB; ++sx) {
                    double x = i + (sx + 0.5) / SUB - 0.5, y = (double)j + (sy + 0.5) / SUB - 0.5;
                    double own = d, between = d, p[3];
                    (void)depth_at(v->depth, W, H, x, y, &own, &between); // texel t holds d
                    // A point this view would not see itself (the depth
                    // between the texel centres off the texel's own by more
                    // than the rule's tolerance: a layer's neighbours holding
                    // other surfaces, the point in mid-air) lies on no
                    // surface of the texel: its centre's verdict stands for
                    // it. (wx_owner_sees' test of this view at p, without
                    // projecting p back: p's texel is t, whose normal is n.)
                    if (!(fabs(between - own) <= tolerance(v, n, between, own))) {
                        owned += b->centre[t] > 0.5f;
                        continue;
                    }
                    world_point(job, x, y, between, p);
                    owned += owner_within(job->views, job->count, p, n, job->c, slack) == job->c;
                }
            }
            job->out[t] = (float)owned / (float)(SUB * SUB);
        }
    }
}

wx_result wx_owned_fraction(const wx_owner_view *views, int count, int c, const float *nx,
                            const float *ny, const float *nz, size_t stride, int threads,
                            float *out, wx_error *err)
{
    const wx_owner_view *v = &views[c];
    owned_job job = { .views = views, .count = count, .c = c, .nx = nx, .ny = ny, .nz = nz,
                      .stride = stride, .out = out };
    size_t n = (size_t)v->width * (size_t)v->height;
    float *centre = wx_big_malloc((n > 0 ? n : 1) * sizeof *centre);
    if (centre == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (%d x %d ownership)",
                       v->width, v->height);
    }
    wx_parallel_for(threads, v->height, 8, centres, &job);
    memcpy(centre, out, n * sizeof *centre);
    border_job b = { .owned = &job, .centre = centre };
    wx_parallel_for(threads, v->height, 8, borders, &b);
    free(centre);
    return WX_OK;
}
