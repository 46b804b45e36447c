// test_adaptive.c: the gather's adaptive radius (no radius given:
// gather/adaptive.h, docs/mask.md), on a wall of flat quads (gather_fixture.h)
// hit by reproducible Poisson impacts: the noise it aims at, the radius it
// picks, initial dirt, shadow edges, creases and depth jumps.
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "ensure.h"
#include "gather/adaptive.h"
#include "gather/gather.h"
#include "gather_fixture.h"

// ---------------------------------------------------------------------------
// Adaptive smoothing (no radius: gather/adaptive.h, docs/mask.md).

// A reproducible Poisson count of mean `mean` (Knuth's product of uniforms).
static int poisson(uint64_t *state, double mean)
{
    double limit = exp(-mean), product = 1.0;
    int k = -1;
    do {
        *state += 0x9e3779b97f4a7c15ull;
        uint64_t z = *state;
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        z ^= z >> 31;
        product *= (double)(z >> 11) * (1.0 / 9007199254740992.0);
        k++;
    } while (product > limit);
    return k;
}

// Impacts of one unit of dirt each: a Poisson count per texel of mean
// lambda(i, j) on the texels with a surface; dirt = initial + count, hits = count.
typedef double (*rate_fn)(int i, int j);

typedef struct simulated {
    float *initial, *hits;
} simulated;

static simulated simulate_hits(test_maps *in, rate_fn lambda, float initial, uint64_t seed)
{
    size_t n = (size_t)in->w * in->h;
    simulated sim = { calloc(n, sizeof(float)), calloc(n, sizeof(float)) };
    for (int j = 0; j < in->h; ++j) {
        for (int i = 0; i < in->w; ++i) {
            size_t t = (size_t)j * in->w + i;
            if (!isfinite(in->depth[t])) {
                continue;
            }
            int k = poisson(&seed, lambda(i, j));
            sim.initial[t] = initial;
            sim.hits[t] = (float)k;
            in->dirt[t] = initial + (float)k;
        }
    }
    return sim;
}

static float *run_adaptive(const test_maps *out, const test_maps *in, const simulated *sim,
                           float noise, float max_radius, int threads, wx_gather_stats *stats)
{
    wx_gather_view view = view_of(in);
    view.initial = sim != NULL ? sim->initial : NULL;
    view.hits = sim != NULL ? sim->hits : NULL;
    wx_gather_def def = wx_default_gather_def();
    def.target = target_of(out);
    def.inputs = &view;
    def.input_count = 1;
    def.adaptive = true;
    def.noise = noise;
    def.max_radius = max_radius;
    def.threads = threads;
    float *mask = malloc((size_t)out->w * out->h * sizeof(float));
    wx_error err;
    if (wx_gather_compute(&def, mask, stats, &err) != WX_OK) {
        fprintf(stderr, "gather failed: %s\n", err.message);
        free(mask);
        return NULL;
    }
    return mask;
}

// A 12.8 m wall seen head-on by a 128-texel camera: texels of 0.1 m (0.01 m^2).
static wx_camera wall_camera(void)
{
    return make_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 12.8f, 12.8f, 128, 128);
}

static double four_per_texel(int i, int j)
{
    (void)i;
    (void)j;
    return 4.0;
}

// With lambda impacts per texel the radius holds K = 1.5 / noise^2 impacts:
// h = sqrt(K / (pi lambda)) texels (noise 0.04: K = 937.5, h = 8.64 texels for
// lambda 4). The mean density (lambda / 0.01 m^2 = 400 per m^2) is kept, and
// the texel-to-texel scatter drops from 1/sqrt(lambda) = 50% to about the noise
// aimed at (the estimate's own: 1/sqrt(2/3 K) = 4.0%).
TEST(adaptive_noise_follows_the_impacts)
{
    quad wall = big_wall();
    test_maps in = render(wall_camera(), &wall, 1, NULL);
    test_maps out = render(wall_camera(), &wall, 1, NULL);
    simulated sim = simulate_hits(&in, four_per_texel, 0.0f, 7);
    wx_gather_stats st;
    float *mask = run_adaptive(&out, &in, &sim, 0.04f, 3.0f, 2, &st);
    ENSURE(mask != NULL);
    double sum = 0.0, sum2 = 0.0;
    int n = 0;
    for (int j = 16; j < 112; ++j) {
        for (int i = 16; i < 112; ++i) {
            sum += mask[j * 128 + i];
            sum2 += (double)mask[j * 128 + i] * mask[j * 128 + i];
            n++;
        }
    }
    double mean = sum / n, sd = sqrt(sum2 / n - mean * mean);
    free(mask);
    free(sim.initial);
    free(sim.hits);
    maps_free(&in);
    maps_free(&out);
    ENSURE_NEAR(st.target_hits, 937.5, 1e-3);
    ENSURE_NEAR(st.median_radius, 0.864, 0.04);
    ENSURE(st.capped_texels == 0);
    ENSURE_NEAR(mean, 400.0, 400.0 * 0.01);
    ENSURE(sd / mean > 0.025 && sd / mean < 0.055);
}

static double one_per_texel(int i, int j)
{
    (void)i;
    (void)j;
    return 1.0;
}

// Four times fewer impacts: twice the radius (sqrt(937.5 / pi) = 17.3 texels,
// 1.73 m), the same noise; with max_radius below the radius needed, the radius
// stops there and the texels are counted as capped.
TEST(adaptive_radius_doubles_for_a_quarter_of_the_impacts)
{
    quad wall = big_wall();
    test_maps in = render(wall_camera(), &wall, 1, NULL);
    test_maps out = render(wall_camera(), &wall, 1, NULL);
    simulated sim = simulate_hits(&in, one_per_texel, 0.0f, 8);
    wx_gather_stats wide, capped;
    float *a = run_adaptive(&out, &in, &sim, 0.04f, 3.0f, 2, &wide);
    float *b = run_adaptive(&out, &in, &sim, 0.04f, 1.0f, 2, &capped);
    ENSURE(a != NULL && b != NULL);
    double sum = 0.0, sum2 = 0.0;
    int n = 0;
    for (int j = 32; j < 96; ++j) {
        for (int i = 32; i < 96; ++i) {
            sum += a[j * 128 + i];
            sum2 += (double)a[j * 128 + i] * a[j * 128 + i];
            n++;
        }
    }
    double mean = sum / n, sd = sqrt(sum2 / n - mean * mean);
    free(a);
    free(b);
    free(sim.initial);
    free(sim.hits);
    maps_free(&in);
    maps_free(&out);
    ENSURE(wide.capped_texels < 128 * 128 / 50); // near the corners only
    ENSURE_NEAR(wide.median_radius, 1.727, 0.08);
    ENSURE_NEAR(mean, 100.0, 100.0 * 0.02);
    ENSURE(sd / mean > 0.025 && sd / mean < 0.055);
    ENSURE(capped.largest_radius <= 1.0 + 1e-6);
    ENSURE(capped.capped_texels > 128 * 128 / 2);
    // Capped at 1 m, a disc holds (1 / 1.727)^2 of the impacts 4% needs: the
    // noise it keeps is 4% x 1.727 = 6.9% (the note of the gather says so).
    printf("        capped at 1 m: noise %.4f (the median over the capped texels)\n",
           capped.capped_noise);
    ENSURE_NEAR(capped.capped_noise, 0.04 * 1.727, 0.004);
    // Counted in bins (what a TextureMap's note merges over its cameras): every
    // capped texel counted once, and the bins' median within half a bin (a
    // 64th of an octave, 1.09%) of the exact one.
    int64_t binned = 0;
    for (int k = 0; k < WX_NOISE_BINS; ++k) {
        binned += capped.capped_noise_bins[k];
    }
    ENSURE(binned == capped.capped_texels);
    double from_bins = wx_noise_bins_median(capped.capped_noise_bins);
    printf("        the same from the bins: %.4f\n", from_bins);
    ENSURE(fabs(log2(from_bins / capped.capped_noise)) <= 0.5 / WX_NOISE_BINS_PER_OCTAVE + 1e-9);
}

// The noise bins: a 32nd of an octave from 0.1%, everything below in the first
// and everything above in the last; the median is the bin of the element a sort
// puts at count / 2, as the exact median takes it.
TEST(noise_bins_cover_every_noise_and_give_the_median)
{
    ENSURE(wx_noise_bin(0.0) == 0);
    ENSURE(wx_noise_bin(-1.0) == 0);
    ENSURE(wx_noise_bin(NAN) == 0);
    ENSURE(wx_noise_bin(1e300) == WX_NOISE_BINS - 1);
    ENSURE(wx_noise_bin(INFINITY) == WX_NOISE_BINS - 1);
    ENSURE(wx_noise_bin(0.002) == WX_NOISE_BINS_PER_OCTAVE); // one octave above 0.1%
    ENSURE(wx_noise_bin(0.002 * 1.001) == WX_NOISE_BINS_PER_OCTAVE);
    ENSURE(wx_noise_bin(0.002 * 0.999) == WX_NOISE_BINS_PER_OCTAVE - 1);
    int64_t bins[WX_NOISE_BINS] = { 0 };
    ENSURE(wx_noise_bins_median(bins) == 0.0);
    // 0.01, 0.04, 0.04, 0.5: sorted, element 2 is 0.04.
    const double values[] = { 0.5, 0.04, 0.01, 0.04 };
    for (int k = 0; k < 4; ++k) {
        bins[wx_noise_bin(values[k])]++;
    }
    double median = wx_noise_bins_median(bins);
    ENSURE(fabs(log2(median / 0.04)) <= 1.0 / WX_NOISE_BINS_PER_OCTAVE);
    bins[wx_noise_bin(0.5)] += 2; // now 0.01, 0.04, 0.04, 0.5, 0.5, 0.5: element 3
    ENSURE(fabs(log2(wx_noise_bins_median(bins) / 0.5)) <= 1.0 / WX_NOISE_BINS_PER_OCTAVE);
}

static double one_on_the_left_half(int i, int j)
{
    (void)j;
    return i < 64 ? 1.0 : 0.0;
}

// Capped means noisier than aimed at: a texel whose radius stops at max_radius
// with some impact inside it. The same wall with one impact per texel on its
// left half and none on the right, max_radius 1 m (10 texels): every texel of
// the left half is capped (sqrt(937.5 / pi) = 17.3 texels would be needed).
// The right half is not: beside the edge its texels are clean (an empty
// half-disc where their density would have put 12 impacts), and beyond
// 1 m no impact comes near them. Beyond 2 m (the reach of a capped kernel
// from the lit side) it is exactly 0. (Between the clean band and 2 m, the
// lit side's capped kernels leave a faint trace: docs/mask.md, "Adaptive
// smoothing", notes it.)
TEST(adaptive_counts_as_capped_only_what_impacts_reach)
{
    quad wall = big_wall();
    test_maps in = render(wall_camera(), &wall, 1, NULL);
    test_maps out = render(wall_camera(), &wall, 1, NULL);
    simulated sim = simulate_hits(&in, one_on_the_left_half, 0.0f, 9);
    wx_gather_stats st;
    float *mask = run_adaptive(&out, &in, &sim, 0.04f, 1.0f, 2, &st);
    ENSURE(mask != NULL);
    double far = 0.0, near = 0.0, lit = 0.0;
    for (int j = 0; mask != NULL && j < 128; ++j) {
        for (int i = 0; i < 128; ++i) {
            double v = fabs(mask[j * 128 + i]);
            if (i >= 64 + 20) {
                far = fmax(far, v); // beyond twice max_radius: no kernel reaches
            } else if (i >= 64 + 2) {
                near = fmax(near, v);
            } else if (i < 54 && j >= 10 && j < 118) {
                lit += v / (54.0 * 108.0);
            }
        }
    }
    printf("        lit half %.1f per texel; 2-20 texels right of the edge at most %.1f\n", lit,
           near);
    printf("        capped %lld of %lld texels (the left half: %d), far right at most %g\n",
           (long long)st.capped_texels, (long long)st.surface_texels, 128 * 64, far);
    ENSURE(st.capped_texels >= 128 * 64 && st.capped_texels <= 128 * 66);
    ENSURE(far == 0.0);
    free(mask);
    free(sim.initial);
    free(sim.hits);
    maps_free(&in);
    maps_free(&out);
}

// The wall with one impact per texel on its left half and none on its right,
// max_radius 10 texels, the right half unseen by the input camera when asked:
// the mean of the lit half (away from its edges) and the most of the mask 2
// to 20 texels right of the edge (and where). False when it could not run.
static bool beyond_the_edge(bool right_unseen, double *lit, double *near, int *worst)
{
    quad wall = big_wall();
    test_maps in = render(wall_camera(), &wall, 1, NULL);
    test_maps out = render(wall_camera(), &wall, 1, NULL);
    for (int j = 0; right_unseen && j < in.h; ++j) {
        for (int i = in.w / 2; i < in.w; ++i) {
            in.depth[(size_t)j * (size_t)in.w + (size_t)i] = INFINITY;
        }
    }
    simulated sim = simulate_hits(&in, one_on_the_left_half, 0.0f, 9);
    float *mask = run_adaptive(&out, &in, &sim, 0.04f, 1.0f, 2, NULL);
    *lit = *near = 0.0;
    *worst = -1;
    for (int j = 0; mask != NULL && j < 128; ++j) {
        for (int i = 0; i < 128; ++i) {
            double v = fabs(mask[j * 128 + i]);
            if (i >= 64 + 2 && i < 64 + 20 && v > *near) {
                *near = v;
                *worst = j * 128 + i;
            } else if (i < 54 && j >= 10 && j < 118) {
                *lit += v / (54.0 * 108.0);
            }
        }
    }
    bool ran = mask != NULL;
    free(mask);
    free(sim.initial);
    free(sim.hits);
    maps_free(&in);
    maps_free(&out);
    return ran;
}

// A sparse lit side's kernels, capped at max_radius, stop at the clean band
// along its shadow edge: beyond the band (whose half-discs find too few
// impacts to call the shelter further on clean) the kernels reached up to 21%
// of the lit side before 7 December 2026, the thin black slivers inside grey
// on the bunny's ear (docs/mask.md, "Kernels stop at a clean band"). Every
// row, the map's border rows too, from 2 to 20 texels right of the edge: at
// most 0.5% of the lit side.
TEST(adaptive_capped_kernels_stop_at_a_clean_band)
{
    double lit, near;
    int worst;
    ENSURE(beyond_the_edge(false, &lit, &near, &worst));
    printf("        lit half %.1f per texel; 2-20 texels right of the edge at most %.2f (%.2f%%, "
           "texel %d)\n",
           lit, near, 100.0 * near / lit, worst);
    ENSURE(lit > 90.0 && near <= 0.005 * lit);
}

// A gap in what the input cameras see is not a shelter: where the output
// camera sees a surface that no input camera sees (the first pass finds no
// tap), the clean texels beside the lit side do not stop its kernels, which
// reach into the gap as they did before 7 December 2026 (the tank's moss at
// the foot of its body kept a crescent of such texels; with them as stops,
// the strip beyond went dark where a fixed gather shows moss).
TEST(adaptive_a_gap_no_camera_sees_stops_no_kernel)
{
    double lit, near;
    int worst;
    ENSURE(beyond_the_edge(true, &lit, &near, &worst));
    printf("        lit half %.1f per texel; 2-20 texels into the gap at most %.1f (texel %d)\n",
           lit, near, worst);
    ENSURE(lit > 90.0 && near > 0.05 * lit);
}

// The dirt the bake gave (initial) is exact and is never smoothed: a map with
// a sharp pattern of initial dirt and no impacts comes out as the first pass,
// whatever the smoothing; and a map no simulation wrote (no initial, no hits
// planes) is exact the same way.
TEST(adaptive_keeps_the_initial_dirt_exact)
{
    quad wall = big_wall();
    test_maps in = render(wall_camera(), &wall, 1, NULL);
    test_maps out = render(wall_camera(), &wall, 1, NULL);
    simulated sim = { calloc(128 * 128, sizeof(float)), calloc(128 * 128, sizeof(float)) };
    for (size_t t = 0; t < 128 * 128; ++t) {
        in.dirt[t] = sim.initial[t] = (t / 128 + t % 128) % 7 == 0 ? 0.05f : 0.0f;
    }
    float *first = run_gather(&out, &in, 1, 0.0f, WX_SECOND_PASS_MEAN, WX_GATHER_BILINEAR, 1);
    float *a = run_adaptive(&out, &in, &sim, 0.04f, 3.0f, 2, NULL);
    float *b = run_adaptive(&out, &in, NULL, 0.04f, 3.0f, 2, NULL);
    ENSURE(first != NULL && a != NULL && b != NULL);
    bool same = memcmp(first, a, 128 * 128 * sizeof(float)) == 0 &&
                memcmp(first, b, 128 * 128 * sizeof(float)) == 0;
    free(first);
    free(a);
    free(b);
    free(sim.initial);
    free(sim.hits);
    maps_free(&in);
    maps_free(&out);
    ENSURE(same);
}

static double left_half_only(int i, int j)
{
    (void)j;
    return i < 64 ? 4.0 : 0.0;
}

// A shadow edge (rain on the left half of the wall only): the clean half stays
// clean beyond a texel or two of the edge, the lit half keeps its density up
// to the edge, and the rise takes a few texels, not the radius (8.6 texels).
TEST(adaptive_does_not_cross_a_shadow_edge)
{
    quad wall = big_wall();
    test_maps in = render(wall_camera(), &wall, 1, NULL);
    test_maps out = render(wall_camera(), &wall, 1, NULL);
    simulated sim = simulate_hits(&in, left_half_only, 0.0f, 9);
    float *mask = run_adaptive(&out, &in, &sim, 0.04f, 3.0f, 2, NULL);
    ENSURE(mask != NULL);
    double column[128] = { 0 };
    for (int j = 8; j < 120; ++j) {
        for (int i = 0; i < 128; ++i) {
            column[i] += mask[j * 128 + i] / 112.0;
        }
    }
    double clean_max = 0.0, lit = 0.0;
    for (int j = 0; j < 128; ++j) {
        for (int i = 67; i < 128; ++i) {
            clean_max = fmax(clean_max, mask[j * 128 + i]);
        }
    }
    for (int i = 16; i < 60; ++i) {
        lit += column[i] / 44.0;
    }
    int i10 = -1, i90 = -1; // the columns where the profile falls below 90% and 10%
    for (int i = 40; i < 90; ++i) {
        if (i90 < 0 && column[i] < 0.9 * lit) {
            i90 = i;
        }
        if (i10 < 0 && column[i] < 0.1 * lit) {
            i10 = i;
        }
    }
    free(mask);
    free(sim.initial);
    free(sim.hits);
    maps_free(&in);
    maps_free(&out);
    for (int i = 50; i < 70; ++i) {
        fprintf(stderr, " %d:%.0f", i, column[i]);
    }
    fprintf(stderr, "\n");
    ENSURE(clean_max == 0.0);
    ENSURE_NEAR(lit, 400.0, 400.0 * 0.02);
    ENSURE_NEAR(column[62], 400.0, 400.0 * 0.05); // two texels from the edge
    ENSURE(i90 >= 62 && i10 <= 66);
}

// A shadow edge across the grid: rain (4 impacts per texel) on one side of a
// line through the wall's centre at `edge_angle` degrees to the camera's rows.
static double edge_angle;

static double edge_distance(int i, int j) // texels, positive on the dry side
{
    double a = edge_angle * 3.14159265358979323846 / 180.0;
    return (i + 0.5 - 64.0) * cos(a) + (j + 0.5 - 64.0) * sin(a);
}

static double dry_beyond_a_slanted_edge(int i, int j)
{
    return edge_distance(i, j) < 0.0 ? 4.0 : 0.0;
}

// The clean side of a shadow edge reaches the edge whichever way the edge
// crosses the grid: the texels 1.5 to 4.5 texels into the shadow read nothing
// of the lit side, lined up with the rows or at 30 or 45 degrees to them. (The
// four half-rectangles of the clean test until 6 December 2026 fitted a
// slanted edge only some way from it, up to 0.7 times their reach, half the
// radius: that band read 39% of the lit side at 30 degrees and 35% at 45,
// lined up 0%, and turning a model moved the edge of every clean region:
// docs/performance.md.)
TEST(adaptive_shadow_edge_is_clean_at_any_angle_to_the_grid)
{
    static const double angles[3] = { 0.0, 30.0, 45.0 };
    double band[3];
    for (int a = 0; a < 3; ++a) {
        edge_angle = angles[a];
        quad wall = big_wall();
        test_maps in = render(wall_camera(), &wall, 1, NULL);
        test_maps out = render(wall_camera(), &wall, 1, NULL);
        simulated sim = simulate_hits(&in, dry_beyond_a_slanted_edge, 0.0f, 11);
        float *mask = run_adaptive(&out, &in, &sim, 0.04f, 3.0f, 2, NULL);
        ENSURE(mask != NULL);
        double lit = 0.0, dry = 0.0;
        int n_lit = 0, n_dry = 0;
        for (int j = 16; mask != NULL && j < 112; ++j) {
            for (int i = 16; i < 112; ++i) {
                double d = edge_distance(i, j);
                if (d > -30.0 && d < -10.0) {
                    lit += mask[j * 128 + i];
                    n_lit++;
                } else if (d > 1.5 && d < 4.5) {
                    dry += mask[j * 128 + i];
                    n_dry++;
                }
            }
        }
        band[a] = n_lit > 0 && n_dry > 0 ? (dry / n_dry) / (lit / n_lit) : 1.0;
        printf("        edge at %2.0f degrees: 1.5-4.5 texels into the shadow %.4f of the lit "
               "side (%.1f)\n",
               angles[a], band[a], n_lit > 0 ? lit / n_lit : 0.0);
        free(mask);
        free(sim.initial);
        free(sim.hits);
        maps_free(&in);
        maps_free(&out);
    }
    for (int a = 0; a < 3; ++a) {
        ENSURE(band[a] <= 0.01);
    }
}

// The wall ends at column 100, its edge along the camera's rows (a roof's eave
// lined up with the grid, seen from above), and that last column got none of
// the rain (as it did when the wall's camera took the eave's hits: collider.c,
// pick_camera). One empty column with nothing beyond it is no clean region:
// the smoothing fills it from the wall's side. When the clean test counted the
// texel's own column, the whole column read 0 (a texture, which reads the
// camera bilinearly, drew a dark line two of its texels wide that a grid
// turned 30 degrees did not draw).
static double four_but_the_last_column(int i, int j)
{
    (void)j;
    return i < 100 ? 4.0 : 0.0;
}

TEST(adaptive_keeps_an_empty_last_column_of_a_silhouette)
{
    quad wall = big_wall();
    test_maps in = render(wall_camera(), &wall, 1, NULL);
    test_maps out = render(wall_camera(), &wall, 1, NULL);
    for (int j = 0; j < 128; ++j) {
        for (int i = 101; i < 128; ++i) {
            in.depth[j * 128 + i] = out.depth[j * 128 + i] = INFINITY; // beyond the edge
        }
    }
    simulated sim = simulate_hits(&in, four_but_the_last_column, 0.0f, 10);
    float *mask = run_adaptive(&out, &in, &sim, 0.04f, 3.0f, 2, NULL);
    ENSURE(mask != NULL);
    double column[128] = { 0 };
    for (int j = 16; j < 112; ++j) {
        for (int i = 0; i < 128; ++i) {
            column[i] += mask[j * 128 + i] / 96.0;
        }
    }
    free(mask);
    free(sim.initial);
    free(sim.hits);
    maps_free(&in);
    maps_free(&out);
    fprintf(stderr, "        columns 96-101: %.0f %.0f %.0f %.0f %.0f %.0f (lit 400)\n", column[96],
            column[97], column[98], column[99], column[100], column[101]);
    ENSURE(column[101] == 0.0); // no surface
    ENSURE(column[100] > 400.0 * 0.7); // 333 (was 0)
    ENSURE(column[99] > 400.0 * 0.75); // 343 (395)
}

// What the particles left is kept: the mask integrates to the dirt (here over a
// density that rises across the wall) within 1%, and 1 or 2 threads give the
// same bytes.
static double rising(int i, int j)
{
    (void)j;
    return 0.5 + 6.0 * i / 127.0;
}

TEST(adaptive_keeps_the_dirt_and_its_bytes)
{
    quad wall = big_wall();
    test_maps in = render(wall_camera(), &wall, 1, NULL);
    test_maps out = render(wall_camera(), &wall, 1, NULL);
    simulated sim = simulate_hits(&in, rising, 0.0f, 10);
    double dirt = 0.0;
    for (size_t t = 0; t < 128 * 128; ++t) {
        dirt += in.dirt[t];
    }
    float *one = run_adaptive(&out, &in, &sim, 0.04f, 3.0f, 1, NULL);
    float *two = run_adaptive(&out, &in, &sim, 0.04f, 3.0f, 2, NULL);
    ENSURE(one != NULL && two != NULL);
    double integral = 0.0;
    for (size_t t = 0; t < 128 * 128; ++t) {
        integral += one[t] * 0.01; // per square metre times the texel's 0.01 m^2
    }
    bool same = memcmp(one, two, 128 * 128 * sizeof(float)) == 0;
    free(one);
    free(two);
    free(sim.initial);
    free(sim.hits);
    maps_free(&in);
    maps_free(&out);
    ENSURE(same);
    ENSURE_NEAR(integral / dirt, 1.0, 0.01);
}

static double everywhere(int i, int j)
{
    (void)i;
    (void)j;
    return 3.0;
}

// A right-angled ridge (normals at 90 degrees) with impacts on its left face
// only, and a plate 1 m in front of a wall with impacts on the wall only:
// neither the other face nor the plate gets anything.
TEST(adaptive_does_not_cross_creases_or_depth_jumps)
{
    double a = 45.0 * PI / 180.0, c = 2.0 * cos(a), s = 2.0 * sin(a);
    quad ridge[2] = { make_quad(-c, 0, -s, c, 0, s, 0, 5, 0, -sin(a), 0, cos(a)),
                      make_quad(c, 0, -s, c, 0, -s, 0, 5, 0, sin(a), 0, cos(a)) };
    quad plate[2] = { make_quad(0, 0, 1, 1, 0, 0, 0, 5, 0, 0, 0, 1), big_wall() };
    wx_camera cam = make_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 3.2f, 3.2f, 64, 64);
    for (int k = 0; k < 2; ++k) {
        test_maps in = render(cam, k == 0 ? ridge : plate, 2, NULL);
        test_maps out = render(cam, k == 0 ? ridge : plate, 2, NULL);
        simulated sim = simulate_hits(&in, everywhere, 0.0f, 11 + (uint64_t)k);
        for (int t = 0; t < 64 * 64; ++t) {
            // Keep the impacts on the left face, or on the wall (behind the plate).
            bool keep = k == 0 ? t % 64 < 32 : in.depth[t] > 9.5f;
            if (!keep) {
                in.dirt[t] = sim.hits[t] = 0.0f;
            }
        }
        float *mask = run_adaptive(&out, &in, &sim, 0.04f, 1.0f, 2, NULL);
        ENSURE(mask != NULL);
        double leak = 0.0;
        for (int t = 0; t < 64 * 64; ++t) {
            bool other = k == 0 ? t % 64 >= 32 : out.depth[t] < 9.5f;
            leak = other ? fmax(leak, mask[t]) : leak;
        }
        free(mask);
        free(sim.initial);
        free(sim.hits);
        maps_free(&in);
        maps_free(&out);
        ENSURE(leak == 0.0);
    }
}

int main(void)
{
    RUN(adaptive_noise_follows_the_impacts);
    RUN(adaptive_radius_doubles_for_a_quarter_of_the_impacts);
    RUN(noise_bins_cover_every_noise_and_give_the_median);
    RUN(adaptive_counts_as_capped_only_what_impacts_reach);
    RUN(adaptive_capped_kernels_stop_at_a_clean_band);
    RUN(adaptive_a_gap_no_camera_sees_stops_no_kernel);
    RUN(adaptive_keeps_the_initial_dirt_exact);
    RUN(adaptive_does_not_cross_a_shadow_edge);
    RUN(adaptive_shadow_edge_is_clean_at_any_angle_to_the_grid);
    RUN(adaptive_keeps_an_empty_last_column_of_a_silhouette);
    RUN(adaptive_keeps_the_dirt_and_its_bytes);
    RUN(adaptive_does_not_cross_creases_or_depth_jumps);
    return ensure_summary();
}
