// force_field.c: gravity, wind and Perlin turbulence (thesis 3.7, 4.8.2).
//
// The noise is written for the block loop in wx_forces_block to vectorise: no
// tables, no branches (selects and bit operations), a truncating floor, 32-bit
// integer hashing without multiplications, everything inlined.
#include "sim/force_field.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim/particles.h"

// Lattice hashing: simplex corner (i, j, k, l) hashes i*P1 ^ j*P2 ^ k*P3 ^ l*P4 ^
// seed, mixed with shifts and adds (no multiplication: SSE2 has no 32-bit vector
// multiply); bits 20-31 pick one gradient per force component.
#define P1 0x8da6b343u
#define P2 0xd8163841u
#define P3 0xcb1ab31fu
#define P4 0x9e3779b1u

// 4D simplex skew and unskew factors: (sqrt(5) - 1) / 4 and (5 - sqrt(5)) / 20.
#define F4 0.309016994374947f
#define G4 0.138196601125011f

// Scales the raw sum into about [-1, 1]: over 1.2e8 random samples the raw
// value stays within 0.0184 (rms 0.0047); the clamp makes the bound exact.
#define NOISE_SCALE 54.0f

// Keeps lattice coordinates inside int range (a particle far outside the box).
#define NOISE_COORD_MAX 1.0e8f

float wx_turbulence_weight(int o, int octaves)
{
    float sum = 0.0f;
    for (int k = 0; k < octaves; ++k) {
        sum += ldexpf(1.0f, -k);
    }
    return ldexpf(1.0f, -o) / sum;
}

// v clamped to [-limit, limit] (limit > 0) on the bit pattern: a float
// compare-and-select "could trap" and keeps gcc from vectorising the loop, an
// integer one does not. NaN becomes +-limit.
WX_INLINE float clamp_abs(float v, float limit)
{
    uint32_t u, l;
    memcpy(&u, &v, sizeof u);
    memcpy(&l, &limit, sizeof l);
    uint32_t big = -(uint32_t)((u & 0x7fffffffu) > l);
    u = (u & ~big) | (((u & 0x80000000u) | l) & big);
    memcpy(&v, &u, sizeof v);
    return v;
}

WX_INLINE float clamp_coord(float v)
{
    return clamp_abs(v, NOISE_COORD_MAX);
}

WX_INLINE float clamp_unit(float v)
{
    return clamp_abs(v, 1.0f);
}

// floor for |v| < 2^31, by truncation (vectorises without SSE4.1).
WX_INLINE int floor_int(float v)
{
    int i = (int)v;
    return i - (v < (float)i);
}

// A full 32-bit mix (lowbias32) for seeds, once per octave.
static uint32_t seed_mix(uint32_t h)
{
    h ^= h >> 16;
    h *= 0x7feb352du;
    h ^= h >> 15;
    h *= 0x846ca68bu;
    return h ^ (h >> 16);
}

WX_INLINE uint32_t corner_mix(uint32_t h)
{
    h ^= h >> 15;
    h += h << 9;
    h ^= h >> 11;
    h += h << 5;
    return h ^ (h >> 7);
}

// v with its sign flipped when bit `k` of h is set (a vectorisable xor).
WX_INLINE float flip(float v, uint32_t h, int k)
{
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    u ^= (h << (31 - k)) & 0x80000000u;
    memcpy(&v, &u, sizeof v);
    return v;
}

// 1.0f where the mask is all ones, 0.0f where it is zero, on the bit pattern
// (an int to float conversion here became a branch in gcc's hands).
WX_INLINE float mask_one(uint32_t mask)
{
    uint32_t u = mask & 0x3f800000u;
    float v;
    memcpy(&v, &u, sizeof v);
    return v;
}

// Dot product with one of the 16 gradients (+-1, +-1, +-1, +-1), from bits k..k+3.
WX_INLINE float grad(uint32_t h, int k, float x, float y, float z, float w)
{
    return flip(x, h, k) + flip(y, h, k + 1) + flip(z, h, k + 2) + flip(w, h, k + 3);
}

// Adds one simplex corner's contribution ((0.5 - r^2)^4 g.d per component). The
// kernel radius^2 is 0.5, not the 0.6 of Gustavson's code: with 0.6 a corner's
// kernel reaches beyond the simplices it belongs to and the noise jumps.
// max(t, 0) is written (t + |t|) / 2: a compare-and-select on floats "could
// trap" and keeps gcc from vectorising the loop.
WX_INLINE void corner(uint32_t h, float x, float y, float z, float w, float *a, float *b,
                      float *c)
{
    float t = 0.5f - x * x - y * y - z * z - w * w;
    t = 0.5f * (t + fabsf(t));
    t *= t;
    t *= t;
    h = corner_mix(h);
    *a += t * grad(h, 20, x, y, z, w);
    *b += t * grad(h, 24, x, y, z, w);
    *c += t * grad(h, 28, x, y, z, w);
}

// 4D simplex noise (Perlin 2001, after Gustavson's formulation), three
// components from one walk over the five corners, unclamped. Coordinates must
// be clamped (clamp_coord) so that the lattice indices fit in an int.
WX_INLINE void noise_lane(float x, float y, float z, float w, uint32_t seed, float *n0, float *n1,
                          float *n2)
{
    float s = (x + y + z + w) * F4;
    int i = floor_int(x + s), j = floor_int(y + s), k = floor_int(z + s), l = floor_int(w + s);
    float t = (float)(i + j + k + l) * G4;
    float x0 = x - ((float)i - t), y0 = y - ((float)j - t);
    float z0 = z - ((float)k - t), w0 = w - ((float)l - t);
    // Rank of each coordinate among the four: which simplex of the cell we are in.
    int cxy = x0 > y0, cxz = x0 > z0, cxw = x0 > w0, cyz = y0 > z0, cyw = y0 > w0, czw = z0 > w0;
    int rx = cxy + cxz + cxw;
    int ry = (1 - cxy) + cyz + cyw;
    int rz = (1 - cxz) + (1 - cyz) + czw;
    int rw = (1 - cxw) + (1 - cyw) + (1 - czw);
    uint32_t i1 = -(uint32_t)(rx >= 3), j1 = -(uint32_t)(ry >= 3);
    uint32_t k1 = -(uint32_t)(rz >= 3), l1 = -(uint32_t)(rw >= 3);
    uint32_t i2 = -(uint32_t)(rx >= 2), j2 = -(uint32_t)(ry >= 2);
    uint32_t k2 = -(uint32_t)(rz >= 2), l2 = -(uint32_t)(rw >= 2);
    uint32_t i3 = -(uint32_t)(rx >= 1), j3 = -(uint32_t)(ry >= 1);
    uint32_t k3 = -(uint32_t)(rz >= 1), l3 = -(uint32_t)(rw >= 1);
    uint32_t hx = (uint32_t)i * P1, hy = (uint32_t)j * P2, hz = (uint32_t)k * P3;
    uint32_t hw = (uint32_t)l * P4 + seed; // added: lattice offsets commute with it
    float a = 0.0f, b = 0.0f, c = 0.0f;
    corner(hx ^ hy ^ hz ^ hw, x0, y0, z0, w0, &a, &b, &c);
    corner((hx + (P1 & i1)) ^ (hy + (P2 & j1)) ^ (hz + (P3 & k1)) ^ (hw + (P4 & l1)),
           x0 - mask_one(i1) + G4, y0 - mask_one(j1) + G4, z0 - mask_one(k1) + G4,
           w0 - mask_one(l1) + G4, &a, &b, &c);
    corner((hx + (P1 & i2)) ^ (hy + (P2 & j2)) ^ (hz + (P3 & k2)) ^ (hw + (P4 & l2)),
           x0 - mask_one(i2) + 2.0f * G4, y0 - mask_one(j2) + 2.0f * G4,
           z0 - mask_one(k2) + 2.0f * G4, w0 - mask_one(l2) + 2.0f * G4, &a, &b, &c);
    corner((hx + (P1 & i3)) ^ (hy + (P2 & j3)) ^ (hz + (P3 & k3)) ^ (hw + (P4 & l3)),
           x0 - mask_one(i3) + 3.0f * G4, y0 - mask_one(j3) + 3.0f * G4,
           z0 - mask_one(k3) + 3.0f * G4, w0 - mask_one(l3) + 3.0f * G4, &a, &b, &c);
    corner((hx + P1) ^ (hy + P2) ^ (hz + P3) ^ (hw + P4), x0 - 1.0f + 4.0f * G4,
           y0 - 1.0f + 4.0f * G4, z0 - 1.0f + 4.0f * G4, w0 - 1.0f + 4.0f * G4, &a, &b, &c);
    *n0 = a * NOISE_SCALE;
    *n1 = b * NOISE_SCALE;
    *n2 = c * NOISE_SCALE;
}

void wx_noise4(uint32_t seed, float x, float y, float z, float t, float out[3])
{
    float n0, n1, n2;
    noise_lane(clamp_coord(x), clamp_coord(y), clamp_coord(z), clamp_coord(t), seed_mix(seed),
               &n0, &n1, &n2);
    out[0] = clamp_unit(n0);
    out[1] = clamp_unit(n1);
    out[2] = clamp_unit(n2);
}

// Octave o: its seed and a fixed offset so that octaves do not all share the
// same lattice at the origin.
static uint32_t octave_seed(const wx_turbulence *turb, int o)
{
    return turb->seed + (uint32_t)o * 0x632be5abu;
}

static float octave_offset(int o, int axis)
{
    static const float base[4] = { 0.3183099f, 0.5772157f, 0.7390851f, 0.1415927f };
    return base[axis] * (float)(o + 1);
}

void wx_turbulence_octave(const wx_turbulence *turb, int o, const float p[3], float t,
                          float out[3])
{
    float f = turb->frequency * ldexpf(1.0f, o);
    wx_noise4(octave_seed(turb, o), p[0] * f + octave_offset(o, 0), p[1] * f + octave_offset(o, 1),
              p[2] * f + octave_offset(o, 2), t * f + octave_offset(o, 3), out);
}

void wx_turbulence_force(const wx_turbulence *turb, const float p[3], float t, float out[3])
{
    float acc[3] = { 0.0f, 0.0f, 0.0f };
    for (int o = 0; o < turb->octaves; ++o) {
        float n[3];
        wx_turbulence_octave(turb, o, p, t, n);
        float w = turb->weight[o];
        acc[0] += w * n[0];
        acc[1] += w * n[1];
        acc[2] += w * n[2];
    }
    for (int k = 0; k < 3; ++k) {
        out[k] = turb->strength * acc[k];
    }
}

// Inputs the compiler cannot fold: (1 + 2^-12)^2 - (1 + 2^-11) is 2^-24 when the
// product is not rounded before the addition, 0 when it is.
static volatile float probe_a = 1.0f + 0x1p-12f, probe_c = -(1.0f + 0x1p-11f);

WX_HOT static float multiply_add(float a, float b, float c)
{
    return a * b + c;
}

bool wx_kernels_fuse_multiply_add(void)
{
    return multiply_add(probe_a, probe_a, probe_c) != 0.0f;
}

WX_HOT void wx_forces_block(const wx_forces *forces, float t, const float *restrict x,
                            const float *restrict y, const float *restrict z, float *restrict fx,
                            float *restrict fy, float *restrict fz)
{
    enum { B = WX_PARTICLE_BLOCK };
    for (int k = 0; k < B; ++k) {
        fx[k] = forces->wind[0];
        fy[k] = forces->wind[1];
        fz[k] = forces->wind[2];
    }
    for (int f = 0; f < forces->turbulence_count; ++f) {
        const wx_turbulence *turb = &forces->turbulence[f];
        float ax[B], ay[B], az[B];
        for (int k = 0; k < B; ++k) {
            ax[k] = ay[k] = az[k] = 0.0f;
        }
        for (int o = 0; o < turb->octaves; ++o) {
            float freq = turb->frequency * ldexpf(1.0f, o);
            float ox = octave_offset(o, 0), oy = octave_offset(o, 1), oz = octave_offset(o, 2);
            float w = clamp_coord(t * freq + octave_offset(o, 3));
            float weight = turb->weight[o];
            uint32_t seed = seed_mix(octave_seed(turb, o));
            float qx[B], qy[B], qz[B];
            for (int k = 0; k < B; ++k) {
                qx[k] = clamp_coord(x[k] * freq + ox);
                qy[k] = clamp_coord(y[k] * freq + oy);
                qz[k] = clamp_coord(z[k] * freq + oz);
            }
            float n0[B], n1[B], n2[B];
            for (int k = 0; k < B; ++k) {
                noise_lane(qx[k], qy[k], qz[k], w, seed, &n0[k], &n1[k], &n2[k]);
            }
            for (int k = 0; k < B; ++k) {
                ax[k] += weight * clamp_unit(n0[k]);
                ay[k] += weight * clamp_unit(n1[k]);
                az[k] += weight * clamp_unit(n2[k]);
            }
        }
        float strength = turb->strength;
        for (int k = 0; k < B; ++k) {
            fx[k] += strength * ax[k];
            fy[k] += strength * ay[k];
            fz[k] += strength * az[k];
        }
    }
}

wx_result wx_forces_init(wx_forces *forces, const wx_field *fields, int count, uint64_t seed,
                         wx_error *err)
{
    memset(forces, 0, sizeof *forces);
    int turbulence = 0;
    for (int i = 0; i < count; ++i) {
        const wx_field *field = &fields[i];
        if (!isfinite(field->strength)) {
            return wx_fail(err, WX_CAUSE_BAD_VALUE, "force field %d: strength is not finite", i);
        }
        if (field->kind == WX_FIELD_TURBULENCE) {
            if (field->octaves < 1 || field->octaves > WX_MAX_OCTAVES) {
                return wx_fail(err, WX_CAUSE_BAD_VALUE,
                               "turbulence field %d: octaves must be 1..%d, not %d", i,
                               WX_MAX_OCTAVES, field->octaves);
            }
            if (!isfinite(field->frequency)) {
                return wx_fail(err, WX_CAUSE_BAD_VALUE,
                               "turbulence field %d: frequency is not finite", i);
            }
            turbulence++;
        }
    }
    if (turbulence > 0) {
        forces->turbulence = calloc((size_t)turbulence, sizeof *forces->turbulence);
        if (forces->turbulence == NULL) {
            return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (force fields)");
        }
    }
    for (int i = 0; i < count; ++i) {
        const wx_field *field = &fields[i];
        if (field->kind == WX_FIELD_GRAVITY) {
            forces->gravity[1] -= field->strength;
        } else if (field->kind == WX_FIELD_WIND) {
            float len = sqrtf(field->dir[0] * field->dir[0] + field->dir[1] * field->dir[1] +
                              field->dir[2] * field->dir[2]);
            if (len > 0.0f) {
                for (int k = 0; k < 3; ++k) {
                    forces->wind[k] += field->strength * field->dir[k] / len;
                }
            }
        } else if (field->strength != 0.0f) {
            wx_turbulence *turb = &forces->turbulence[forces->turbulence_count++];
            turb->strength = field->strength;
            turb->frequency = field->frequency;
            turb->octaves = field->octaves;
            turb->seed = (uint32_t)wx_mix64(seed ^ wx_mix64((uint64_t)i + 0x7475726275ull));
            for (int o = 0; o < field->octaves; ++o) {
                turb->weight[o] = wx_turbulence_weight(o, field->octaves);
            }
        }
    }
    return WX_OK;
}

void wx_forces_free(wx_forces *forces)
{
    free(forces->turbulence);
    memset(forces, 0, sizeof *forces);
}
