// test_emitter.c: emission counts and start states (docs/design.md section 3).
#include <math.h>
#include <string.h>

#include "sim/emitter.h"
#include "ensure.h"
#include "sim/particles.h"
#include "sim_fixture.h"
#include "sim/simulate.h"

static wx_emitter point_emitter(double rate, double start, double end, float speed)
{
    wx_emitter e;
    memset(&e, 0, sizeof e);
    e.kind = WX_EMITTER_POINT;
    e.rate = rate;
    e.start = start;
    e.end = end;
    e.speed = speed;
    e.mass = 1;
    e.load[0] = 1;
    e.max_collisions = 100;
    return e;
}

// floor(rate * (t - start)), t clipped to [start, end]; worked out by hand.
TEST(emission_count_is_floor_of_rate_times_time)
{
    wx_emitter e = point_emitter(1000, 0.05, 1.0, 1);
    ENSURE(wx_emitter_count_at(&e, 0.0) == 0);
    ENSURE(wx_emitter_count_at(&e, 0.05) == 0);
    ENSURE(wx_emitter_count_at(&e, 0.0505) == 0);   // 0.5
    ENSURE(wx_emitter_count_at(&e, 0.0515) == 1);   // 1.5
    ENSURE(wx_emitter_count_at(&e, 29 * 0.01) == 240); // 1000*0.24, decimal time step
    ENSURE(wx_emitter_count_at(&e, 0.5) == 450);
    ENSURE(wx_emitter_count_at(&e, 1.0) == 950);
    ENSURE(wx_emitter_count_at(&e, 7.0) == 950); // rate * (end - start) in all
    wx_emitter slow = point_emitter(333, 0, 1e30, 1);
    ENSURE(wx_emitter_count_at(&slow, 0.1) == 33);  // 33.3
    ENSURE(wx_emitter_count_at(&slow, 0.3) == 99);  // 99.9
    ENSURE(wx_emitter_count_at(&slow, 1.0) == 333);
    // Beyond int64_t: the most there is, never a negative count (the cast of
    // 1e300 overflowed to INT64_MIN, and the memory check passed a run of
    // -9.2e18 particles).
    wx_emitter flood = point_emitter(1e300, 0, 1.0, 1);
    ENSURE(wx_emitter_count_at(&flood, 0.5) == INT64_MAX);
    flood.rate = 1e19;
    ENSURE(wx_emitter_count_at(&flood, 1.0) == INT64_MAX);
}

// The simulation emits exactly that many, step after step.
TEST(simulation_emits_floor_counts)
{
    fx_scene f;
    fx_scene_init(&f);
    wx_emitter *e = fx_emitter(&f, WX_EMITTER_POINT, 0, 0, 0);
    e->rate = 333;
    e->start = 0.1;
    e->end = 0.75;
    wx_sim_def cfg = wx_default_sim_def(&f.scene);
    cfg.threads = 1;
    wx_sim *sim = NULL;
    wx_error err;
    ENSURE(wx_sim_create(&f.scene, &cfg, &sim, &err) == WX_OK);
    int ok = 1;
    for (int k = 1; k <= 100; ++k) {
        ENSURE(wx_sim_step(sim, &err) == WX_OK);
        wx_sim_stats st;
        wx_sim_get_stats(sim, &st);
        double t = k * 0.01;
        double until = t < 0.75 ? t : 0.75;
        int64_t expect = until > 0.1 ? (int64_t)floor(333 * (until - 0.1) + 1e-9) : 0;
        ok &= st.particles_emitted == expect;
        if (k == 30) {
            ok &= st.particles_emitted == 66; // 333 * 0.2 = 66.6
        }
    }
    wx_sim_stats st;
    wx_sim_get_stats(sim, &st);
    wx_sim_destroy(sim);
    ENSURE(ok);
    ENSURE(st.particles_emitted == 216); // floor(333 * 0.65) = floor(216.45)
    ENSURE(st.alive == 216);             // no gravity, no cameras: nobody leaves
    ENSURE_NEAR(st.dirt_emitted, 216.0, 0.0);
}

// Uniform directions: every component averages 0 and its square 1/3.
TEST(point_emitter_directions_are_uniform)
{
    wx_emitter e = point_emitter(1, 0, 1, 2.0f);
    e.center[0] = 1;
    e.center[1] = 2;
    e.center[2] = 3;
    enum { N = 200000 };
    double mean[3] = { 0 }, square[3] = { 0 };
    int bad = 0;
    for (int i = 0; i < N; ++i) {
        float p[3], v[3];
        wx_emitter_sample(&e, 7, wx_particle_id(0, (uint64_t)i), p, v);
        bad += p[0] != 1 || p[1] != 2 || p[2] != 3;
        double len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        bad += fabs(len - 2.0) > 1e-5;
        for (int k = 0; k < 3; ++k) {
            mean[k] += v[k] / 2.0 / N;
            square[k] += v[k] * v[k] / 4.0 / N;
        }
    }
    ENSURE(bad == 0);
    for (int k = 0; k < 3; ++k) {
        ENSURE_NEAR(mean[k], 0.0, 0.006); // 5 sigma of 1/sqrt(3N)
        ENSURE_NEAR(square[k], 1.0 / 3.0, 0.004);
    }
    // Half the directions in each half-space through the centre, for any axis.
    int upper = 0;
    for (int i = 0; i < N; ++i) {
        float p[3], v[3];
        wx_emitter_sample(&e, 7, wx_particle_id(0, (uint64_t)i), p, v);
        upper += v[0] + v[1] + v[2] > 0;
    }
    ENSURE_NEAR(upper / (double)N, 0.5, 0.006);
}

TEST(point_emitter_speed_zero_drops_at_rest)
{
    wx_emitter e = point_emitter(1, 0, 1, 0.0f);
    float p[3], v[3];
    wx_emitter_sample(&e, 1, wx_particle_id(0, 5), p, v);
    ENSURE(v[0] == 0 && v[1] == 0 && v[2] == 0);
}

// Sky dome: on the sphere of radius r above the centre, moving towards it; the
// height of a uniform point on the hemisphere averages 1/2.
TEST(hemisphere_emitter_rains_towards_its_centre)
{
    wx_emitter e = point_emitter(1, 0, 1, 3.0f);
    e.kind = WX_EMITTER_HEMISPHERE;
    e.radius = 20;
    e.center[1] = -1;
    enum { N = 100000 };
    double mean_y = 0, mean_x = 0;
    int bad = 0;
    for (int i = 0; i < N; ++i) {
        float p[3], v[3];
        wx_emitter_sample(&e, 3, wx_particle_id(2, (uint64_t)i), p, v);
        float d[3] = { p[0] / 20, (p[1] + 1) / 20, p[2] / 20 };
        bad += !(d[1] > 0);
        bad += fabs(sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) - 1) > 1e-5;
        for (int k = 0; k < 3; ++k) {
            bad += fabsf(v[k] + 3.0f * d[k]) > 1e-4f;
        }
        mean_y += d[1] / N;
        mean_x += d[0] / N;
    }
    ENSURE(bad == 0);
    ENSURE_NEAR(mean_y, 0.5, 0.005);
    ENSURE_NEAR(mean_x, 0.0, 0.007);
}

static wx_emitter box_emitter(const float lo[3], const float hi[3], const float dir[3],
                              float spread, float speed)
{
    wx_emitter e = point_emitter(1, 0, 1, speed);
    e.kind = WX_EMITTER_BOX;
    for (int k = 0; k < 3; ++k) {
        e.box_min[k] = lo[k];
        e.box_max[k] = hi[k];
        e.dir[k] = dir[k];
    }
    e.spread = spread;
    return e;
}

// docs/design.md section 8: start points uniform in the box, a flat axis exact;
// with spread 0 every particle moves at speed * dir.
TEST(box_emitter_starts_uniform_in_its_box)
{
    const float lo[3] = { -5, 12, -2 }, hi[3] = { 5, 12, 4 }, down[3] = { 0, -1, 0 };
    wx_emitter e = box_emitter(lo, hi, down, 0, 5);
    enum { N = 100000, BINS = 10 };
    int bins[BINS] = { 0 }, bad = 0;
    double mean_x = 0, mean_z = 0, var_x = 0;
    for (int i = 0; i < N; ++i) {
        float p[3], v[3];
        wx_emitter_sample(&e, 7, wx_particle_id(1, (uint64_t)i), p, v);
        bad += p[1] != 12.0f || !(p[0] >= -5 && p[0] < 5) || !(p[2] >= -2 && p[2] < 4);
        bad += v[0] != 0.0f || v[1] != -5.0f || v[2] != 0.0f;
        mean_x += p[0] / N;
        mean_z += p[2] / N;
        var_x += (double)p[0] * p[0] / N;
        int b = (int)floorf((p[0] + 5) / 10 * BINS);
        bins[b < 0 ? 0 : b >= BINS ? BINS - 1 : b]++;
    }
    ENSURE(bad == 0);
    // Uniform on [-5, 5]: mean 0, variance 100/12 (standard errors 0.009, 0.02).
    ENSURE_NEAR(mean_x, 0.0, 0.04);
    ENSURE_NEAR(mean_z, 1.0, 0.025);
    ENSURE_NEAR(var_x, 100.0 / 12.0, 0.1);
    for (int b = 0; b < BINS; ++b) {
        ENSURE_NEAR(bins[b], N / BINS, 400); // sd 95
    }
}

// Spread s: directions uniform over the cone's solid angle, so cos(theta) is
// uniform on [cos s, 1]: its mean is (1 + cos s) / 2, half of the directions lie
// within cos(theta) > (1 + cos s) / 2, and the mean direction is that times
// the axis (the cone is symmetric about it).
TEST(box_emitter_cone_is_uniform_in_solid_angle)
{
    const float lo[3] = { 0, 0, 0 }, hi[3] = { 1, 1, 1 };
    const float axis[3] = { 1.0f / 3, -2.0f / 3, 2.0f / 3 };
    wx_emitter e = box_emitter(lo, hi, axis, 30, 2);
    const double cos_s = cos(30.0 * 3.14159265358979323846 / 180.0), half = (1 + cos_s) / 2;
    enum { N = 200000 };
    double mean_cos = 0, mean_d[3] = { 0, 0, 0 };
    int inner = 0, bad = 0;
    for (int i = 0; i < N; ++i) {
        float p[3], v[3];
        wx_emitter_sample(&e, 11, wx_particle_id(0, (uint64_t)i), p, v);
        double d[3] = { v[0] / 2.0, v[1] / 2.0, v[2] / 2.0 };
        double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        double c = d[0] * axis[0] + d[1] * axis[1] + d[2] * axis[2];
        bad += fabs(len - 1) > 1e-5 || c < cos_s - 1e-6;
        mean_cos += c / N;
        inner += c > half;
        for (int k = 0; k < 3; ++k) {
            mean_d[k] += d[k] / N;
        }
    }
    ENSURE(bad == 0);
    ENSURE_NEAR(mean_cos, half, 2e-4); // sd 4.3e-5
    ENSURE_NEAR(inner, N / 2, 700);    // sd 224
    for (int k = 0; k < 3; ++k) {
        ENSURE_NEAR(mean_d[k], half * axis[k], 2e-3);
    }
}

// The flux of section 8: with spread 0 and no forces, a flat box of area A
// sends N / A particles through each square metre of every plane parallel to
// it, whatever the direction. 16000 particles from a 4 m x 4 m rectangle 2 m
// above a floor seen by a 40-texel top camera (texels of 0.25 m, the square's
// edges on texel edges): every particle lands (absorption 1), inside the
// rectangle's shadow only, 62.5 per texel on average with Poisson scatter.
TEST(box_emitter_puts_n_over_a_on_each_square_metre)
{
    const float tilted[3] = { 0.6f, -0.8f, 0.0f }, down[3] = { 0, -1, 0 };
    const float *dirs[2] = { down, tilted };
    const double shift[2] = { 0.0, 2.0 / 0.8 * 0.6 }; // 1.5 m along x when tilted
    for (int t = 0; t < 2; ++t) {
        fx_scene f;
        fx_scene_init(&f);
        fx_world world = { 0 };
        fx_box(&world, -5, -1, -5, 5, 0, 5);
        world.absorption = 1;
        world.deposit = 1;
        fx_add_camera(&f, "top", fx_camera(0, 10, 0, 0, 0, 0, 0, 0, -1, 10, 40), &world);
        wx_emitter *e = fx_emitter(&f, WX_EMITTER_BOX, 0, 0, 0);
        const float lo[3] = { -2, 2, -2 }, hi[3] = { 2, 2, 2 };
        *e = box_emitter(lo, hi, dirs[t], 0, 5);
        e->rate = 16000;
        wx_sim_def cfg = wx_default_sim_def(&f.scene);
        cfg.threads = 2;
        cfg.maps = f.maps;
        wx_sim *sim = NULL;
        wx_error err;
        ENSURE(wx_sim_create(&f.scene, &cfg, &sim, &err) == WX_OK);
        bool ok = true;
        for (int k = 0; k < 160 && ok; ++k) { // 1 s of emission, 0.5 s of fall
            ok = wx_sim_step(sim, &err) == WX_OK;
        }
        wx_sim_stats st;
        wx_sim_get_stats(sim, &st);
        const wx_dirt_map *m = wx_sim_dirt_map(sim, 0);
        double inside = 0, outside = 0, sum_sq = 0;
        int n_inside = 0;
        for (int j = 0; j < 40; ++j) {
            for (int i = 0; i < 40; ++i) {
                double x = -5 + 0.25 * (i + 0.5), z = 5 - 0.25 * (j + 0.5);
                double dirt = m->texels[j * 40 + i].dirt;
                if (fabs(x - shift[t]) < 2 && fabs(z) < 2) {
                    inside += dirt;
                    sum_sq += dirt * dirt;
                    n_inside++;
                } else {
                    outside += dirt;
                }
            }
        }
        wx_sim_destroy(sim);
        fx_scene_free(&f);
        ENSURE(ok);
        ENSURE(st.particles_emitted == 16000 && st.absorbed == 16000 && st.alive == 0);
        ENSURE(n_inside == 256);
        ENSURE_NEAR(inside, 16000.0, 1e-6); // 1000 per square metre, all of it
        ENSURE(outside == 0.0);
        double mean = inside / n_inside, var = sum_sq / n_inside - mean * mean;
        ENSURE_NEAR(mean, 62.5, 1e-9);
        // Low-discrepancy starts (wx_emitter_uniforms): the counts per texel
        // spread far less than independent draws' multinomial counts
        // (variance 62.3): a tenth of that at most.
        ENSURE(var < 0.1 * 62.5 * (1 - 1.0 / 256));
    }
}

// A particle's start depends only on seed and id.
TEST(samples_depend_on_seed_and_id_only)
{
    wx_emitter e = point_emitter(1, 0, 1, 1.0f);
    float p1[3], v1[3], p2[3], v2[3], p3[3], v3[3], p4[3], v4[3];
    wx_emitter_sample(&e, 9, wx_particle_id(1, 42), p1, v1);
    wx_emitter_sample(&e, 9, wx_particle_id(1, 43), p3, v3);
    wx_emitter_sample(&e, 9, wx_particle_id(1, 42), p2, v2);
    wx_emitter_sample(&e, 10, wx_particle_id(1, 42), p4, v4);
    ENSURE(memcmp(v1, v2, sizeof v1) == 0);
    ENSURE(memcmp(v1, v3, sizeof v1) != 0);
    ENSURE(memcmp(v1, v4, sizeof v1) != 0);
}

int main(void)
{
    RUN(emission_count_is_floor_of_rate_times_time);
    RUN(simulation_emits_floor_counts);
    RUN(point_emitter_directions_are_uniform);
    RUN(point_emitter_speed_zero_drops_at_rest);
    RUN(hemisphere_emitter_rains_towards_its_centre);
    RUN(box_emitter_starts_uniform_in_its_box);
    RUN(box_emitter_cone_is_uniform_in_solid_angle);
    RUN(box_emitter_puts_n_over_a_on_each_square_metre);
    RUN(samples_depend_on_seed_and_id_only);
    return ensure_summary();
}
