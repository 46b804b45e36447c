// adaptive.c: the gather's adaptive smoothing (adaptive.h, docs/mask.md).
//
// Four steps over the target's texels:
//   1. per texel: the impacts its surface patch holds (hits per unit area times
//      the area the texel covers) and the change delta = total - initial; two
//      summed-area tables, of the impacts and of the texels with a surface;
//   2. per texel (rows on the pool): its radius h by bisection on the impacts
//      within h (the rectangle around the texel scaled to the disc), and
//      whether it lies in a clean region (no impact of its own, and an empty
//      half-disc beside it where its density would put CLEAN_EXPECTED);
//   3. the samples' weights 1 / h^2 and the bounds of the radii per tile;
//   4. per texel q (rows on the pool): the weighted mean of delta over the
//      samples p that reach it with no clean texel on the way, added to the
//      initial dirt.
// Step 4 runs over padded planes in chunks of CHUNK texels of a row, one
// neighbour offset at a time (offsets sorted by distance across the view,
// stopping at the largest radius that can reach the chunk), in a loop the
// compiler vectorises.
#include "gather/adaptive.h"
#include "core/big_alloc.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "model/maps.h"

enum {
    LINE_CELLS_MAX = 1 << 20, // the most texels of the offsets' lines kept (4 MiB)
    CHUNK = 64,               // texels of a row processed together
    TILE = 16,                // texels a side of the tiles that bound the radii
    BISECTIONS = 24,
};

// Normals at right angles weigh 0 even a few ulps off (as in gather.c).
#define NORMAL_EPSILON 1e-6f
// A sample weighs its normal's agreement with the texel's to this power (a
// power of two: kernel_weight squares it there). What falls on a surface
// depends on which way the surface faces, so a sample on a face turned 24
// degrees away has half the weight and one turned 42 degrees a tenth: a
// lit face's density no longer runs a centimetre across a crease onto the
// sheltered face below (docs/mask.md, "The estimate").
#define NORMAL_POWER 8
// |N.view| is clamped to this when the area a texel covers is computed (the
// gather's WX_GATHER_AREA_MIN_COS).
#define AREA_MIN_COS 1e-3f
// The tangent-plane test: q lies on p's plane within PLANE_TOL_TEXELS texels
// plus PLANE_TOL_SLOPE times their distance (a curved surface leaves its
// tangent plane by r^2 / 2R, well inside this for R above a few radii).
#define PLANE_TOL_TEXELS 1.5f
#define PLANE_TOL_SLOPE 0.25f
// Slopes steeper than this (|N.view|) count as this one when a radius is chosen.
#define MIN_SLOPE_COS 0.1f
// A texel is clean (in a shadow, say) when it holds no impact and a
// half-disc beside it holds none either although the texel's density would
// put CLEAN_EXPECTED impacts there: the chance that this happens in a
// uniformly hit region is e^-12 per direction, 6e-6.
#define CLEAN_EXPECTED 12.0
// Fewer impacts than this leave a texel or a rectangle empty (the first pass
// spreads an impact bilinearly over up to four texels).
#define EMPTY_IMPACTS 0.5

// The clean test's half-discs: the disc around a texel is cut into SECTORS
// sectors by the angle of each neighbour's centre. A half-disc facing sector
// m holds the impacts of the SECTORS / 2 + 2 sectors from m (half the disc and
// one sector beyond each end of its straight side, so that the texels along
// that side count for both halves), and its surface is that of the SECTORS / 2
// - 2 sectors inside it (the texels along the straight side, the texel's own
// line, never make a clean region on their own: see is_clean).
enum { SECTORS = 64, IMPACT_SECTORS = SECTORS / 2 + 2, SURFACE_SECTORS = SECTORS / 2 - 2 };

// A neighbour of the clean test: its offset, distance and sector.
typedef struct disc_offset {
    int di, dj;
    float r;
    int sector;
} disc_offset;

// Step 2's verdict on a texel (job.clean): clean, and, for a texel whose
// radius reached max_radius, whether some impact lies within it (a surface no
// particle comes near is not noisy, only unreached).
enum { TEXEL_CLEAN = 1, TEXEL_SPARSE = 2 };

// A neighbour (di, dj): its distance across the view, its world offset
// a = di*step_i + dj*step_j (with a depth difference dd the points are
// a + dd*step_d apart: r^2 = a2 + dd * (az2 + dd * z2)), and the plane
// tolerance at that distance.
typedef struct offset {
    int di, dj;
    // Its line (line_blocked), when job.line holds the lines: line_count
    // texels from line_first on, each as (x, y), the texel q - (x, y).
    int line_first, line_count;
    float r;
    float ax, ay, az;
    float a2, az2;
    float tol;
} offset;

typedef struct job {
    const wx_adaptive_def *def;
    int width, height;
    size_t stride, base; // padded planes: texel (i, j) at base + j*stride + i
    // Padded planes. Margins, texels without a surface and clean texels have
    // normal 0: they neither give nor take.
    float *pd, *pnx, *pny, *pnz, *pzn; // depth, unit normal, step_d . N
    float *pinvh;                      // 1 / h of a sample, 0 elsewhere
    float *pweight;                    // 1 / h^2 of a sample, 0 elsewhere
    float *pcoef;                      // pweight * delta
    int16_t *line;        // the offsets' lines (pairs), or NULL: walked each time
    uint64_t *clean_bits; // the clean texels that stop kernels, a bit per padded texel
    uint64_t spread[256]; // a byte's 8 bits as 8 bytes of 0 or 1
    // Unpadded.
    float *delta;         // change per unit area
    float *radius;        // h (world units) of a sample, 0 elsewhere
    unsigned char *clean; // step 2's verdict: TEXEL_CLEAN, TEXEL_SPARSE bits
    float *impacts;       // the impacts of each texel (step 1's hits times area)
    const disc_offset *disc; // the clean test's neighbours, by distance
    int disc_count;
    int *half_disc;       // [k]: surface texels of a half-disc of radius k, all surface
    int k_max;            // the largest radius of a half-disc, texels
    double *sat;          // (width + 1) * (height + 1) summed impacts; in step 4,
                          // the samples with a change (pcoef != 0)
    double *sat_surface;  // the same for the texels with a surface; in step 4,
                          // the clean texels that stop kernels (clean_bits)
    float *tile_bound;
    int tiles_x, tiles_y;
    const offset *offsets;
    int offset_count;
    int *reach_i, *reach_j; // the largest |di|, |dj| of offsets[0 .. o]
    double target_hits;
    float texel_i, texel_j; // |step_i|, |step_j| across the view
    float z2;               // |step_d|^2
    float inv_z;            // 1 / |step_d|
    float min_radius, max_radius;
    float *out;
    int pass; // 2: radii, 4: gather
} job;

// v, or 0 when c is negative (sign bit set): a select without a comparison, so
// that the loop vectorises under the default -ftrapping-math (as in gather.c).
static inline float keep_if_positive(float v, float c)
{
    uint32_t vb, cb;
    memcpy(&vb, &v, sizeof vb);
    memcpy(&cb, &c, sizeof cb);
    vb &= ~(uint32_t)((int32_t)cb >> 31);
    memcpy(&v, &vb, sizeof v);
    return v;
}

// Sum of table `s` over the inclusive texel rectangle, clipped to the map.
static double rect_sum(const job *jb, const double *s, int i0, int j0, int i1, int j1)
{
    i0 = i0 < 0 ? 0 : i0;
    j0 = j0 < 0 ? 0 : j0;
    i1 = i1 >= jb->width ? jb->width - 1 : i1;
    j1 = j1 >= jb->height ? jb->height - 1 : j1;
    if (i0 > i1 || j0 > j1) {
        return 0.0;
    }
    size_t w = (size_t)jb->width + 1;
    return s[(size_t)(j1 + 1) * w + (size_t)(i1 + 1)] - s[(size_t)j0 * w + (size_t)(i1 + 1)] -
           s[(size_t)(j1 + 1) * w + (size_t)i0] + s[(size_t)j0 * w + (size_t)i0];
}

// Impacts within h of texel (i, j): those of the rectangle of half-sides
// floor(h / texel) around it, scaled by the disc's area over the rectangle's
// (near the map's border both are clipped alike).
static double impacts_within(const job *jb, int i, int j, double h)
{
    int kx = (int)(h / jb->texel_i), ky = (int)(h / jb->texel_j);
    double disc = 3.14159265358979323846 * (h / jb->texel_i) * (h / jb->texel_j);
    double full = (double)(2 * kx + 1) * (double)(2 * ky + 1);
    return rect_sum(jb, jb->sat, i - kx, j - ky, i + kx, j + ky) * (disc / full);
}

// The impacts the disc of the texel at padded index p must hold: K' = K /
// |N.view| (at least MIN_SLOPE_COS), the disc being taken across the view.
static double impacts_wanted(const job *jb, size_t p)
{
    float cos_view = fabsf(jb->pzn[p]) * jb->inv_z;
    return jb->target_hits / (cos_view > MIN_SLOPE_COS ? cos_view : MIN_SLOPE_COS);
}

// Whether texel (i, j), holding no impact of its own, lies in a clean region:
// some half-disc around it, of radius k to k_max, holds no impact (under half
// of one) and enough surface that `density` (impacts per texel) would have put
// CLEAN_EXPECTED there. Half-discs in SECTORS directions: a straight shadow
// edge at any angle to the grid has one facing away from it to within half a
// sector, so the clean region reaches the edge whichever way the grid lies
// (the half-rectangles of four sides used until 6 December 2026 fitted a
// slanted edge only some way from it, up to 0.7 times their reach, and turning
// the model moved the edge of every clean region: docs/performance.md). The
// surface of the texels along the straight side does not count: a
// silhouette's last row, with nothing beyond it, is no evidence of a clean
// region however long it runs empty (and the texture drew a dark line two
// texels wide along the model's edge that turning the model took away).
static bool is_clean(const job *jb, int i, int j, double density, int k)
{
    const int W = jb->width, H = jb->height;
    // Nothing in the square around the texel, all of it surface: every
    // half-disc is empty and whole.
    if (i - k >= 0 && j - k >= 0 && i + k < W && j + k < H &&
        rect_sum(jb, jb->sat, i - k, j - k, i + k, j + k) < EMPTY_IMPACTS &&
        rect_sum(jb, jb->sat_surface, i - k, j - k, i + k, j + k) >=
            (double)(2 * k + 1) * (double)(2 * k + 1)) {
        return density * jb->half_disc[k] >= CLEAN_EXPECTED;
    }
    if (!(density * jb->half_disc[jb->k_max] >= CLEAN_EXPECTED)) {
        return false; // not even the largest half-disc would expect enough
    }
    double impacts[SECTORS] = { 0.0 }, surface[SECTORS] = { 0.0 };
    const double wanted = CLEAN_EXPECTED / density;
    for (int r = 1, o = 0; r <= jb->k_max; ++r) {
        for (; o < jb->disc_count && jb->disc[o].r <= (float)r + 0.5f; ++o) {
            int x = i + jb->disc[o].di, y = j + jb->disc[o].dj;
            if (x < 0 || y < 0 || x >= W || y >= H) {
                continue;
            }
            size_t t = (size_t)y * (size_t)W + (size_t)x;
            if (!wx_depth_is_empty(jb->def->depth[t])) {
                impacts[jb->disc[o].sector] += jb->impacts[t];
                surface[jb->disc[o].sector] += 1.0;
            }
        }
        if (r < k) {
            continue;
        }
        // Running sums twice round: sectors m to m + n - 1 hold run[m + n] -
        // run[m].
        double run_impacts[2 * SECTORS + 1], run_surface[2 * SECTORS + 1];
        run_impacts[0] = run_surface[0] = 0.0;
        for (int m = 0; m < 2 * SECTORS; ++m) {
            run_impacts[m + 1] = run_impacts[m] + impacts[m % SECTORS];
            run_surface[m + 1] = run_surface[m] + surface[m % SECTORS];
        }
        bool empty_one = false;
        for (int m = 0; m < SECTORS; ++m) {
            if (run_impacts[m + IMPACT_SECTORS] - run_impacts[m] < EMPTY_IMPACTS) {
                empty_one = true;
                if (run_surface[m + 2 + SURFACE_SECTORS] - run_surface[m + 2] >= wanted) {
                    return true;
                }
            }
        }
        if (!empty_one) {
            return false; // every half-disc holds an impact, and so do larger ones
        }
    }
    return false;
}

// Step 2 for row j: the radius of every texel with a surface, and whether it
// is clean. The kernel's disc of radius h on the surface covers |N.view| of
// the image-plane disc's texels: the image-plane disc must hold K / |N.view|
// impacts (|N.view| at least MIN_SLOPE_COS).
static void radii_row(const job *jb, int j)
{
    const int k_max = jb->k_max;
    for (int i = 0; i < jb->width; ++i) {
        size_t t = (size_t)j * (size_t)jb->width + (size_t)i;
        size_t p = jb->base + (size_t)j * jb->stride + (size_t)i;
        jb->radius[t] = 0.0f;
        jb->clean[t] = 0;
        if (wx_depth_is_empty(jb->def->depth[t])) {
            continue;
        }
        double want = impacts_wanted(jb, p);
        double lo = jb->min_radius, hi = jb->max_radius;
        double h, at_max;
        unsigned char sparse = 0;
        if (impacts_within(jb, i, j, lo) >= want) {
            h = lo;
        } else if ((at_max = impacts_within(jb, i, j, hi)) < want) {
            h = hi;
            sparse = at_max >= EMPTY_IMPACTS ? TEXEL_SPARSE : 0;
        } else {
            for (int k = 0; k < BISECTIONS; ++k) {
                double mid = 0.5 * (lo + hi);
                if (impacts_within(jb, i, j, mid) >= want) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            h = hi;
        }
        jb->radius[t] = (float)h;
        double own = rect_sum(jb, jb->sat, i, j, i, j);
        if (own < EMPTY_IMPACTS) {
            double texels = 3.14159265358979323846 * (h / jb->texel_i) * (h / jb->texel_j);
            double density = impacts_within(jb, i, j, h) / texels;
            // The half-disc reaches at least half the texel's radius (so that
            // the sparse fringe of a dense region, where empty pockets are
            // small next to the radius, is not cut out of the mask), and as
            // far as a whole one must to expect CLEAN_EXPECTED impacts.
            int k = (int)ceil(0.5 * h / fmax(jb->texel_i, jb->texel_j));
            k = k < 1 ? 1 : k;
            while (k < k_max && density * jb->half_disc[k] < CLEAN_EXPECTED) {
                ++k;
            }
            jb->clean[t] = is_clean(jb, i, j, density, k) ? TEXEL_CLEAN : 0;
        }
        jb->clean[t] |= sparse;
    }
}

// The largest sample radius that can reach texels of row j, columns [x0, x1).
static float chunk_bound(const job *jb, int j, int x0, int x1)
{
    int ty = j / TILE, tx0 = x0 / TILE, tx1 = (x1 - 1) / TILE;
    float bound = 0.0f;
    for (int tx = tx0; tx <= tx1; ++tx) {
        float b = jb->tile_bound[(size_t)ty * (size_t)jb->tiles_x + (size_t)tx];
        bound = b > bound ? b : bound;
    }
    return bound;
}

// The weight sample p's kernel gives texel q at offset `off` from p.
static inline float kernel_weight(const offset *off, float z2, float dq, float nxq, float nyq,
                                  float nzq, float dp, float nxp, float nyp, float nzp, float znp,
                                  float ihp)
{
    float dd = dq - dp;
    float r2 = off->a2 + dd * (off->az2 + dd * z2);
    float cone = 1.0f - sqrtf(keep_if_positive(r2, r2)) * ihp;
    float agree = nxp * nxq + nyp * nyq + nzp * nzq;
    float power = agree;
    for (int k = 1; k < NORMAL_POWER; k *= 2) {
        power *= power;
    }
    float plane = off->ax * nxp + off->ay * nyp + off->az * nzp + dd * znp;
    float w = keep_if_positive(keep_if_positive(cone * power, cone), agree - NORMAL_EPSILON);
    return keep_if_positive(w, off->tol - fabsf(plane));
}

// The clean bits of the 64 padded texels from padded index `at` on (bit x:
// texel at + x).
static inline uint64_t clean_run(const job *jb, size_t at)
{
    const uint64_t *w = jb->clean_bits + at / 64;
    unsigned shift = (unsigned)(at % 64);
    return shift == 0 ? w[0] : (w[0] >> shift) | (w[1] << (64 - shift));
}

// The texels strictly between q and its sample q - (di, dj) that the segment
// between their centres passes through, from q on; where it passes exactly
// through a corner, the two texels beside the corner too, so that it cannot
// slip between the corners of a band one texel thin. Each as (x, y), the
// texel q - (x, y), into cells when not NULL; returns their number.
static int line_cells(int di, int dj, int16_t *cells)
{
    const int si = di > 0 ? 1 : -1, sj = dj > 0 ? 1 : -1;
    const long ni = labs((long)di), nj = labs((long)dj);
    int n = 0, x = 0, y = 0;
    for (long ki = 0, kj = 0; ki < ni || kj < nj;) {
        // The next border the segment crosses: i's at (ki + 1/2) / ni of
        // the way, j's at (kj + 1/2) / nj.
        long next = (1 + 2 * ki) * nj - (1 + 2 * kj) * ni;
        if (next == 0) {
            if (cells != NULL) {
                cells[2 * n] = (int16_t)(x + si);
                cells[2 * n + 1] = (int16_t)y;
                cells[2 * n + 2] = (int16_t)x;
                cells[2 * n + 3] = (int16_t)(y + sj);
            }
            n += 2;
            x += si;
            y += sj;
            ++ki;
            ++kj;
        } else if (next < 0) {
            x += si;
            ++ki;
        } else {
            y += sj;
            ++kj;
        }
        if (x != di || y != dj) {
            if (cells != NULL) {
                cells[2 * n] = (int16_t)x;
                cells[2 * n + 1] = (int16_t)y;
            }
            ++n;
        }
    }
    return n;
}

// For the 64 texels from padded index q on, bit x: whether a clean texel lies
// on the line (line_cells) between q + x and its sample at offset `off`.
static uint64_t line_blocked(const job *jb, size_t q, const offset *off)
{
    int16_t walked[2 * 1024], *heap = NULL;
    const int16_t *cells = jb->line != NULL ? jb->line + 2 * (size_t)off->line_first : walked;
    const int n = off->line_count;
    if (jb->line == NULL) {
        int16_t *own = walked;
        if (n > 1024) { // lines of hundreds of texels: slow anyway
            own = heap = malloc(2 * (size_t)n * sizeof *heap);
            if (heap == NULL) {
                return 0; // out of memory: the kernel as it was before the clip
            }
        }
        line_cells(off->di, off->dj, own);
        cells = own;
    }
    uint64_t bits = 0;
    for (int k = 0; k < n && bits != ~(uint64_t)0; ++k) {
        bits |= clean_run(jb, (size_t)((ptrdiff_t)q -
                                       (ptrdiff_t)cells[2 * k + 1] * (ptrdiff_t)jb->stride -
                                       cells[2 * k]));
    }
    free(heap);
    return bits;
}

// Step 4 for a chunk of texels q: the initial dirt plus the weighted mean of
// the change over the samples that reach it. A kernel does not reach past a
// clean texel on its way: where a clean texel lies within reach, each
// offset's line of texels (line_cells) is read from the clean bits for the
// chunk's 64 texels at once, and a sample whose line from q crosses a clean
// texel gives nothing (docs/mask.md, "Kernels stop at a clean band").
static void gather_chunk(const job *jb, int j, int x0)
{
    const int x1 = x0 + CHUNK < jb->width ? x0 + CHUNK : jb->width;
    // A chunk with no surface is 0 (the deeper layers of a layered camera are
    // mostly empty: docs/design.md section 14).
    const float *row_depth = jb->def->depth + (size_t)j * (size_t)jb->width;
    bool any = false;
    for (int x = x0; x < x1 && !any; ++x) {
        any = !wx_depth_is_empty(row_depth[x]);
    }
    if (!any) {
        for (int x = x0; x < x1; ++x) {
            jb->out[(size_t)j * (size_t)jb->width + (size_t)x] = 0.0f;
        }
        return;
    }
    const float bound = chunk_bound(jb, j, x0, x1);
    // A chunk no sample with a change can reach keeps its initial dirt: the
    // sum below would add w * 0 over every offset (the sheltered walls and the
    // deeper layers, where every radius is the largest: most of the work).
    int reach = 0;
    for (int lo = 0, hi = jb->offset_count; lo < hi;) {
        int mid = lo + (hi - lo) / 2; // reach: the offsets with r < bound
        if (jb->offsets[mid].r < bound) {
            lo = reach = mid + 1;
        } else {
            hi = mid;
        }
    }
    if (reach == 0 || rect_sum(jb, jb->sat, x0 - jb->reach_i[reach - 1], j - jb->reach_j[reach - 1],
                               x1 - 1 + jb->reach_i[reach - 1], j + jb->reach_j[reach - 1]) < 0.5) {
        for (int x = x0; x < x1; ++x) {
            size_t t = (size_t)j * (size_t)jb->width + (size_t)x;
            jb->out[t] = wx_depth_is_empty(row_depth[x]) ? 0.0f : jb->def->initial[t] + 0.0f;
        }
        return;
    }
    const size_t q = jb->base + (size_t)j * jb->stride + (size_t)x0;
    // As for the samples with a change above: whether a clean texel that stops
    // kernels lies within reach.
    const bool clean =
        rect_sum(jb, jb->sat_surface, x0 - jb->reach_i[reach - 1], j - jb->reach_j[reach - 1],
                 x1 - 1 + jb->reach_i[reach - 1], j + jb->reach_j[reach - 1]) >= 0.5;
    float num[CHUNK], den[CHUNK];
    for (int x = 0; x < CHUNK; ++x) {
        num[x] = 0.0f;
        den[x] = 0.0f;
    }
    const float z2 = jb->z2;
    const float *restrict dq = jb->pd + q, *restrict nxq = jb->pnx + q;
    const float *restrict nyq = jb->pny + q, *restrict nzq = jb->pnz + q;
    for (int o = 0; o < reach; ++o) {
        const offset off = jb->offsets[o];
        // The sample is p = q - (di, dj); the offset from p to q is (di, dj).
        const size_t p = (size_t)((ptrdiff_t)q - (ptrdiff_t)off.dj * (ptrdiff_t)jb->stride - off.di);
        const float *restrict dp = jb->pd + p, *restrict nxp = jb->pnx + p;
        const float *restrict nyp = jb->pny + p, *restrict nzp = jb->pnz + p;
        const float *restrict znp = jb->pzn + p, *restrict ihp = jb->pinvh + p;
        const float *restrict cp = jb->pcoef + p, *restrict vp = jb->pweight + p;
        // Bit x: a clean texel lies strictly between q + x and its sample.
        const uint64_t bits = clean ? line_blocked(jb, q, &off) : 0;
        if (bits == ~(uint64_t)0) {
            continue; // every weight 0: the sums stay as they are
        }
        if (bits == 0) {
            for (int x = 0; x < CHUNK; ++x) {
                float w = kernel_weight(&off, z2, dq[x], nxq[x], nyq[x], nzq[x], dp[x], nxp[x],
                                        nyp[x], nzp[x], znp[x], ihp[x]);
                num[x] += w * cp[x];
                den[x] += w * vp[x];
            }
            continue;
        }
        unsigned char b[CHUNK];
        for (int k = 0; k < CHUNK / 8; ++k) {
            memcpy(b + 8 * k, &jb->spread[(bits >> (8 * k)) & 0xff], 8);
        }
        for (int x = 0; x < CHUNK; ++x) {
            float w = kernel_weight(&off, z2, dq[x], nxq[x], nyq[x], nzq[x], dp[x], nxp[x], nyp[x],
                                    nzp[x], znp[x], ihp[x]);
            w = keep_if_positive(w, 0.5f - (float)b[x]);
            num[x] += w * cp[x];
            den[x] += w * vp[x];
        }
    }
    const wx_adaptive_def *def = jb->def;
    for (int x = x0; x < x1; ++x) {
        size_t t = (size_t)j * (size_t)jb->width + (size_t)x;
        float change = den[x - x0] > 0.0f ? num[x - x0] / den[x - x0] : 0.0f;
        jb->out[t] = wx_depth_is_empty(def->depth[t]) ? 0.0f : def->initial[t] + change;
    }
}

static void run_rows(int64_t begin, int64_t end, int worker, void *context)
{
    (void)worker;
    const job *jb = context;
    for (int64_t j = begin; j < end; ++j) {
        if (jb->pass == 2) {
            radii_row(jb, (int)j);
            continue;
        }
        for (int x0 = 0; x0 < jb->width; x0 += CHUNK) {
            gather_chunk(jb, (int)j, x0);
        }
    }
}

// The order of both neighbour tables: by distance, then row, then column (a
// fixed order, so ties between equal distances never depend on qsort).
static int compare_by_distance(float ra, int dja, int dia, float rb, int djb, int dib)
{
    if (ra != rb) {
        return ra < rb ? -1 : 1;
    }
    if (dja != djb) {
        return dja < djb ? -1 : 1;
    }
    return dia < dib ? -1 : dia > dib;
}

static int compare_offsets(const void *a, const void *b)
{
    const offset *x = a, *y = b;
    return compare_by_distance(x->r, x->dj, x->di, y->r, y->dj, y->di);
}

static int compare_floats(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return x < y ? -1 : x > y;
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// The neighbour offsets within max_r across the view, sorted by distance.
static int build_offsets(const wx_adaptive_def *def, const double px[3], const double py[3],
                         const double z[3], int span_i, int span_j, double max_r, double texel,
                         offset *out)
{
    int count = 0;
    for (int dj = -span_j; dj <= span_j; ++dj) {
        for (int di = -span_i; di <= span_i; ++di) {
            double d[3];
            for (int k = 0; k < 3; ++k) {
                d[k] = di * px[k] + dj * py[k];
            }
            double rr = sqrt(dot3(d, d));
            if (!(rr < max_r)) {
                continue;
            }
            offset *o = &out[count++];
            double a[3];
            for (int k = 0; k < 3; ++k) {
                a[k] = di * def->step_i[k] + dj * def->step_j[k];
            }
            o->di = di;
            o->dj = dj;
            o->r = (float)rr;
            o->ax = (float)a[0];
            o->ay = (float)a[1];
            o->az = (float)a[2];
            o->a2 = (float)dot3(a, a);
            o->az2 = (float)(2.0 * dot3(a, z));
            o->tol = (float)(PLANE_TOL_TEXELS * texel + PLANE_TOL_SLOPE * rr);
        }
    }
    qsort(out, (size_t)count, sizeof *out, compare_offsets);
    return count;
}

static int compare_disc_offsets(const void *a, const void *b)
{
    const disc_offset *x = a, *y = b;
    return compare_by_distance(x->r, x->dj, x->di, y->r, y->dj, y->di);
}

// The clean test's neighbours within k_max + 1/2 texels, by distance, each
// with its sector, and half_disc[k] for k = 0 .. k_max: the most surface texels
// a half-disc of radius k counts where every texel has a surface.
static int build_disc(int k_max, disc_offset *out, int *half_disc)
{
    const double pi = 3.14159265358979323846;
    int count = 0;
    for (int dj = -k_max; dj <= k_max; ++dj) {
        for (int di = -k_max; di <= k_max; ++di) {
            float r = sqrtf((float)(di * di + dj * dj));
            if ((di == 0 && dj == 0) || r > (float)k_max + 0.5f) {
                continue;
            }
            int sector = (int)floor((atan2((double)dj, (double)di) + pi) / (2.0 * pi) * SECTORS);
            out[count++] = (disc_offset){ di, dj, r, sector < SECTORS ? sector : SECTORS - 1 };
        }
    }
    qsort(out, (size_t)count, sizeof *out, compare_disc_offsets);
    int per_sector[SECTORS] = { 0 };
    for (int k = 0, o = 0; k <= k_max; ++k) {
        for (; o < count && out[o].r <= (float)k + 0.5f; ++o) {
            per_sector[out[o].sector]++;
        }
        int best = 0;
        for (int m = 0; m < SECTORS; ++m) {
            int n = 0;
            for (int q = 0; q < SURFACE_SECTORS; ++q) {
                n += per_sector[(m + 2 + q) % SECTORS];
            }
            best = n > best ? n : best;
        }
        half_disc[k] = best;
    }
    return count;
}

// A tile's bound: the largest radius of the samples of the tiles that can
// reach it.
static void bound_tiles(job *jb, const float *tile_max)
{
    for (int ty = 0; ty < jb->tiles_y; ++ty) {
        for (int tx = 0; tx < jb->tiles_x; ++tx) {
            float m = tile_max[(size_t)ty * (size_t)jb->tiles_x + (size_t)tx];
            if (m <= 0.0f) {
                continue;
            }
            int rx = (int)ceilf(m / jb->texel_i / TILE) + 1;
            int ry = (int)ceilf(m / jb->texel_j / TILE) + 1;
            for (int y = ty - ry; y <= ty + ry; ++y) {
                for (int x = tx - rx; x <= tx + rx; ++x) {
                    if (x >= 0 && y >= 0 && x < jb->tiles_x && y < jb->tiles_y) {
                        float *b = &jb->tile_bound[(size_t)y * (size_t)jb->tiles_x + (size_t)x];
                        *b = m > *b ? m : *b;
                    }
                }
            }
        }
    }
}

int wx_noise_bin(double noise)
{
    if (!(noise > WX_NOISE_BIN_LOW)) {
        return 0;
    }
    double b = floor(WX_NOISE_BINS_PER_OCTAVE * log2(noise / WX_NOISE_BIN_LOW));
    return b < WX_NOISE_BINS - 1 ? (int)b : WX_NOISE_BINS - 1;
}

double wx_noise_bins_median(const int64_t bins[WX_NOISE_BINS])
{
    int64_t count = 0;
    for (int b = 0; b < WX_NOISE_BINS; ++b) {
        count += bins[b];
    }
    // The element sorted to count / 2, as the exact median takes it.
    int64_t below = 0;
    for (int b = 0; b < WX_NOISE_BINS && count > 0; ++b) {
        if (below + bins[b] > count / 2) {
            return WX_NOISE_BIN_LOW * exp2((b + 0.5) / WX_NOISE_BINS_PER_OCTAVE);
        }
        below += bins[b];
    }
    return 0.0;
}

wx_result wx_adaptive_smooth(const wx_adaptive_def *def, float *out, wx_adaptive_stats *stats,
                             wx_error *err)
{
    const int W = def->width, H = def->height;
    const size_t texels = (size_t)W * (size_t)H;
    // The texel steps across the view.
    double z[3] = { def->step_d[0], def->step_d[1], def->step_d[2] };
    double zl = sqrt(dot3(z, z));
    if (!(zl > 0.0) || !(def->noise > 0.0f)) {
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "adaptive smoothing: bad definition");
    }
    double px[3], py[3];
    double fi = dot3(def->step_i, z) / (zl * zl), fj = dot3(def->step_j, z) / (zl * zl);
    for (int k = 0; k < 3; ++k) {
        px[k] = def->step_i[k] - fi * z[k];
        py[k] = def->step_j[k] - fj * z[k];
    }
    double cross[3] = { px[1] * py[2] - px[2] * py[1], px[2] * py[0] - px[0] * py[2],
                        px[0] * py[1] - px[1] * py[0] };
    const double head_area = sqrt(dot3(cross, cross));
    const double texel_i = sqrt(dot3(px, px)), texel_j = sqrt(dot3(py, py));
    const double texel = sqrt(head_area);
    if (!(head_area > 0.0) || !isfinite(head_area)) {
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "adaptive smoothing: degenerate target");
    }
    double max_r = def->max_radius > texel ? def->max_radius : texel;

    job jb;
    memset(&jb, 0, sizeof jb);
    jb.def = def;
    jb.width = W;
    jb.height = H;
    jb.out = out;
    jb.texel_i = (float)texel_i;
    jb.texel_j = (float)texel_j;
    jb.min_radius = (float)texel;
    jb.max_radius = (float)max_r;
    jb.z2 = (float)(zl * zl);
    jb.inv_z = (float)(1.0 / zl);
    jb.target_hits = 1.5 / ((double)def->noise * (double)def->noise);
    int pad_x = (int)ceil(max_r / texel_i) + 1, pad_y = (int)ceil(max_r / texel_j) + 1;
    jb.stride = (size_t)pad_x * 2 + ((size_t)W + CHUNK - 1) / CHUNK * CHUNK;
    size_t plane = jb.stride * ((size_t)H + 2 * (size_t)pad_y);
    jb.base = (size_t)pad_y * jb.stride + (size_t)pad_x;
    jb.tiles_x = (W + TILE - 1) / TILE;
    jb.tiles_y = (H + TILE - 1) / TILE;
    const size_t tiles = (size_t)jb.tiles_x * (size_t)jb.tiles_y;
    const size_t sat_size = ((size_t)W + 1) * ((size_t)H + 1);

    size_t cap = (size_t)(2 * pad_x - 1) * (size_t)(2 * pad_y - 1);
    offset *offsets = malloc(cap * sizeof *offsets);
    jb.reach_i = malloc(2 * cap * sizeof *jb.reach_i);
    jb.reach_j = jb.reach_i + cap;
    float *scratch = wx_big_calloc(8 * plane, sizeof *scratch);
    jb.clean_bits = wx_big_calloc(plane / 64 + 2, sizeof *jb.clean_bits);
    for (int v = 0; v < 256; ++v) {
        uint64_t bytes = 0;
        for (int k = 0; k < 8; ++k) {
            bytes |= (uint64_t)((v >> k) & 1) << (8 * k);
        }
        jb.spread[v] = bytes; // little-endian: byte k of the word is bit k
    }
    jb.delta = wx_big_malloc(texels * sizeof *jb.delta);
    jb.radius = wx_big_calloc(texels, sizeof *jb.radius);
    jb.clean = wx_big_calloc(texels, 1);
    jb.impacts = wx_big_malloc(texels * sizeof *jb.impacts);
    const int k_max = (int)ceil(max_r / fmin(texel_i, texel_j));
    const size_t disc_cap = (size_t)(2 * k_max + 1) * (size_t)(2 * k_max + 1);
    disc_offset *disc = malloc(disc_cap * sizeof *disc);
    jb.half_disc = malloc(((size_t)k_max + 1) * sizeof *jb.half_disc);
    jb.sat = wx_big_calloc(2 * sat_size, sizeof *jb.sat);
    jb.tile_bound = calloc(tiles, sizeof *jb.tile_bound);
    float *tile_max = calloc(tiles, sizeof *tile_max);
    float *sorted = NULL;
    // The noise each capped texel keeps, for the stats (step 3).
    float *capped_noise = stats != NULL ? malloc(texels * sizeof *capped_noise) : NULL;
    wx_result r = WX_OK;
    if (offsets == NULL || jb.reach_i == NULL || scratch == NULL || jb.delta == NULL ||
        jb.radius == NULL || jb.clean == NULL || jb.sat == NULL || jb.tile_bound == NULL ||
        tile_max == NULL || jb.impacts == NULL || disc == NULL || jb.half_disc == NULL ||
        (stats != NULL && capped_noise == NULL) || jb.clean_bits == NULL) {
        r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "gather: out of memory (adaptive smoothing)");
        goto done;
    }
    jb.sat_surface = jb.sat + sat_size;
    jb.k_max = k_max;
    jb.disc_count = build_disc(k_max, disc, jb.half_disc);
    jb.disc = disc;
    jb.offset_count = build_offsets(def, px, py, z, pad_x - 1, pad_y - 1, max_r, texel, offsets);
    jb.offsets = offsets;
    // The lines, kept when they fit in LINE_CELLS_MAX cells (radii up to
    // about 68 texels), else walked each time they are needed.
    size_t cells = 0;
    for (int o = 0; o < jb.offset_count; ++o) {
        offsets[o].line_first = cells <= LINE_CELLS_MAX ? (int)cells : 0;
        offsets[o].line_count = line_cells(offsets[o].di, offsets[o].dj, NULL);
        cells += (size_t)offsets[o].line_count;
    }
    jb.line =
        cells <= LINE_CELLS_MAX ? malloc(2 * (cells > 0 ? cells : 1) * sizeof *jb.line) : NULL;
    for (int o = 0; jb.line != NULL && o < jb.offset_count; ++o) {
        line_cells(offsets[o].di, offsets[o].dj, jb.line + 2 * (size_t)offsets[o].line_first);
    }
    for (int o = 0; o < jb.offset_count; ++o) {
        int di = abs(offsets[o].di), dj = abs(offsets[o].dj);
        jb.reach_i[o] = o > 0 && jb.reach_i[o - 1] > di ? jb.reach_i[o - 1] : di;
        jb.reach_j[o] = o > 0 && jb.reach_j[o - 1] > dj ? jb.reach_j[o - 1] : dj;
    }
    jb.pd = scratch;
    jb.pnx = scratch + plane;
    jb.pny = scratch + 2 * plane;
    jb.pnz = scratch + 3 * plane;
    jb.pzn = scratch + 4 * plane;
    jb.pinvh = scratch + 5 * plane;
    jb.pweight = scratch + 6 * plane;
    jb.pcoef = scratch + 7 * plane;

    // Step 1: impacts, changes, the geometry in the padded planes.
    const float view[3] = { (float)(z[0] / zl), (float)(z[1] / zl), (float)(z[2] / zl) };
    const size_t sw = (size_t)W + 1;
    for (int j = 0; j < H; ++j) {
        double row = 0.0, row_surface = 0.0;
        for (int i = 0; i < W; ++i) {
            size_t t = (size_t)j * (size_t)W + (size_t)i;
            size_t p = jb.base + (size_t)j * jb.stride + (size_t)i;
            const float *n = &def->normal[3 * t];
            jb.delta[t] = 0.0f;
            jb.impacts[t] = 0.0f;
            if (!wx_depth_is_empty(def->depth[t])) {
                float cos_view = fabsf(n[0] * view[0] + n[1] * view[1] + n[2] * view[2]);
                double area = head_area / (cos_view > AREA_MIN_COS ? cos_view : AREA_MIN_COS);
                jb.pd[p] = def->depth[t];
                jb.pnx[p] = n[0];
                jb.pny[p] = n[1];
                jb.pnz[p] = n[2];
                jb.pzn[p] = (float)(n[0] * z[0] + n[1] * z[1] + n[2] * z[2]);
                float hits = def->hits[t];
                double impacts = hits > 0.0f && hits < INFINITY ? (double)hits * area : 0.0;
                jb.impacts[t] = (float)impacts;
                row += impacts;
                row_surface += 1.0;
                float change = def->total[t] - def->initial[t];
                jb.delta[t] = isfinite(change) ? change : 0.0f;
            }
            size_t s = (size_t)(j + 1) * sw + (size_t)(i + 1);
            jb.sat[s] = jb.sat[s - sw] + row;
            jb.sat_surface[s] = jb.sat_surface[s - sw] + row_surface;
        }
    }

    // Step 2: radii and clean texels.
    jb.pass = 2;
    wx_pool_for(def->pool, H, 8, run_rows, &jb);

    // Step 3: the samples, and the noise the capped ones keep (while the
    // impacts' table is still there).
    int64_t samples = 0, capped = 0;
    double largest = 0.0;
    for (int j = 0; j < H; ++j) {
        for (int i = 0; i < W; ++i) {
            size_t t = (size_t)j * (size_t)W + (size_t)i;
            size_t p = jb.base + (size_t)j * jb.stride + (size_t)i;
            float h = jb.radius[t];
            if (jb.clean[t] & TEXEL_CLEAN) {
                jb.pnx[p] = jb.pny[p] = jb.pnz[p] = 0.0f; // neither gives nor takes
                jb.radius[t] = h = 0.0f;
            }
            if ((jb.clean[t] & TEXEL_CLEAN) && !(def->hits[t] < 0.0f)) {
                // Nor lets a kernel past, unless no camera saw it (a gap
                // in what the cameras see is not a shelter).
                jb.clean_bits[p / 64] |= (uint64_t)1 << (p % 64);
            }
            if (h > 0.0f) {
                jb.pinvh[p] = 1.0f / h;
                jb.pweight[p] = 1.0f / (h * h);
                jb.pcoef[p] = jb.pweight[p] * jb.delta[t];
                samples++;
                if (h >= jb.max_radius && (jb.clean[t] & TEXEL_SPARSE)) {
                    // Its noise: K' impacts give the aim, fewer give it times
                    // sqrt(K' / impacts) (docs/mask.md, "The radius").
                    if (capped_noise != NULL) {
                        double have = impacts_within(&jb, i, j, jb.max_radius);
                        capped_noise[capped] =
                            (float)(def->noise * sqrt(impacts_wanted(&jb, p) / have));
                    }
                    capped++;
                }
                largest = h > largest ? h : largest;
                size_t tile = (size_t)(j / TILE) * (size_t)jb.tiles_x + (size_t)(i / TILE);
                tile_max[tile] = h > tile_max[tile] ? h : tile_max[tile];
            }
        }
    }
    bound_tiles(&jb, tile_max);
    // Step 4's tables: the samples with a change, the clean texels that stop
    // kernels (the impacts' and the surface's tables are done with).
    for (int j = 0; j < H; ++j) {
        double row = 0.0, row_clean = 0.0;
        for (int i = 0; i < W; ++i) {
            size_t p = jb.base + (size_t)j * jb.stride + (size_t)i;
            row += jb.pcoef[p] != 0.0f ? 1.0 : 0.0;
            row_clean += (double)((jb.clean_bits[p / 64] >> (p % 64)) & 1);
            size_t s = (size_t)(j + 1) * sw + (size_t)(i + 1);
            jb.sat[s] = jb.sat[s - sw] + row;
            jb.sat_surface[s] = jb.sat_surface[s - sw] + row_clean;
        }
    }

    // Step 4: the mask.
    jb.pass = 4;
    wx_pool_for(def->pool, H, 4, run_rows, &jb);

    if (stats != NULL) {
        memset(stats, 0, sizeof *stats);
        stats->target_hits = jb.target_hits;
        stats->max_radius_used = largest;
        stats->capped = capped;
        if (samples > 0 && (sorted = malloc((size_t)samples * sizeof *sorted)) != NULL) {
            int64_t k = 0;
            for (size_t t = 0; t < texels; ++t) {
                if (jb.radius[t] > 0.0f) {
                    sorted[k++] = jb.radius[t];
                }
            }
            qsort(sorted, (size_t)samples, sizeof *sorted, compare_floats);
            stats->median_radius = sorted[samples / 2];
        }
        if (capped > 0 && capped_noise != NULL) {
            qsort(capped_noise, (size_t)capped, sizeof *capped_noise, compare_floats);
            stats->capped_noise = capped_noise[capped / 2];
            for (int64_t k = 0; k < capped; ++k) {
                stats->capped_noise_bins[wx_noise_bin(capped_noise[k])]++;
            }
        }
    }
done:
    free(jb.clean_bits);
    free(jb.line);
    free(capped_noise);
    free(sorted);
    free(tile_max);
    free(jb.tile_bound);
    free(jb.sat);
    free(jb.half_disc);
    free(disc);
    free(jb.impacts);
    free(jb.clean);
    free(jb.radius);
    free(jb.delta);
    free(scratch);
    free(jb.reach_i);
    free(offsets);
    return r;
}
