// test_force_field.c: gravity, wind and the Perlin (simplex) turbulence.
#include <math.h>
#include <string.h>

#include "ensure.h"
#include "sim/force_field.h"
#include "sim/particles.h"

static wx_field field(wx_field_kind kind, float strength)
{
    wx_field f;
    memset(&f, 0, sizeof f);
    f.kind = kind;
    f.strength = strength;
    f.frequency = 1;
    f.octaves = 4;
    return f;
}

TEST(gravity_and_wind_fold_into_constants)
{
    wx_field fields[4] = { field(WX_FIELD_GRAVITY, 9.8f), field(WX_FIELD_GRAVITY, 0.2f),
                           field(WX_FIELD_WIND, 2.0f), field(WX_FIELD_WIND, 1.0f) };
    fields[2].dir[0] = 3;
    fields[2].dir[2] = 4; // 2 * (0.6, 0, 0.8)
    fields[3].dir[1] = -1;
    wx_forces forces;
    wx_error err;
    ENSURE(wx_forces_init(&forces, fields, 4, 1, &err) == WX_OK);
    ENSURE_NEAR(forces.gravity[0], 0, 0);
    ENSURE_NEAR(forces.gravity[1], -10.0, 1e-6);
    ENSURE_NEAR(forces.wind[0], 1.2, 1e-6);
    ENSURE_NEAR(forces.wind[1], -1.0, 1e-6);
    ENSURE_NEAR(forces.wind[2], 1.6, 1e-6);
    ENSURE(forces.turbulence_count == 0);
    // The block force is the wind alone.
    float x[WX_PARTICLE_BLOCK] = { 0 }, fx[WX_PARTICLE_BLOCK], fy[WX_PARTICLE_BLOCK],
          fz[WX_PARTICLE_BLOCK];
    wx_forces_block(&forces, 0.5f, x, x, x, fx, fy, fz);
    ENSURE(fx[3] == forces.wind[0] && fy[7] == forces.wind[1] && fz[15] == forces.wind[2]);
    wx_forces_free(&forces);
}

TEST(bad_octaves_are_refused)
{
    wx_field f = field(WX_FIELD_TURBULENCE, 1);
    f.octaves = 0;
    wx_forces forces;
    wx_error err;
    ENSURE(wx_forces_init(&forces, &f, 1, 1, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_VALUE);
    ENSURE(ensure_contains(err.message, "octaves"));
}

// Octave weights 2^-o / sum 2^-k: for 3 octaves 4/7, 2/7, 1/7.
TEST(octave_weights_halve_and_sum_to_one)
{
    ENSURE_NEAR(wx_turbulence_weight(0, 1), 1.0, 1e-7);
    ENSURE_NEAR(wx_turbulence_weight(0, 3), 4.0 / 7.0, 1e-7);
    ENSURE_NEAR(wx_turbulence_weight(1, 3), 2.0 / 7.0, 1e-7);
    ENSURE_NEAR(wx_turbulence_weight(2, 3), 1.0 / 7.0, 1e-7);
    for (int n = 1; n <= WX_MAX_OCTAVES; ++n) {
        double sum = 0;
        for (int o = 0; o < n; ++o) {
            sum += wx_turbulence_weight(o, n);
        }
        ENSURE_NEAR(sum, 1.0, 1e-6);
    }
}

// The force is strength * sum_o weight_o * octave_o, octave o at frequency f*2^o.
TEST(turbulence_is_the_weighted_octave_sum)
{
    wx_field f = field(WX_FIELD_TURBULENCE, 3.0f);
    f.frequency = 0.5f;
    f.octaves = 3;
    wx_forces forces;
    wx_error err;
    ENSURE(wx_forces_init(&forces, &f, 1, 11, &err) == WX_OK);
    ENSURE(forces.turbulence_count == 1);
    const wx_turbulence *turb = &forces.turbulence[0];
    for (int i = 0; i < 100; ++i) {
        float p[3] = { 0.37f * i, -1.3f + 0.11f * i, 2.0f - 0.07f * i };
        float t = 0.01f * i;
        float force[3], o0[3], o1[3], o2[3];
        wx_turbulence_force(turb, p, t, force);
        wx_turbulence_octave(turb, 0, p, t, o0);
        wx_turbulence_octave(turb, 1, p, t, o1);
        wx_turbulence_octave(turb, 2, p, t, o2);
        for (int k = 0; k < 3; ++k) {
            double expect = 3.0 * (4.0 / 7.0 * o0[k] + 2.0 / 7.0 * o1[k] + 1.0 / 7.0 * o2[k]);
            ENSURE_NEAR(force[k], expect, 1e-5);
        }
        // Octave 1 is octave 0's noise field at twice the frequency (other seed):
        // a different value at the same point.
        ENSURE(o0[0] != o1[0]);
    }
    wx_forces_free(&forces);
}

TEST(noise_is_deterministic_and_depends_on_everything)
{
    float a[3], b[3], c[3], d[3], e[3];
    wx_noise4(5, 1.25f, -3.5f, 7.75f, 0.3f, a);
    wx_noise4(5, 1.25f, -3.5f, 7.75f, 0.3f, b);
    wx_noise4(6, 1.25f, -3.5f, 7.75f, 0.3f, c);
    wx_noise4(5, 1.25f, -3.5f, 7.75f, 1.3f, d);
    wx_noise4(5, 1.75f, -3.5f, 7.75f, 0.3f, e);
    ENSURE(memcmp(a, b, sizeof a) == 0);
    ENSURE(memcmp(a, c, sizeof a) != 0);
    ENSURE(memcmp(a, d, sizeof a) != 0); // changes with time
    ENSURE(memcmp(a, e, sizeof a) != 0);
    ENSURE(a[0] != a[1] && a[1] != a[2]); // three independent components
}

// Bounded by 1, zero mean, not degenerate, and the components uncorrelated.
TEST(noise_is_bounded_and_zero_mean)
{
    enum { N = 400000 };
    double mean[3] = { 0 }, square[3] = { 0 }, cross = 0, peak = 0;
    uint64_t state = 12345;
    for (int i = 0; i < N; ++i) {
        float q[4];
        for (int k = 0; k < 4; ++k) {
            state = wx_mix64(state + (uint64_t)k + 1);
            q[k] = (float)((state >> 11) * (1.0 / 9007199254740992.0) * 200.0 - 100.0);
        }
        float n[3];
        wx_noise4(77, q[0], q[1], q[2], q[3], n);
        for (int k = 0; k < 3; ++k) {
            mean[k] += n[k] / N;
            square[k] += (double)n[k] * n[k] / N;
            peak = fmax(peak, fabs(n[k]));
        }
        cross += (double)n[0] * n[1] / N;
    }
    ENSURE(peak <= 1.0);
    ENSURE(peak > 0.7);
    for (int k = 0; k < 3; ++k) {
        ENSURE_NEAR(mean[k], 0.0, 0.005);
        ENSURE(sqrt(square[k]) > 0.2 && sqrt(square[k]) < 0.4);
    }
    ENSURE_NEAR(cross, 0.0, 0.005);
}

// Continuous (no jumps where the simplex changes): a step of 1e-4 lattice units
// in a random 4D direction never moves a component by more than 2e-3 (the
// steepest slope is about 5 per lattice unit).
TEST(noise_is_continuous)
{
    double worst = 0;
    uint64_t state = 99;
    for (int i = 0; i < 200000; ++i) {
        float q[4], d[4];
        for (int k = 0; k < 4; ++k) {
            state = wx_mix64(state + 1);
            q[k] = (float)((state >> 11) * (1.0 / 9007199254740992.0) * 40.0 - 20.0);
            state = wx_mix64(state + 1);
            d[k] = (float)((state >> 11) * (1.0 / 9007199254740992.0) - 0.5) * 2e-4f;
        }
        float a[3], b[3];
        wx_noise4(3, q[0], q[1], q[2], q[3], a);
        wx_noise4(3, q[0] + d[0], q[1] + d[1], q[2] + d[2], q[3] + d[3], b);
        for (int k = 0; k < 3; ++k) {
            worst = fmax(worst, fabs(a[k] - b[k]));
        }
    }
    ENSURE(worst < 2e-3);
}

// The vectorised block gives the scalar reference (to rounding: the block may
// use fused multiply-adds).
TEST(block_matches_scalar_reference)
{
    wx_field fields[2] = { field(WX_FIELD_TURBULENCE, 2.0f), field(WX_FIELD_WIND, 1.0f) };
    fields[0].frequency = 0.7f;
    fields[0].octaves = 3;
    fields[1].dir[1] = 1;
    wx_forces forces;
    wx_error err;
    ENSURE(wx_forces_init(&forces, fields, 2, 3, &err) == WX_OK);
    float x[WX_PARTICLE_BLOCK], y[WX_PARTICLE_BLOCK], z[WX_PARTICLE_BLOCK];
    float fx[WX_PARTICLE_BLOCK], fy[WX_PARTICLE_BLOCK], fz[WX_PARTICLE_BLOCK];
    for (int k = 0; k < WX_PARTICLE_BLOCK; ++k) {
        x[k] = 0.9f * k - 3;
        y[k] = 0.31f * k;
        z[k] = 1e9f * (k == 5); // far outside: clamped, still finite
    }
    wx_forces_block(&forces, 1.5f, x, y, z, fx, fy, fz);
    for (int k = 0; k < WX_PARTICLE_BLOCK; ++k) {
        float p[3] = { x[k], y[k], z[k] }, f[3];
        wx_turbulence_force(&forces.turbulence[0], p, 1.5f, f);
        ENSURE(fabsf(fx[k]) <= 2.0f && isfinite(fz[k]));
        if (k == 5) {
            continue; // at 1e8 rounding decides everything: only bounded
        }
        ENSURE_NEAR(fx[k], f[0], 1e-4);
        ENSURE_NEAR(fy[k], f[1] + 1.0f, 1e-4);
        ENSURE_NEAR(fz[k], f[2], 1e-4);
    }
    wx_forces_free(&forces);
}

int main(void)
{
    RUN(gravity_and_wind_fold_into_constants);
    RUN(bad_octaves_are_refused);
    RUN(octave_weights_halve_and_sum_to_one);
    RUN(turbulence_is_the_weighted_octave_sum);
    RUN(noise_is_deterministic_and_depends_on_everything);
    RUN(noise_is_bounded_and_zero_mean);
    RUN(noise_is_continuous);
    RUN(block_matches_scalar_reference);
    return ensure_summary();
}
