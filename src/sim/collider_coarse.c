// collider_coarse.c: the collider's coarse test (docs/physics.md), run on a
// block of segments at a time: each segment against the camera's coarse
// pyramid, vectorised; what it clears needs no swept test.
#include "sim/collider.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim/force_field.h"
#include "sim/particles.h"

// --- the coarse test -------------------------------------------------------------

// |v| clamped to `limit` on the bit pattern (vectorises; NaN becomes limit).
WX_INLINE float abs_clamped(float v, float limit)
{
    uint32_t u, l;
    memcpy(&u, &v, sizeof u);
    memcpy(&l, &limit, sizeof l);
    u &= 0x7fffffffu;
    uint32_t big = -(uint32_t)(u > l);
    u = (u & ~big) | (l & big);
    memcpy(&v, &u, sizeof v);
    return v;
}

// max(a, b) without a float select (rounding error: one ulp of the larger).
WX_INLINE float max_arith(float a, float b)
{
    return 0.5f * (a + b + fabsf(a - b));
}

// One lane of the coarse test against one camera. Sets *usable when the segment
// lies inside the frame and short enough for a pyramid level, *index to that
// level's cell, *dmax to the segment's largest d (plus rounding slack) and
// returns 1 when the segment lies wholly outside the frame.
typedef struct coarse_geometry {
    const float *mx, *my, *md;
    float W, H, slack_scale, slack_base;
    int offset0, width0, offset1, width1, offset2, width2, offset3, width3, offset4, width4;
} coarse_geometry;

static inline coarse_geometry coarse_setup(const wx_collider_camera *cam)
{
    coarse_geometry g;
    g.mx = cam->fmx;
    g.my = cam->fmy;
    g.md = cam->fmd;
    g.W = (float)cam->width;
    g.H = (float)cam->height;
    g.slack_scale = 4e-7f * (fabsf(g.md[0]) + fabsf(g.md[1]) + fabsf(g.md[2]));
    g.slack_base = 4e-7f * fabsf(g.md[3]);
    // Level geometry in locals: a load under a condition "could trap" and keeps
    // gcc from vectorising.
    g.offset0 = cam->level_offset[0];
    g.width0 = cam->level_width[0];
    g.offset1 = cam->level_offset[1];
    g.width1 = cam->level_width[1];
    g.offset2 = cam->level_offset[2];
    g.width2 = cam->level_width[2];
    g.offset3 = cam->level_offset[3];
    g.width3 = cam->level_width[3];
    g.offset4 = cam->level_offset[4];
    g.width4 = cam->level_width[4];
    return g;
}

WX_INLINE int coarse_lane(const coarse_geometry *g, float x0, float y0, float z0, float x1,
                          float y1, float z1, int *usable, int *index, float *dmax)
{
    const float margin = 1.0f / 64.0f; // texels kept from the frame edge
    const float *mx = g->mx, *my = g->my, *md = g->md;
    float W = g->W, H = g->H;
    float X0 = x0 * mx[0] + y0 * mx[1] + z0 * mx[2] + mx[3];
    float Y0 = x0 * my[0] + y0 * my[1] + z0 * my[2] + my[3];
    float D0 = x0 * md[0] + y0 * md[1] + z0 * md[2] + md[3];
    float X1 = x1 * mx[0] + y1 * mx[1] + z1 * mx[2] + mx[3];
    float Y1 = x1 * my[0] + y1 * my[1] + z1 * my[2] + my[3];
    float D1 = x1 * md[0] + y1 * md[1] + z1 * md[2] + md[3];
    int in = (X0 >= margin) & (X0 < W - margin) & (Y0 >= margin) & (Y0 < H - margin) &
             (X1 >= margin) & (X1 < W - margin) & (Y1 >= margin) & (Y1 < H - margin);
    int out = ((X0 < -margin) & (X1 < -margin)) | ((X0 > W + margin) & (X1 > W + margin)) |
              ((Y0 < -margin) & (Y1 < -margin)) | ((Y0 > H + margin) & (Y1 > H + margin));
    // How far the segment reaches, in texels, picks the pyramid level.
    int reach = (int)max_arith(abs_clamped(X1 - X0, 1e9f), abs_clamped(Y1 - Y0, 1e9f));
    int xi = (int)abs_clamped(X0, 1e9f), yi = (int)abs_clamped(Y0, 1e9f);
    // (Written out level by level: an inner loop keeps gcc from vectorising.)
    int chosen = 0, found = 0;
#define WX_COARSE_PICK(l)                                                                          \
    {                                                                                              \
        int shift = WX_COARSE_BLOCK_SHIFT + WX_COARSE_LEVEL_SHIFT * (l);                           \
        int fits = ((reach + 2) <= (1 << shift)) & !found;                                         \
        int here = g->offset##l + (yi >> shift) * g->width##l + (xi >> shift);                     \
        chosen = fits ? here : chosen;                                                             \
        found |= fits;                                                                             \
    }
    WX_COARSE_PICK(0)
    WX_COARSE_PICK(1)
    WX_COARSE_PICK(2)
    WX_COARSE_PICK(3)
    WX_COARSE_PICK(4)
#undef WX_COARSE_PICK
    *usable = in & found;
    *index = *usable ? chosen : 0;
    float slack = g->slack_base + g->slack_scale * (fabsf(x0) + fabsf(y0) + fabsf(z0) + fabsf(x1) +
                                                    fabsf(y1) + fabsf(z1));
    *dmax = max_arith(D0, D1) + slack;
    return out;
}

_Static_assert(WX_PARTICLE_BLOCK == 16, "lane_bit below has 16 entries");

WX_HOT uint32_t wx_collider_coarse_block(const wx_collider *collider, const int *cams, int count,
                                         uint32_t *restrict credit, const float *restrict x0,
                                         const float *restrict y0, const float *restrict z0,
                                         const float *restrict x1, const float *restrict y1,
                                         const float *restrict z1, uint32_t *restrict outside)
{
    enum { B = WX_PARTICLE_BLOCK };
    static const uint32_t lane_bit[B] = { 1u << 0,  1u << 1,  1u << 2,  1u << 3, 1u << 4,  1u << 5,
                                          1u << 6,  1u << 7,  1u << 8,  1u << 9, 1u << 10, 1u << 11,
                                          1u << 12, 1u << 13, 1u << 14, 1u << 15 };
    const uint32_t all = (1u << B) - 1u;
    uint32_t cleared = 0, out_all = all;
    for (int n = 0; n < count; ++n) {
        int c = cams[n];
        const wx_collider_camera *cam = &collider->cameras[c];
        coarse_geometry g = coarse_setup(cam);
        int idx[B], usable[B], out[B];
        float dmax[B];
        for (int k = 0; k < B; ++k) {
            out[k] = coarse_lane(&g, x0[k], y0[k], z0[k], x1[k], y1[k], z1[k], &usable[k], &idx[k],
                                 &dmax[k]);
        }
        float least[B];
        for (int k = 0; k < B; ++k) {
            least[k] = cam->coarse[idx[k]];
        }
        // Lane k to bit k as an OR reduction with constant weights (vectorises;
        // a shift by k does not).
        uint32_t clear_bits = 0, out_bits = 0;
        for (int k = 0; k < B; ++k) {
            clear_bits |= -(uint32_t)(usable[k] & (dmax[k] < least[k])) & lane_bit[k];
            out_bits |= -(uint32_t)out[k] & lane_bit[k];
        }
        if (cam->frames_model) {
            clear_bits |= out_bits; // wholly outside a frame that holds the model
        }
        if (credit != NULL) {
            credit[c] += (uint32_t)__builtin_popcount(clear_bits & ~cleared);
        }
        cleared |= clear_bits;
        out_all &= out_bits;
        if (cleared == all) {
            break; // one camera vouches for every lane: the others are not needed
        }
    }
    *outside = out_all;
    return cleared;
}

bool wx_collider_coarse_clear(const wx_collider *collider, const float p0[3], const float p1[3])
{
    bool outside = collider->camera_count > 0;
    for (int c = 0; c < collider->camera_count; ++c) {
        const wx_collider_camera *cam = &collider->cameras[c];
        coarse_geometry g = coarse_setup(cam);
        int usable, index;
        float dmax;
        int out = coarse_lane(&g, p0[0], p0[1], p0[2], p1[0], p1[1], p1[2], &usable, &index, &dmax);
        outside &= out != 0;
        if ((usable && dmax < cam->coarse[index]) || (out && cam->frames_model)) {
            return true;
        }
    }
    return outside || collider->camera_count == 0;
}

// --- the fine test ----------------------------------------------------------------

// Whether camera `cam` sees the segment p0 + s d, s in [0, 1], inside its frame
// and in front of near3 over each texel it crosses: a walk over the texels of
// its projection, each compared with the segment's farthest depth over the
// part that crosses it. The projection is the swept test's (march_init: the
// float ends in double). Every half-texel cell of a point in texel T reads
// texels within one of T (the bilinear cell's corners, the texel's own), and
// a point that rounding puts across a texel's edge lies in a half cell that
// reads T and its neighbour, so T's 3 x 3 minimum bounds every crossing the
// swept test meets there.
static bool camera_clears(const wx_collider_camera *cam, const double p[3], const double d[3])
{
    const double margin = 1.0 / 64.0; // texels kept from the frame edge, as coarse_lane
    double W = cam->width, H = cam->height;
    double X0 = p[0] * cam->mx[0] + p[1] * cam->mx[1] + p[2] * cam->mx[2] + cam->mx[3];
    double Y0 = p[0] * cam->my[0] + p[1] * cam->my[1] + p[2] * cam->my[2] + cam->my[3];
    double D0 = p[0] * cam->md[0] + p[1] * cam->md[1] + p[2] * cam->md[2] + cam->md[3];
    double dX = d[0] * cam->mx[0] + d[1] * cam->mx[1] + d[2] * cam->mx[2];
    double dY = d[0] * cam->my[0] + d[1] * cam->my[1] + d[2] * cam->my[2];
    double dD = d[0] * cam->md[0] + d[1] * cam->md[1] + d[2] * cam->md[2];
    double X1 = X0 + dX, Y1 = Y0 + dY;
    if (!(X0 >= margin && X0 < W - margin && Y0 >= margin && Y0 < H - margin && X1 >= margin &&
          X1 < W - margin && Y1 >= margin && Y1 < H - margin)) {
        return false;
    }
    int i = (int)X0, j = (int)Y0;
    int si = dX > 0.0 ? 1 : -1, sj = dY > 0.0 ? 1 : -1;
    double rx = dX != 0.0 ? 1.0 / fabs(dX) : INFINITY, ry = dY != 0.0 ? 1.0 / fabs(dY) : INFINITY;
    double tx = dX > 0.0 ? (i + 1 - X0) * rx : dX < 0.0 ? (X0 - i) * rx : INFINITY;
    double ty = dY > 0.0 ? (j + 1 - Y0) * ry : dY < 0.0 ? (Y0 - j) * ry : INFINITY;
    int steps = abs((int)X1 - i) + abs((int)Y1 - j) + 2;
    double s = 0.0;
    for (int n = 0; n <= steps; ++n) {
        double next = tx < ty ? tx : ty;
        next = next < 1.0 ? next : 1.0;
        double da = D0 + s * dD, db = D0 + next * dD;
        double far = da > db ? da : db;
        if (i < 0 || i >= cam->width || j < 0 || j >= cam->height ||
            !(far < cam->near3[(size_t)j * (size_t)cam->width + (size_t)i])) {
            return false;
        }
        if (next >= 1.0) {
            return true;
        }
        if (tx <= ty) {
            i += si;
            tx += rx;
        } else {
            j += sj;
            ty += ry;
        }
        s = next;
    }
    return false; // (rounding kept the walk from its end: the swept test decides)
}

bool wx_collider_fine_clear(const wx_collider *collider, const float p0[3], const float p1[3])
{
    double p[3] = { p0[0], p0[1], p0[2] };
    double d[3] = { (double)p1[0] - p0[0], (double)p1[1] - p0[1], (double)p1[2] - p0[2] };
    for (int c = 0; c < collider->camera_count; ++c) {
        if (camera_clears(&collider->cameras[c], p, d)) {
            return true;
        }
    }
    return false;
}

void wx_collider_prefetch(const wx_collider *collider, const float p[3])
{
    for (int c = 0; c < collider->camera_count; ++c) {
        const wx_collider_camera *cam = &collider->cameras[c];
        float X = p[0] * cam->fmx[0] + p[1] * cam->fmx[1] + p[2] * cam->fmx[2] + cam->fmx[3];
        float Y = p[0] * cam->fmy[0] + p[1] * cam->fmy[1] + p[2] * cam->fmy[2] + cam->fmy[3];
        if (!(X >= 0.0f && X < (float)cam->width && Y >= 0.0f && Y < (float)cam->height)) {
            continue;
        }
        int i = (int)X, j = (int)Y;
        size_t t = (size_t)j * (size_t)cam->width + (size_t)i;
        // The texel's row and the neighbouring row bilinear depth reads.
        __builtin_prefetch(&cam->depth[t]);
        int other = Y - (float)j < 0.5f ? j - 1 : j + 1;
        if (other >= 0 && other < cam->height) {
            __builtin_prefetch(&cam->depth[(size_t)other * (size_t)cam->width + (size_t)i]);
        }
    }
}
