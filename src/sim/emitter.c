// emitter.c: point, hemisphere and box emitters (thesis 4.8.2, docs/design.md sections 3
// and 8).
#include "sim/emitter.h"

#include <math.h>

#include "sim/particles.h"

int64_t wx_emitter_count_at(const wx_emitter *e, double t)
{
    double until = t < e->end ? t : e->end;
    double span = until - e->start;
    if (!(span > 0.0) || !(e->rate > 0.0)) {
        return 0;
    }
    double n = floor(e->rate * span * (1.0 + 1e-12) + 1e-12);
    // Clamped in double before the cast: rate="1e300" is more than any count
    // (the cast overflowed to a negative count, which the memory check let
    // through).
    return n < 9.2e18 ? (int64_t)n : INT64_MAX;
}

void wx_uniform_sphere(float u1, float u2, float d[3])
{
    // Archimedes: the height is uniform on [-1, 1] for a uniform point on the sphere.
    float y = 1.0f - 2.0f * u1;
    float r = sqrtf(fmaxf(0.0f, 1.0f - y * y));
    float phi = 6.2831853071795865f * u2;
    d[0] = r * cosf(phi);
    d[1] = y;
    d[2] = r * sinf(phi);
}

void wx_uniform_hemisphere(float u1, float u2, float d[3])
{
    // Height uniform on (0, 1]: never exactly horizontal.
    float y = 1.0f - u1;
    float r = sqrtf(fmaxf(0.0f, 1.0f - y * y));
    float phi = 6.2831853071795865f * u2;
    d[0] = r * cosf(phi);
    d[1] = y;
    d[2] = r * sinf(phi);
}

void wx_uniform_cone(const float axis[3], float spread, float u1, float u2, float d[3])
{
    if (!(spread > 0.0f)) {
        d[0] = axis[0];
        d[1] = axis[1];
        d[2] = axis[2];
        return;
    }
    // Solid angle is uniform in cos(theta) (Archimedes again).
    float cos_t = 1.0f - u1 * (1.0f - cosf(spread));
    float sin_t = sqrtf(fmaxf(0.0f, 1.0f - cos_t * cos_t));
    float phi = 6.2831853071795865f * u2;
    // An orthonormal basis around the axis without a branch on its direction
    // (Duff et al. 2017, "Building an orthonormal basis, revisited").
    float sign = copysignf(1.0f, axis[2]);
    float a = -1.0f / (sign + axis[2]);
    float b = axis[0] * axis[1] * a;
    float t[3] = { 1.0f + sign * axis[0] * axis[0] * a, sign * b, -sign * axis[0] };
    float s[3] = { b, sign + axis[1] * axis[1] * a, -axis[1] };
    float x = sin_t * cosf(phi), y = sin_t * sinf(phi);
    for (int k = 0; k < 3; ++k) {
        d[k] = x * t[k] + y * s[k] + cos_t * axis[k];
    }
}

// The Kronecker sequences R1, R2, R3 (Roberts 2018): alpha_k = 1 / phi_d^k,
// phi_d the root of x^(d+1) = x + 1. Their points n = 0, 1, 2, ... cover the
// unit cube evenly, and so do the points of any run of consecutive n.
static const double R_ALPHA[3][3] = {
    { 0.6180339887498949, 0.0, 0.0 },
    { 0.7548776662466927, 0.5698402909980532, 0.0 },
    { 0.8191725133961645, 0.6710436067037893, 0.5497004779019703 },
};

void wx_emitter_uniforms(uint64_t seed, uint64_t id, int dimensions, double *u)
{
    uint64_t serial = id & ((UINT64_C(1) << 48) - 1), emitter = id >> 48;
    const double *alpha = R_ALPHA[dimensions - 1];
    for (int k = 0; k < dimensions; ++k) {
        // One random shift of the whole sequence per seed, emitter and
        // dimension (Cranley and Patterson 1976): a seed moves every point.
        double shift = wx_particle_random(seed, wx_particle_id((uint32_t)emitter, WX_EMIT_SHIFT_SERIAL),
                                          WX_RANDOM_EMIT_BOX + (uint64_t)k);
        double x = shift + (double)serial * alpha[k];
        u[k] = x - floor(x);
    }
}

void wx_emitter_sample(const wx_emitter *e, uint64_t seed, uint64_t id, float pos[3],
                       float vel[3])
{
    if (e->kind == WX_EMITTER_BOX) {
        // The start from the sequence of as many dimensions as the box has
        // extent (a rectangle: R2 over its two axes); the direction from the
        // particle's own random numbers: a direction drawn from the same
        // sequence would be tied to the start, and a cone of rain would print
        // the sequence's lattice as stripes.
        int axes[3], d_count = 0;
        for (int k = 0; k < 3; ++k) {
            pos[k] = e->box_min[k];
            if (e->box_max[k] > e->box_min[k]) {
                axes[d_count++] = k;
            }
        }
        double u[3];
        if (d_count > 0) {
            wx_emitter_uniforms(seed, id, d_count, u);
        }
        for (int j = 0; j < d_count; ++j) {
            int k = axes[j];
            pos[k] = e->box_min[k] + (float)u[j] * (e->box_max[k] - e->box_min[k]);
        }
        float u1 = wx_particle_random(seed, id, WX_RANDOM_EMIT_0);
        float u2 = wx_particle_random(seed, id, WX_RANDOM_EMIT_1);
        float d[3];
        wx_uniform_cone(e->dir, e->spread * 0.017453292519943295f, u1, u2, d);
        for (int k = 0; k < 3; ++k) {
            vel[k] = e->speed * d[k];
        }
        return;
    }
    // The point and hemisphere emitters draw a direction only: from R2.
    double u[2];
    wx_emitter_uniforms(seed, id, 2, u);
    float u1 = (float)u[0], u2 = (float)u[1];
    float d[3];
    if (e->kind == WX_EMITTER_HEMISPHERE) {
        // thesis 4.8.2 samples a cube and rejects; the direct map is uniform too.
        wx_uniform_hemisphere(u1, u2, d);
        for (int k = 0; k < 3; ++k) {
            pos[k] = e->center[k] + e->radius * d[k];
            vel[k] = -e->speed * d[k];
        }
    } else {
        wx_uniform_sphere(u1, u2, d);
        for (int k = 0; k < 3; ++k) {
            pos[k] = e->center[k];
            vel[k] = e->speed * d[k];
        }
    }
}
