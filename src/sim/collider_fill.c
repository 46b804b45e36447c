// collider_fill.c: surfaces a camera misses (docs/physics.md, "Surfaces a camera
// sees edge-on").
//
// The point rule lets any camera veto a collision ("not behind", and a texel
// with no surface says so too). A camera that sees a surface edge-on does not
// record it: rasterising a face whose projection is thinner than a texel
// leaves the texels it passes through empty, or holding whatever lies behind.
// So a one-sided sign or an open pipe lined up with the camera grid was free
// space for the cameras that look along it, and every particle passed through
// it (an open tube along a side camera's axis: 97% of the rain fell through).
//
// Every other camera's surface samples tell where that happens: a texel of
// camera A holds a point p of a surface with normal n; a camera B that sees
// that surface at a grazing angle (|n . axis_B| small) and says "not behind"
// just inside it (p - n * a quarter of A's texel), while none of B's crossings
// over the 3 x 3 texels around lies near p, does not know the surface is
// there. The same holds along B's silhouette: where the surface lies between
// two texel centres of B, the texel outside holds nothing, and B cut a
// staircase of up to a texel into the solid, which turns with the model in
// the camera grid (a closed cylinder lined up with the side cameras: its
// flanks took 11% more rain than turned 30 degrees, against 1.2% between two
// seeds). B then stops vetoing over that stretch of its ray: its texels
// around get a *fill*, a solid interval around p's depth (half a texel of
// either camera wider, so that the fills of neighbouring samples join), and
// the other cameras, which see the surface, decide where a particle meets
// it. A fill is not a surface: it gives no hit (pick_camera skips it, but
// where every camera that agrees holds only a fill), so its texel's normal,
// impact and dirt stay unread.
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/big_alloc.h"
#include "core/matrix.h"
#include "core/parallel.h"
#include "sim/collider_internal.h"

/// B may miss a surface it sees at a cosine below this (73 degrees from its axis).
#define FILL_GRAZING 0.3
/// Only a camera that sees the surface at a cosine of at least this vouches for it.
#define FILL_WITNESS 0.5

// The fills found for one camera: per texel, whether it has one and its
// interval. Zeroed pages that are never written stay unmapped, so the three
// planes cost memory only where fills are (wx_big_calloc).
enum { FILL_AROUND = 1, FILL_OWN = 2 }; ///< a span's set: a sample's texel, or one around

typedef struct fill_span {
    uint8_t *set; ///< NULL until a fill is needed
    float *lo, *hi;
} fill_span;

// World point of texel-space (X, Y, D): inverse of the camera's affine map.
static bool texel_to_world(const double inv[9], const wx_collider_camera *cam, double X, double Y,
                           double D, double p[3])
{
    double r[3] = { X - cam->mx[3], Y - cam->my[3], D - cam->md[3] };
    for (int k = 0; k < 3; ++k) {
        p[k] = inv[3 * k] * r[0] + inv[3 * k + 1] * r[1] + inv[3 * k + 2] * r[2];
    }
    return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]);
}

// Texel-space point (X, Y, D) of world point p in camera `cam`.
static void world_to_texel(const wx_collider_camera *cam, const double p[3], double *X, double *Y,
                           double *D)
{
    *X = p[0] * cam->mx[0] + p[1] * cam->mx[1] + p[2] * cam->mx[2] + cam->mx[3];
    *Y = p[0] * cam->my[0] + p[1] * cam->my[1] + p[2] * cam->my[2] + cam->my[3];
    *D = p[0] * cam->md[0] + p[1] * cam->md[1] + p[2] * cam->md[2] + cam->md[3];
}

// Whether some crossing of camera B over the 3 x 3 texels around (tx, ty)
// lies within `tol` of depth D: then B records a surface there (this one, a
// texel off at most, or one it meets: the top of a box whose side B sees
// edge-on), and what it says is its precision, not a miss. (Asking the
// surface to face the way of the sample's filled the last texels under a
// box's top too, but it changed where dust settles on thin ledges, a
// handrail's top, where the top camera's texel beside the ledge got a fill;
// left for later.)
static bool records_near(const wx_collider_camera *B, int tx, int ty, double D, double tol)
{
    size_t texels = (size_t)B->width * (size_t)B->height;
    for (int j = ty - 1; j <= ty + 1; ++j) {
        for (int i = tx - 1; i <= tx + 1; ++i) {
            if (i < 0 || j < 0 || i >= B->width || j >= B->height) {
                continue;
            }
            size_t t = (size_t)j * (size_t)B->width + (size_t)i;
            for (int k = 0; k < B->layers; ++k) {
                size_t at = (size_t)k * texels + t;
                float d = B->depth[at];
                if (!isfinite(d)) {
                    break;
                }
                if (fabs(d - D) <= tol) {
                    return true;
                }
            }
        }
    }
    return false;
}

// Whether depth D lies more than `tol` inside one of the solids of camera B's
// texel t (its own crossings, no bilinear cell): most samples on a wall do, for
// the cameras that see the wall edge-on and the solid behind it; the full
// tests below need not run for them.
static bool deep_inside(const wx_collider_camera *B, size_t t, double D, double tol)
{
    size_t texels = (size_t)B->width * (size_t)B->height;
    if (B->layers <= 1) {
        return D > (double)B->depth[t] + tol;
    }
    for (int k = 0; k < B->layers; ++k) {
        size_t at = (size_t)k * texels + t;
        float d = B->depth[at];
        if (!isfinite(d)) {
            return false;
        }
        int kind = B->role[at] & WX_ROLE_KIND;
        if (kind == WX_ROLE_TAIL) {
            return D > d + tol;
        }
        if (kind == WX_ROLE_ENTER && k + 1 < B->layers && D > d + tol &&
            D < (double)B->depth[at + texels] - tol) {
            return true;
        }
    }
    return false;
}

// A sample that camera b missed: the texel-space point just inside the surface.
typedef struct fill_record {
    int b;
    float X, Y, D;
    bool clipped; ///< a texel the surface's plane clips: no spreading around it
} fill_record;

// What one worker found, in a list that grows.
typedef struct fill_list {
    fill_record *items;
    size_t count, capacity;
    bool failed;
} fill_list;

typedef struct fill_job {
    const wx_collider *collider;
    const double (*axes)[3];
    int a;         ///< the witness camera
    double inv[9]; ///< its texel space to world (linear part)
    /// World displacement of one texel along X and along Y of every camera, at
    /// a constant depth (the first two columns of its inverse).
    double step_x[WX_MAX_INPUT_CAMERAS][3], step_y[WX_MAX_INPUT_CAMERAS][3];
    double back_len[WX_MAX_INPUT_CAMERAS]; ///< |back| of every camera (d units per world unit)
    fill_list *lists;                      ///< one per worker
} fill_job;

static void push_record(fill_list *list, fill_record r)
{
    if (list->count == list->capacity) {
        size_t capacity = list->capacity > 0 ? 2 * list->capacity : 256;
        fill_record *items = realloc(list->items, capacity * sizeof *items);
        if (items == NULL) {
            list->failed = true;
            return;
        }
        list->items = items;
        list->capacity = capacity;
    }
    list->items[list->count++] = r;
}

// Whether the witness camera sees the surface's plane go on to B's texel: the
// point of the plane under the texel's deepest corner (dx, dy texels of B
// from p) lies on one of A's crossings there. Past a face's edge (a box's top
// beyond its side) the plane goes on but the face does not, and A sees
// something else there; a fill would change nothing the other cameras do not
// decide, but it is not needed.
static bool witness_sees_plane(const fill_job *job, const double p[3], const float *n, double nl,
                               double dx, double dy, int b)
{
    const wx_collider *collider = job->collider;
    const wx_collider_camera *A = &collider->cameras[job->a];
    const double *ex = job->step_x[b], *ey = job->step_y[b];
    double c[3], h = 0.0;
    for (int k = 0; k < 3; ++k) {
        c[k] = p[k] + dx * ex[k] + dy * ey[k];
        h += (c[k] - p[k]) * n[k] / nl;
    }
    for (int k = 0; k < 3; ++k) {
        c[k] -= h * n[k] / nl; // onto the plane
    }
    double X, Y, D;
    world_to_texel(A, c, &X, &Y, &D);
    if (!(X >= 0.0 && X < A->width && Y >= 0.0 && Y < A->height)) {
        return false;
    }
    // A sees the surface at a cosine of 0.5 or more: across half a texel its
    // depth changes by at most tan(60 degrees) of a half texel.
    double tol = 1.5 * A->texel_ws / job->back_len[job->a];
    size_t texels = (size_t)A->width * (size_t)A->height;
    size_t t = (size_t)(int)Y * (size_t)A->width + (size_t)(int)X;
    for (int k = 0; k < A->layers; ++k) {
        float d = A->depth[(size_t)k * texels + t];
        if (!isfinite(d)) {
            break;
        }
        if (fabs(d - D) <= tol) {
            return true;
        }
    }
    return false;
}

// The texels of B around a witness's point that the surface's plane cuts
// into and that say "not behind" there. The quarter-texel sample above lands
// in one texel of B; along B's silhouette the surface also clips the texel
// beside it, whose centre lies outside: a tube along B's axis has one such
// texel every few rows, at the same place along its whole length, and each
// let the rain a millimetre or two into the wall (the rows there took twice
// their share of hits, and the tube weathered 5% more on its flanks than
// turned 30 degrees). p_in is the sample pulled a quarter of A's texel
// inside; the plane through it with normal n stands for the surface over
// the 3 x 3 texels around.
static void find_cut_texels(const fill_job *job, int b, const double p_in[3], const float *n,
                            double nl, fill_list *list)
{
    const wx_collider *collider = job->collider;
    const wx_collider_camera *B = &collider->cameras[b];
    const double *ex = job->step_x[b], *ey = job->step_y[b];
    double nx = (n[0] * ex[0] + n[1] * ex[1] + n[2] * ex[2]) / nl;
    double ny = (n[0] * ey[0] + n[1] * ey[1] + n[2] * ey[2]) / nl;
    double inside = 0.25 * collider->cameras[job->a].texel_ws;
    // The surface itself, a quarter of A's texel out from p_in.
    double p[3] = { p_in[0] + inside * n[0] / nl, p_in[1] + inside * n[1] / nl,
                    p_in[2] + inside * n[2] / nl };
    double X, Y, D;
    world_to_texel(B, p, &X, &Y, &D);
    if (!(X >= 0.0 && X < B->width && Y >= 0.0 && Y < B->height)) {
        return;
    }
    double cut = B->texel_ws / 16.0;
    double tol = 2.0 * fmax(collider->cameras[job->a].texel_ws, B->texel_ws) / job->back_len[b];
    int x0 = (int)X, y0 = (int)Y;
    for (int j = y0 - 1; j <= y0 + 1; ++j) {
        for (int i = x0 - 1; i <= x0 + 1; ++i) {
            if (i < 0 || j < 0 || i >= B->width || j >= B->height) {
                continue;
            }
            // The texel's corner deepest into the solid (n . (corner - p)
            // least), and its centre outside: a texel whose centre lies inside
            // holds the solid (B draws it), or p_in's test above finds it.
            double dx = (nx > 0.0 ? i : i + 1) - X, dy = (ny > 0.0 ? j : j + 1) - Y;
            double m = dx * nx + dy * ny;
            double centre = (i + 0.5 - X) * nx + (j + 0.5 - Y) * ny;
            if (!(m < -cut) || !(centre > 0.0)) {
                continue;
            }
            size_t t = (size_t)j * (size_t)B->width + (size_t)i;
            // With one layer a fill replaces the texel's depth: one that holds
            // a surface further on (a facade behind a handrail's top) would
            // lose it, and the dust that falls there went to another camera.
            if (B->layers <= 1 && isfinite(B->depth[t])) {
                continue;
            }
            if (deep_inside(B, t, D, tol) ||
                wx_collider_camera_may_collide(collider, b, i + 0.5, j + 0.5, D) ||
                records_near(B, i, j, D, tol) || !witness_sees_plane(job, p, n, nl, dx, dy, b)) {
                continue;
            }
            push_record(list,
                        (fill_record){ b, (float)(i + 0.5), (float)(j + 0.5), (float)D, true });
        }
    }
}

// The samples of witness camera job->a over texels [begin, end): each of its
// crossings that it sees well is a point of a surface; every camera that sees
// that surface at a grazing angle and missed it gets a record.
static void find_range(int64_t begin, int64_t end, int worker, void *context)
{
    fill_job *job = context;
    const wx_collider *collider = job->collider;
    const wx_collider_camera *A = &collider->cameras[job->a];
    fill_list *list = &job->lists[worker];
    size_t texels = (size_t)A->width * (size_t)A->height;
    double inside = 0.25 * A->texel_ws;
    const double *aa = job->axes[job->a];
    for (int64_t t = begin; t < end; ++t) {
        for (int k = 0; k < A->layers; ++k) {
            size_t at = (size_t)k * texels + (size_t)t;
            float d = A->depth[at];
            if (!isfinite(d)) {
                break; // the texel's later layers are empty too
            }
            size_t layer = A->layers > 1 ? A->origin[at] : 0;
            const float *n = A->normal + 3 * (layer * texels + (size_t)t);
            double nl = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
            // A witness sees the surface well (its crossing then lies on it:
            // margins widen only the cameras that see it worse).
            if (!(nl > 1e-6) || !isfinite(nl) ||
                !(fabs(n[0] * aa[0] + n[1] * aa[1] + n[2] * aa[2]) >= FILL_WITNESS * nl)) {
                continue;
            }
            double p[3];
            bool placed = false;
            for (int b = 0; b < collider->camera_count; ++b) {
                const double *ax = job->axes[b];
                if (b == job->a ||
                    !(fabs(n[0] * ax[0] + n[1] * ax[1] + n[2] * ax[2]) < FILL_GRAZING * nl)) {
                    continue;
                }
                if (!placed) {
                    int tx = (int)(t % A->width), ty = (int)(t / A->width);
                    if (!texel_to_world(job->inv, A, tx + 0.5, ty + 0.5, d, p)) {
                        break;
                    }
                    for (int q = 0; q < 3; ++q) {
                        p[q] -= inside * n[q] / nl;
                    }
                    placed = true;
                }
                const wx_collider_camera *B = &collider->cameras[b];
                double X, Y, D;
                world_to_texel(B, p, &X, &Y, &D);
                if (!(X >= 0.0 && X < B->width && Y >= 0.0 && Y < B->height)) {
                    continue;
                }
                double tol = 2.0 * fmax(A->texel_ws, B->texel_ws) / job->back_len[b];
                if (!(deep_inside(B, (size_t)(int)Y * (size_t)B->width + (size_t)(int)X, D, tol) ||
                      wx_collider_camera_may_collide(collider, b, X, Y, D) ||
                      records_near(B, (int)X, (int)Y, D, tol))) {
                    push_record(list, (fill_record){ b, (float)X, (float)Y, (float)D, false });
                }
                find_cut_texels(job, b, p, n, nl, list);
            }
        }
    }
}

// Spreads a record into its camera's span: the 3 x 3 texels around (the
// samples lie a texel of A apart, and a surface crossing B's texels at an
// angle clips some of them between two samples), half of the larger texel
// deeper and shallower, so that neighbouring samples' fills join.
static bool spread_record(const wx_collider *collider, int a, const fill_record *r, fill_span *span)
{
    const wx_collider_camera *B = &collider->cameras[r->b];
    size_t btexels = (size_t)B->width * (size_t)B->height;
    if (span->set == NULL) {
        span->set = wx_big_calloc(btexels, 1);
        span->lo = wx_big_calloc(btexels, sizeof *span->lo);
        span->hi = wx_big_calloc(btexels, sizeof *span->hi);
        if (span->set == NULL || span->lo == NULL || span->hi == NULL) {
            return false;
        }
    }
    double bl = sqrt((double)B->back[0] * B->back[0] + (double)B->back[1] * B->back[1] +
                     (double)B->back[2] * B->back[2]);
    double grow = 0.5 * fmax(collider->cameras[a].texel_ws, B->texel_ws) / bl;
    float lo = (float)(r->D - grow), hi = (float)(r->D + grow);
    int around = r->clipped ? 0 : 1; // the texels a plane clips are found one by one
    for (int j = (int)r->Y - around; j <= (int)r->Y + around; ++j) {
        for (int i = (int)r->X - around; i <= (int)r->X + around; ++i) {
            if (i < 0 || j < 0 || i >= B->width || j >= B->height) {
                continue;
            }
            // A clipped texel's centre lies outside the surface: it is never
            // the sample's own, whose fill may make the rest of the texel's
            // ray solid where no layer is left for an interval (apply_layers).
            bool own = !r->clipped && i == (int)r->X && j == (int)r->Y;
            // A texel around that is solid there already needs none (a face
            // between two texel centres: the texel inside holds the solid,
            // and a fill there would only hide its free space further on).
            if (!own && wx_collider_camera_may_collide(collider, r->b, i + 0.5, j + 0.5, r->D)) {
                continue;
            }
            size_t bt = (size_t)j * (size_t)B->width + (size_t)i;
            span->lo[bt] = span->set[bt] ? fminf(span->lo[bt], lo) : lo;
            span->hi[bt] = span->set[bt] ? fmaxf(span->hi[bt], hi) : hi;
            span->set[bt] |= own ? FILL_OWN : FILL_AROUND;
        }
    }
    return true;
}

// A camera with one layer: the fill's start becomes the texel's depth (solid
// from there on, the one-layer rule), marked as no surface.
static void apply_one_layer(wx_collider_camera *B, size_t t, float lo)
{
    if (!(lo < B->depth[t])) {
        return;
    }
    B->depth[t] = lo;
    B->fill[t] = 1;
}

// A camera with layers: the fill goes into the texel's outline as an interval
// of its own (ENTER and LEAVE marked FILL) where it lies between the texel's
// solids; without two free layers, solid from its start on (TAIL).
static void apply_layers(wx_collider_camera *B, size_t t, float lo, float hi, bool own)
{
    int K = B->layers;
    size_t texels = (size_t)B->width * (size_t)B->height;
    float depth[WX_MAX_LAYERS];
    uint8_t role[WX_MAX_LAYERS], origin[WX_MAX_LAYERS];
    int n = 0;
    for (; n < K; ++n) {
        size_t at = (size_t)n * texels + t;
        if (!isfinite(B->depth[at])) {
            break;
        }
        depth[n] = B->depth[at];
        role[n] = B->role[at];
        origin[n] = B->origin[at];
    }
    // The first crossing at or past the fill's start, not splitting an interval.
    int j = 0;
    while (j < n && depth[j] < lo) {
        ++j;
    }
    if (j < n && (role[j] & WX_ROLE_KIND) == WX_ROLE_LEAVE) {
        lo = depth[j];
        ++j;
    }
    if (j > 0 && (role[j - 1] & WX_ROLE_KIND) == WX_ROLE_TAIL) {
        return; // solid from there on already
    }
    if (j < n && depth[j] < hi) {
        hi = depth[j];
    }
    if (!(hi > lo)) {
        return;
    }
    if (n + 2 <= K) {
        for (int k = n - 1; k >= j; --k) {
            depth[k + 2] = depth[k];
            role[k + 2] = role[k];
            origin[k + 2] = origin[k];
        }
        depth[j] = lo;
        role[j] = WX_ROLE_ENTER | WX_ROLE_FACING | WX_ROLE_FILL;
        depth[j + 1] = hi;
        role[j + 1] = WX_ROLE_LEAVE | WX_ROLE_FILL;
        origin[j] = origin[j + 1] = 0;
        n += 2;
    } else if (j < K && own) {
        depth[j] = lo;
        role[j] = WX_ROLE_TAIL | WX_ROLE_FACING | WX_ROLE_FILL;
        origin[j] = 0;
        n = j + 1;
    } else {
        return;
    }
    for (int k = 0; k < K; ++k) {
        size_t at = (size_t)k * texels + t;
        B->depth[at] = k < n ? depth[k] : INFINITY;
        B->role[at] = k < n ? role[k] : WX_ROLE_NONE;
        B->origin[at] = k < n ? origin[k] : 0;
    }
}

wx_result wx_collider_fill_missed(wx_collider *collider, const double (*axes)[3], wx_error *err)
{
    int count = collider->camera_count;
    int threads = wx_cpu_count();
    fill_span spans[WX_MAX_INPUT_CAMERAS];
    memset(spans, 0, sizeof spans);
    fill_list *lists = calloc((size_t)threads, sizeof *lists);
    bool ok = lists != NULL;
    // Every camera's samples against the maps as they are (no fill is applied
    // before all are found, so no sample is a fill and the order does not matter), in parallel over
    // its texels; then each camera's fills.
    // Every camera's texel space to world (linear part) and |back|, once.
    fill_job job = { .collider = collider, .axes = axes, .lists = lists };
    double inv[WX_MAX_INPUT_CAMERAS][9];
    bool invertible[WX_MAX_INPUT_CAMERAS];
    for (int c = 0; c < count; ++c) {
        const wx_collider_camera *C = &collider->cameras[c];
        const float *v = C->back;
        job.back_len[c] = sqrt((double)v[0] * v[0] + (double)v[1] * v[1] + (double)v[2] * v[2]);
        double m3[9] = { C->mx[0], C->mx[1], C->mx[2], C->my[0], C->my[1],
                         C->my[2], C->md[0], C->md[1], C->md[2] };
        invertible[c] = wx_invert3(m3, inv[c]);
        for (int k = 0; k < 3; ++k) {
            job.step_x[c][k] = invertible[c] ? inv[c][3 * k] : 0.0;
            job.step_y[c][k] = invertible[c] ? inv[c][3 * k + 1] : 0.0;
        }
    }
    for (int a = 0; a < count && ok; ++a) {
        const wx_collider_camera *A = &collider->cameras[a];
        if (!invertible[a]) {
            continue;
        }
        job.a = a;
        memcpy(job.inv, inv[a], sizeof job.inv);
        for (int w = 0; w < threads; ++w) {
            lists[w].count = 0;
        }
        wx_parallel_for(threads, (int64_t)A->width * A->height, 16384, find_range, &job);
        for (int w = 0; w < threads && ok; ++w) {
            ok = !lists[w].failed;
            for (size_t q = 0; q < lists[w].count && ok; ++q) {
                const fill_record *r = &lists[w].items[q];
                ok = spread_record(collider, a, r, &spans[r->b]);
            }
        }
    }
    for (int b = 0; b < count && ok; ++b) {
        wx_collider_camera *B = &collider->cameras[b];
        if (spans[b].set == NULL) {
            continue;
        }
        size_t texels = (size_t)B->width * (size_t)B->height;
        if (B->layers <= 1) {
            B->fill = wx_big_calloc(texels, 1);
            ok = B->fill != NULL;
        }
        for (size_t t = 0; t < texels && ok; ++t) {
            if (spans[b].set[t]) {
                B->fill_texels++;
                if (B->layers <= 1) {
                    apply_one_layer(B, t, spans[b].lo[t]);
                } else {
                    apply_layers(B, t, spans[b].lo[t], spans[b].hi[t],
                                 (spans[b].set[t] & FILL_OWN) != 0);
                }
            }
        }
    }
    for (int b = 0; b < count; ++b) {
        free(spans[b].set);
        free(spans[b].lo);
        free(spans[b].hi);
    }
    for (int w = 0; lists != NULL && w < threads; ++w) {
        free(lists[w].items);
    }
    free(lists);
    return ok ? WX_OK : wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (collider fills)");
}
