// masks.c: the derived masks (masks.h).
#include "sim/masks.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/limits.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "sim/noise.h"
#include "sim/particles.h"

#define PI 3.14159265358979323846

// Curvature looks at most this many texels of the grid away from a point.
#define CURVATURE_MAX_REACH 32

double wx_sigmoid(double x, double offset, double steepness)
{
    if (!(steepness > 0.0)) {
        return x;
    }
    double d = x - offset;
    return d / (2.0 * sqrt(1.0 / steepness + d * d)) + 0.5;
}

void wx_sun_direction(double elevation, double azimuth, double out[3])
{
    double e = elevation * PI / 180.0, a = azimuth * PI / 180.0;
    out[0] = cos(e) * cos(a);
    out[1] = sin(e);
    out[2] = cos(e) * sin(a);
}

int wx_mask_rays(const wx_mask_def *mask)
{
    switch (mask->kind) {
    case WX_MASK_ACCESSIBILITY:
        return mask->rays;
    case WX_MASK_EXPOSURE:
        return mask->side_weight != 0.0f ? 3 : 1;
    default:
        return 0;
    }
}

// ---------------------------------------------------------------------------
// Rays.

typedef struct job {
    const wx_masks_def *def;
    float *const *out;
    float offset;   // first start this far above the surface (ray_start)
    double first;   // length of a ray's first segment
    int mask;       // the mask being computed
    int stride;     // accessibility's pass: the points of this level (settled)
    double suns[3][3];
    double sun_weights[3];
    int sun_count;
    wx_progress *progress; // drawn by worker 0: rows of all the masks
} job;

static uint64_t splitmix(uint64_t x)
{
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

static double unit_of(uint64_t x)
{
    return (double)(x >> 11) * (1.0 / 9007199254740992.0);
}

static double radical_inverse(uint32_t i)
{
    i = (i << 16) | (i >> 16);
    i = ((i & 0x00ff00ffu) << 8) | ((i & 0xff00ff00u) >> 8);
    i = ((i & 0x0f0f0f0fu) << 4) | ((i & 0xf0f0f0f0u) >> 4);
    i = ((i & 0x33333333u) << 2) | ((i & 0xccccccccu) >> 2);
    i = ((i & 0x55555555u) << 1) | ((i & 0xaaaaaaaau) >> 1);
    return (double)i * (1.0 / 4294967296.0);
}

// An orthonormal frame (t, b) around unit n (Duff et al. 2017).
static void frame_of(const float n[3], double t[3], double b[3])
{
    double sign = n[2] >= 0.0f ? 1.0 : -1.0;
    double a = -1.0 / (sign + n[2]);
    double c = n[0] * n[1] * a;
    t[0] = 1.0 + sign * n[0] * n[0] * a;
    t[1] = sign * c;
    t[2] = -sign * n[0];
    b[0] = c;
    b[1] = sign + n[1] * n[1] * a;
    b[2] = -n[1];
}

// fmin and fmax for the rays' finite values, inline (the library calls took 4%
// of an accessibility mask's time).
static inline double min_of(double a, double b)
{
    return b < a ? b : a;
}

static inline double max_of(double a, double b)
{
    return b > a ? b : a;
}

// The part of a ray that some camera sees: beyond the last camera's frame
// nothing can stop it (docs/design.md section 4: a point no camera sees does
// not collide). The distance from p along dir where the last frame is left.
static double frames_exit(const wx_collider *collider, const double p[3], const double dir[3],
                          double length)
{
    double last = 0.0;
    for (int c = 0; c < collider->camera_count; ++c) {
        const wx_collider_camera *cam = &collider->cameras[c];
        double lo = 0.0, hi = length;
        const double *rows[2] = { cam->mx, cam->my };
        const double size[2] = { cam->width, cam->height };
        for (int a = 0; a < 2 && lo <= hi; ++a) {
            const double *m = rows[a];
            double x0 = m[0] * p[0] + m[1] * p[1] + m[2] * p[2] + m[3];
            double dx = m[0] * dir[0] + m[1] * dir[1] + m[2] * dir[2];
            if (fabs(dx) < 1e-12) {
                if (!(x0 >= 0.0 && x0 <= size[a])) {
                    hi = -1.0;
                }
                continue;
            }
            double t0 = (0.0 - x0) / dx, t1 = (size[a] - x0) / dx;
            lo = max_of(lo, min_of(t0, t1));
            hi = min_of(hi, max_of(t0, t1));
        }
        if (lo <= hi) {
            last = max_of(last, hi);
        }
    }
    return last;
}

static bool segment_free(const wx_collider *collider, const double a[3], const double b[3],
                         double length, double finest);

// segment_free past the coarse pyramid: swept when no longer than `finest`,
// else cut in two halves, each tested again.
static bool segment_past_coarse(const wx_collider *collider, const double a[3], const double b[3],
                                double length, double finest)
{
    float fa[3] = { (float)a[0], (float)a[1], (float)a[2] };
    float fb[3] = { (float)b[0], (float)b[1], (float)b[2] };
    if (wx_collider_fine_clear(collider, fa, fb)) {
        return true; // some camera sees it in front over each texel it crosses
    }
    if (length <= finest) {
        wx_hit hit;
        return !wx_collider_sweep(collider, fa, fb, &hit);
    }
    double m[3] = { 0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2]) };
    return segment_free(collider, a, m, 0.5 * length, finest) &&
           segment_free(collider, m, b, 0.5 * length, finest);
}

// Whether segment a -> b of a ray is free: cleared by the coarse pyramid, or
// cut in two halves (the finer levels bound it tighter) down to `finest`, then
// swept.
static bool segment_free(const wx_collider *collider, const double a[3], const double b[3],
                         double length, double finest)
{
    float fa[3] = { (float)a[0], (float)a[1], (float)a[2] };
    float fb[3] = { (float)b[0], (float)b[1], (float)b[2] };
    return wx_collider_coarse_clear(collider, fa, fb) ||
           segment_past_coarse(collider, a, b, length, finest);
}

// Which of up to RAY_BLOCK rays (lanes `active`; ray k from start[k] along
// unit dir[k] for length[k]) travel their length without entering a surface
// the collider records. Each ray is cut at the last camera frame it crosses,
// then walked in segments of doubling length from `first`; the rays' segments
// go side by side through the collider's vectorised coarse test, and a segment
// it cannot clear is cut and swept as segment_free does. Each ray's answer
// is its own, whichever rays share the block. Returns the lanes whose rays are
// free.
enum { RAY_BLOCK = WX_PARTICLE_BLOCK };
static uint32_t rays_free(const wx_collider *collider, uint32_t active, double start[RAY_BLOCK][3],
                          double dir[RAY_BLOCK][3], const double length[RAY_BLOCK], double first)
{
    if (collider == NULL || collider->camera_count == 0) {
        return active; // nothing can stop them
    }
    int cams[WX_MAX_INPUT_CAMERAS]; // (a collider holds at most that many)
    for (int c = 0; c < collider->camera_count; ++c) {
        cams[c] = c;
    }
    double len[RAY_BLOCK];
    for (int k = 0; k < RAY_BLOCK; ++k) {
        len[k] = (active >> k) & 1u ? frames_exit(collider, start[k], dir[k], length[k]) : 0.0;
    }
    uint32_t free_lanes = active;
    double t0 = 0.0, step = first;
    for (;;) {
        uint32_t pending = 0;
        float x0[RAY_BLOCK], y0[RAY_BLOCK], z0[RAY_BLOCK], x1[RAY_BLOCK], y1[RAY_BLOCK],
            z1[RAY_BLOCK];
        double t1[RAY_BLOCK];
        for (int k = 0; k < RAY_BLOCK; ++k) {
            bool on = ((free_lanes >> k) & 1u) && t0 < len[k];
            pending |= (uint32_t)on << k;
            t1[k] = on ? min_of(len[k], t0 + step) : t0;
            // A lane without a ray (fewer rays than lanes, or one already
            // decided) tests a point at the origin: its answer is not read.
            const double none[3] = { 0.0, 0.0, 0.0 };
            const double *p = on ? start[k] : none, *d = on ? dir[k] : none;
            x0[k] = (float)(p[0] + d[0] * t0);
            y0[k] = (float)(p[1] + d[1] * t0);
            z0[k] = (float)(p[2] + d[2] * t0);
            x1[k] = (float)(p[0] + d[0] * t1[k]);
            y1[k] = (float)(p[1] + d[1] * t1[k]);
            z1[k] = (float)(p[2] + d[2] * t1[k]);
        }
        if (pending == 0) {
            return free_lanes;
        }
        uint32_t outside = 0;
        uint32_t clear = wx_collider_coarse_block(collider, cams, collider->camera_count, NULL, x0,
                                                  y0, z0, x1, y1, z1, &outside);
        // (outside is whole when some lane is not cleared: then no camera was skipped)
        for (uint32_t left = pending & ~(clear | outside); left != 0; left &= left - 1) {
            int k = __builtin_ctz(left);
            double a[3], b[3];
            for (int c = 0; c < 3; ++c) {
                a[c] = start[k][c] + dir[k][c] * t0;
                b[c] = start[k][c] + dir[k][c] * t1[k];
            }
            if (!segment_past_coarse(collider, a, b, t1[k] - t0, first)) {
                free_lanes &= ~(1u << k);
            }
        }
        t0 += step;
        step *= 2.0;
    }
}

// Where a ray from surface point p along unit dir starts: on the ray itself
// (so that a shadow's edge does not move), within one of the collider's finest
// texels of p: at a height of 1/8, then 1/4, then 1/2 of that texel above the
// surface (along the ray: the height over max(cos, 1/2)), then a whole texel
// along the ray, the first start the collider's point rule says is free. The
// maps record a surface to about half a texel where a camera sees it edge-on or
// at a silhouette, so a low start may read as inside it and the next one up is
// taken. Starts two texels up (four along grazing rays) skipped a sill's edge
// or the far side of a crease nearer than that and left those texels bright.
// Returns the distance skipped, or -1 when every start lies inside (the ray is
// closed: the point lies within what the maps record as solid).
static double ray_start(const job *jb, const double p[3], const float n[3], const double dir[3],
                        double out[3])
{
    double c = n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2];
    double texel = 8.0 * jb->offset;
    for (int tries = 0; tries < 4; ++tries) {
        double skip = min_of(texel, jb->offset * (double)(1 << tries) / max_of(c, 0.5));
        float f[3];
        for (int k = 0; k < 3; ++k) {
            out[k] = p[k] + dir[k] * skip;
            f[k] = (float)out[k];
        }
        if (jb->def->collider == NULL || !wx_collider_point_collides(jb->def->collider, f)) {
            return skip;
        }
    }
    return -1.0;
}

static float finest_texel(const wx_collider *collider)
{
    float finest = INFINITY;
    for (int c = 0; collider != NULL && c < collider->camera_count; ++c) {
        finest = fminf(finest, collider->cameras[c].texel_ws);
    }
    return finest;
}

typedef struct enclosed_job {
    const wx_collider *collider;
    const double *position;
    const float *normal;
    float *seen;
    int width;
    double offset;
} enclosed_job;

static void enclosed_rows(int64_t begin, int64_t end, int worker, void *context)
{
    (void)worker;
    const enclosed_job *ej = context;
    for (int64_t j = begin; j < end; ++j) {
        for (int i = 0; i < ej->width; ++i) {
            size_t t = (size_t)j * (size_t)ej->width + (size_t)i;
            if (!(ej->seen[t] > 0.5f)) {
                continue;
            }
            const double *p = &ej->position[3 * t];
            const float *n = &ej->normal[3 * t];
            bool inside = true;
            for (int tries = 0; tries < 4 && inside; ++tries) {
                double h = ej->offset * (double)(1 << tries);
                float f[3] = { (float)(p[0] + n[0] * h), (float)(p[1] + n[1] * h),
                               (float)(p[2] + n[2] * h) };
                inside = wx_collider_point_collides(ej->collider, f);
            }
            if (inside) {
                ej->seen[t] = 0.0f;
            }
        }
    }
}

void wx_masks_unsee_enclosed(const wx_collider *collider, const wx_mask_points *points, float *seen,
                             int threads)
{
    bool layered = false;
    for (int c = 0; collider != NULL && c < collider->camera_count; ++c) {
        layered = layered || collider->cameras[c].layers > 1;
    }
    float finest = finest_texel(collider);
    if (!layered || !isfinite(finest)) {
        return;
    }
    enclosed_job ej = { .collider = collider,
                        .position = points->position,
                        .normal = points->normal,
                        .seen = seen,
                        .width = points->width,
                        .offset = finest / 8.0 };
    wx_parallel_for(threads, points->height, 16, enclosed_rows, &ej);
}

// Distance from p along dir to the exit of the solver's bounding box (0 when p
// lies outside it).
static double box_exit(const wx_scene *scene, const double p[3], const double dir[3])
{
    double h = 0.5 * scene->bbox_size, t = INFINITY;
    for (int k = 0; k < 3; ++k) {
        double lo = scene->bbox_center[k] - h, hi = scene->bbox_center[k] + h;
        if (!(p[k] >= lo && p[k] <= hi)) {
            return 0.0;
        }
        if (dir[k] > 0.0) {
            t = fmin(t, (hi - p[k]) / dir[k]);
        } else if (dir[k] < 0.0) {
            t = fmin(t, (lo - p[k]) / dir[k]);
        }
    }
    return isfinite(t) ? t : 0.0;
}

static float accessibility(const job *jb, const wx_mask_def *m, size_t t, const double p[3],
                           const float n[3])
{
    double tx[3], bx[3];
    frame_of(n, tx, bx);
    uint64_t h = splitmix(jb->def->seed ^ splitmix((uint64_t)jb->mask * 0x632be59bd9b4e019ull ^
                                                   (uint64_t)t));
    double r1 = unit_of(h), r2 = unit_of(splitmix(h));
    int open = 0;
    for (int i0 = 0; i0 < m->rays; i0 += RAY_BLOCK) {
        double start[RAY_BLOCK][3], dir[RAY_BLOCK][3], length[RAY_BLOCK];
        uint32_t active = 0;
        for (int k = 0; k < RAY_BLOCK && i0 + k < m->rays; ++k) {
            int i = i0 + k;
            // A stratified point of the unit square, rotated per point, mapped to
            // cosine-weighted directions (Malley's method).
            double u = fmod((i + 0.5) / m->rays + r1, 1.0),
                   v = fmod(radical_inverse((uint32_t)i) + r2, 1.0);
            double r = sqrt(u), phi = 2.0 * PI * v, z = sqrt(max_of(0.0, 1.0 - u));
            for (int c = 0; c < 3; ++c) {
                dir[k][c] = r * cos(phi) * tx[c] + r * sin(phi) * bx[c] + z * n[c];
            }
            double skipped = ray_start(jb, p, n, dir[k], start[k]);
            length[k] = m->distance - skipped;
            open += skipped >= m->distance; // past the distance already: open
            active |= (uint32_t)(skipped >= 0.0 && skipped < m->distance) << k;
        }
        open +=
            __builtin_popcount(rays_free(jb->def->collider, active, start, dir, length, jb->first));
    }
    return (float)open / (float)m->rays;
}

static float exposure(const job *jb, const double p[3], const float n[3])
{
    // The suns' rays side by side (at most 3 of the RAY_BLOCK lanes).
    double start[RAY_BLOCK][3], dir[RAY_BLOCK][3], length[RAY_BLOCK], cosine[RAY_BLOCK];
    uint32_t active = 0;
    for (int s = 0; s < jb->sun_count; ++s) {
        const double *sun = jb->suns[s];
        double c = n[0] * sun[0] + n[1] * sun[1] + n[2] * sun[2];
        if (!(c > 0.0) || jb->sun_weights[s] == 0.0) {
            continue;
        }
        memcpy(dir[s], sun, sizeof dir[s]);
        if (ray_start(jb, p, n, sun, start[s]) < 0.0) {
            continue; // inside what the maps record: no light
        }
        length[s] = box_exit(jb->def->scene, start[s], sun);
        cosine[s] = c;
        active |= 1u << s;
    }
    uint32_t lit = rays_free(jb->def->collider, active, start, dir, length, jb->first);
    double sum = 0.0;
    for (int s = 0; s < jb->sun_count; ++s) {
        if ((lit >> s) & 1u) {
            sum += jb->sun_weights[s] * cosine[s];
        }
    }
    return (float)fmin(1.0, fmax(0.0, sum));
}

// Mean curvature: the least-squares normal curvature over the neighbours
// within the radius, sum (n_q - n_p) . (q - p) / sum |q - p|^2 (a sphere of
// radius R gives 1/R exactly, a plane 0, a cylinder 1/(2R)).
static float curvature(const job *jb, const wx_mask_def *m, int i, int j)
{
    const wx_mask_points *g = &jb->def->points;
    double radius = m->radius > 0.0f ? m->radius : 4.0 * g->texel;
    // Clamped in double before the cast: a radius of 1e30 is the most texels
    // allowed, not an overflow (which made it one texel).
    int reach = (int)fmin((double)CURVATURE_MAX_REACH, fmax(1.0, ceil(radius / g->texel)));
    size_t t = (size_t)j * (size_t)g->width + (size_t)i;
    const double *p = &g->position[3 * t];
    const float *n = &g->normal[3 * t];
    double num = 0.0, den = 0.0, r2max = radius * radius;
    for (int y = j - reach; y <= j + reach; ++y) {
        for (int x = i - reach; x <= i + reach; ++x) {
            if (x < 0 || y < 0 || x >= g->width || y >= g->height || (x == i && y == j)) {
                continue;
            }
            size_t q = (size_t)y * (size_t)g->width + (size_t)x;
            if (!g->valid[q]) {
                continue;
            }
            const double *pq = &g->position[3 * q];
            const float *nq = &g->normal[3 * q];
            double d[3] = { pq[0] - p[0], pq[1] - p[1], pq[2] - p[2] };
            double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            if (!(r2 <= r2max) || !(r2 > 0.0) ||
                !(n[0] * nq[0] + n[1] * nq[1] + n[2] * nq[2] > 0.0f)) {
                continue; // too far, the same point, or the other side of a thin part
            }
            num += (nq[0] - n[0]) * d[0] + (nq[1] - n[1]) * d[1] + (nq[2] - n[2]) * d[2];
            den += r2;
        }
    }
    return den > 0.0 ? (float)(num / den) : 0.0f;
}

static float combine(const job *jb, const wx_mask_def *m, size_t t)
{
    double sum = 0.0;
    for (int k = 0; k < m->term_count; ++k) {
        const wx_term *term = &m->terms[k];
        double x = term->kind == WX_TERM_CONSTANT ? term->constant
                   : term->kind == WX_TERM_AGE    ? term->constant * jb->def->age
                   : term->kind == WX_TERM_MASK   ? jb->out[term->index][t]
                                                  : jb->def->substances[term->index][t];
        sum += term->weight * wx_sigmoid(x, term->offset, term->steepness);
    }
    return (float)fmin(1.0, fmax(0.0, m->scale * sum));
}

// Noise's value at p: its raw value through the scene's remap table, or,
// without one, the raw value mapped from [-1, 1] to [0, 1].
static float noise_value(const job *jb, const wx_mask_def *m, const double p[3])
{
    const double *table = jb->def->noise_tables != NULL ? jb->def->noise_tables[jb->mask] : NULL;
    double raw = wx_noise_raw(m, p);
    return table != NULL ? wx_noise_remap(table, raw)
                         : (float)fmin(1.0, fmax(0.0, 0.5 * raw + 0.5));
}

// Accessibility is computed coarse to fine (wx_masks_compute): the points whose
// i and j are multiples of REFINE_STRIDE first, then those of stride 2 (the
// midpoints of their cells' edges and their centres), then the rest. A point of
// a finer level whose cell of the coarser level has its four corners on the
// same surface near it (valid, within two cell sizes, normals within 25
// degrees) and their values within REFINE_SPREAD of each other takes their
// bilinear interpolation without a ray. On the default house 72-87% of the
// points are open in every direction (1): where four corners 4 texels apart
// send their rays and none meets a surface, or all but a few, the points
// between them are as open. Where the corners differ more (creases, the foot of
// a wall, a reveal, a sill's shadow) every point is computed, so the edges the
// mask is for keep their rays. On the house's run of docs/masks.md ("Against
// Blender's AO bake") 27% of the points are computed, and r and the mean
// difference against Cycles do not move (docs/performance.md, issue 26).
#define REFINE_STRIDE 4
#define REFINE_SPREAD 0.0625f // 4 rays of 64

static int level_of(int i, int j)
{
    int s = REFINE_STRIDE;
    while (s > 1 && ((i % s) != 0 || (j % s) != 0)) {
        s /= 2;
    }
    return s;
}

// Whether point (i, j) of a finer level than the grid of `cell` texels can take
// the bilinear interpolation of its cell's four corners, already computed (*value).
static bool settled(const wx_mask_points *g, const float *out, int i, int j, int cell, float *value)
{
    int i0 = i - i % cell, j0 = j - j % cell;
    if (i0 + cell >= g->width || j0 + cell >= g->height) {
        return false;
    }
    size_t t = (size_t)j * (size_t)g->width + (size_t)i;
    const double *p = &g->position[3 * t];
    const float *n = &g->normal[3 * t];
    double reach = 2.0 * cell * (double)g->texel;
    float v[4], lo = INFINITY, hi = -INFINITY;
    for (int c = 0; c < 4; ++c) {
        size_t q =
            (size_t)(j0 + (c >> 1) * cell) * (size_t)g->width + (size_t)(i0 + (c & 1) * cell);
        if (!g->valid[q]) {
            return false;
        }
        const double *pq = &g->position[3 * q];
        const float *nq = &g->normal[3 * q];
        double d[3] = { pq[0] - p[0], pq[1] - p[1], pq[2] - p[2] };
        if (!(d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= reach * reach) ||
            !(n[0] * nq[0] + n[1] * nq[1] + n[2] * nq[2] >= 0.9f)) {
            return false;
        }
        v[c] = out[q];
        lo = fminf(lo, v[c]);
        hi = fmaxf(hi, v[c]);
    }
    if (!(hi - lo <= REFINE_SPREAD)) {
        return false;
    }
    float fx = (float)(i - i0) / (float)cell, fy = (float)(j - j0) / (float)cell;
    *value = lo == hi ? lo
                      : (v[0] * (1.0f - fx) + v[1] * fx) * (1.0f - fy) +
                            (v[2] * (1.0f - fx) + v[3] * fx) * fy;
    return true;
}

static void mask_rows(int64_t begin, int64_t end, int worker, void *context)
{
    const job *jb = context;
    const wx_masks_def *def = jb->def;
    const wx_mask_def *m = &def->scene->masks[jb->mask];
    const wx_mask_points *g = &def->points;
    float *out = jb->out[jb->mask];
    double lo = m->has_min ? m->min : def->height_min, hi = m->has_max ? m->max : def->height_max;
    for (int64_t j = begin; j < end; ++j) {
        for (int i = 0; i < g->width; ++i) {
            size_t t = (size_t)j * (size_t)g->width + (size_t)i;
            if (!g->valid[t]) {
                out[t] = 0.0f;
                continue;
            }
            const double *p = &g->position[3 * t];
            const float *n = &g->normal[3 * t];
            switch (m->kind) {
            case WX_MASK_ACCESSIBILITY: {
                int level = level_of(i, (int)j);
                if (level != jb->stride) {
                    break; // another pass's point
                }
                float value;
                if (level == REFINE_STRIDE || !settled(g, out, i, (int)j, 2 * level, &value)) {
                    value = accessibility(jb, m, t, p, n);
                }
                out[t] = value;
                break;
            }
            case WX_MASK_EXPOSURE:
                out[t] = exposure(jb, p, n);
                break;
            case WX_MASK_CURVATURE:
                out[t] = curvature(jb, m, i, (int)j);
                break;
            case WX_MASK_HEIGHT:
                out[t] = hi > lo ? (float)fmin(1.0, fmax(0.0, (p[1] - lo) / (hi - lo))) : 0.0f;
                break;
            case WX_MASK_COMBINE:
                out[t] = combine(jb, m, t);
                break;
            case WX_MASK_NOISE:
                out[t] = noise_value(jb, m, p);
                break;
            }
        }
        if (worker == 0 && jb->stride == 1) {
            wx_progress_update(jb->progress, (int64_t)jb->mask * g->height + j + 1);
        }
    }
}

wx_result wx_masks_compute(const wx_masks_def *def, float *const *out, wx_error *err)
{
    (void)err;
    const wx_scene *scene = def->scene;
    job jb;
    memset(&jb, 0, sizeof jb);
    jb.def = def;
    jb.out = out;
    // Rays start within one of the collider's finest texels of the surface
    // (ray_start: an eighth of it up first); their first segment is four of
    // its coarsest texels (the target's, when they are coarser) long.
    float texel = def->points.texel, finest = finest_texel(def->collider);
    for (int c = 0; def->collider != NULL && c < def->collider->camera_count; ++c) {
        texel = fmaxf(texel, def->collider->cameras[c].texel_ws);
    }
    jb.offset = (isfinite(finest) ? finest : def->points.texel) / 8.0f;
    jb.first = 4.0 * texel;
    wx_progress progress;
    wx_progress_begin(&progress, "masks", (int64_t)scene->mask_count * def->points.height,
                      def->quiet);
    jb.progress = &progress;
    const wx_mask_points *g = &def->points;
    for (int m = 0; m < scene->mask_count; ++m) {
        const wx_mask_def *md = &scene->masks[m];
        jb.mask = m;
        if (def->known != NULL && def->known[m] != NULL) {
            memcpy(out[m], def->known[m], (size_t)g->width * (size_t)g->height * sizeof *out[m]);
            wx_progress_update(&progress, (int64_t)(m + 1) * g->height);
            continue;
        }
        if (md->kind == WX_MASK_EXPOSURE) {
            // The main sun, and the two side suns at azimuth +- spread.
            wx_sun_direction(md->elevation, md->azimuth, jb.suns[0]);
            jb.sun_weights[0] = 1.0;
            jb.sun_count = 1;
            if (md->side_weight != 0.0f) {
                double e = (double)md->side_elevation * md->elevation;
                wx_sun_direction(e, (double)md->azimuth + md->side_spread, jb.suns[1]);
                wx_sun_direction(e, (double)md->azimuth - md->side_spread, jb.suns[2]);
                jb.sun_weights[1] = jb.sun_weights[2] = md->side_weight;
                jb.sun_count = 3;
            }
        }
        // Rays cost far more than the rest: rows in small work items.
        // Accessibility coarse to fine (REFINE_STRIDE), the rest in one pass.
        jb.stride = md->kind == WX_MASK_ACCESSIBILITY ? REFINE_STRIDE : 1;
        for (; jb.stride >= 1; jb.stride /= 2) {
            wx_parallel_for(def->threads, g->height, wx_mask_rays(md) > 0 ? 1 : 16, mask_rows, &jb);
        }
    }
    wx_progress_end(&progress);
    return WX_OK;
}

bool wx_mask_is_geometric(const wx_scene *scene, int m)
{
    const wx_mask_def *md = &scene->masks[m];
    if (md->kind != WX_MASK_COMBINE) {
        return true;
    }
    for (int k = 0; k < md->term_count; ++k) {
        const wx_term *term = &md->terms[k];
        if (term->kind == WX_TERM_SUBSTANCE || term->kind == WX_TERM_AGE ||
            (term->kind == WX_TERM_MASK && !wx_mask_is_geometric(scene, term->index))) {
            return false;
        }
    }
    return true;
}
