// noise.c: the Noise mask's noise and its rank remap (noise.h).
#include "sim/noise.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static uint64_t mix(uint64_t x)
{
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

// Perlin's 12 gradients: the edges' midpoints of a cube.
static const signed char gradients[12][3] = {
    { 1, 1, 0 },  { -1, 1, 0 },  { 1, -1, 0 }, { -1, -1, 0 }, { 1, 0, 1 },  { -1, 0, 1 },
    { 1, 0, -1 }, { -1, 0, -1 }, { 0, 1, 1 },  { 0, -1, 1 },  { 0, 1, -1 }, { 0, -1, -1 },
};

static double fade(double t)
{
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

// The dot of lattice point (x, y, z)'s gradient, hashed with key, and the
// offset (dx, dy, dz) from it.
static double corner(uint64_t key, int64_t x, int64_t y, int64_t z, double dx, double dy, double dz)
{
    uint64_t h = mix(mix(mix(key ^ (uint64_t)x) ^ (uint64_t)y) ^ (uint64_t)z);
    const signed char *g = gradients[(h >> 32) % 12u];
    return g[0] * dx + g[1] * dy + g[2] * dz;
}

static double lerp(double a, double b, double t)
{
    return a + t * (b - a);
}

// Improved Perlin noise (Perlin 2002) of q with the lattice keyed by `key`.
static double perlin(const double q[3], uint64_t key)
{
    double f[3], d[3], u[3];
    int64_t i[3];
    for (int k = 0; k < 3; ++k) {
        // Far beyond any scene's lattice (a frequency of 1e6 at 2^15 per
        // octave) the cell is clamped: the cast stays defined.
        f[k] = fmax(-4.0e18, fmin(4.0e18, floor(q[k])));
        i[k] = (int64_t)f[k];
        d[k] = q[k] - f[k];
        u[k] = fade(d[k]);
    }
    double c[2][2][2];
    for (int a = 0; a < 2; ++a) {
        for (int b = 0; b < 2; ++b) {
            for (int e = 0; e < 2; ++e) {
                c[a][b][e] =
                    corner(key, i[0] + a, i[1] + b, i[2] + e, d[0] - a, d[1] - b, d[2] - e);
            }
        }
    }
    double x00 = lerp(c[0][0][0], c[1][0][0], u[0]), x10 = lerp(c[0][1][0], c[1][1][0], u[0]);
    double x01 = lerp(c[0][0][1], c[1][0][1], u[0]), x11 = lerp(c[0][1][1], c[1][1][1], u[0]);
    return lerp(lerp(x00, x10, u[1]), lerp(x01, x11, u[1]), u[2]);
}

double wx_noise_fbm(const double p[3], double frequency, int octaves, double gain, uint64_t seed)
{
    double sum = 0.0, amplitude = 1.0, scale = frequency;
    for (int o = 0; o < octaves; ++o) {
        double q[3] = { p[0] * scale, p[1] * scale, p[2] * scale };
        sum += amplitude * perlin(q, mix(seed ^ mix((uint64_t)o + 0x51ed27u)));
        amplitude *= gain;
        scale *= 2.0;
    }
    return sum;
}

double wx_noise_raw(const wx_mask_def *mask, const double p[3])
{
    return wx_noise_fbm(p, mask->frequency, mask->octaves, mask->gain, mask->noise_seed);
}

typedef struct weighted {
    double raw, weight;
} weighted;

static int by_raw(const void *a, const void *b)
{
    const weighted *x = a, *y = b;
    return (x->raw > y->raw) - (x->raw < y->raw);
}

wx_result wx_noise_table_build(const wx_mask_def *mask, const double *points, const double *weight,
                               size_t count, double *table, wx_error *err)
{
    const int K = WX_NOISE_TABLE_SIZE;
    weighted *w = malloc((count + 1) * sizeof *w);
    if (w == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "noise: out of memory (%zu points)", count);
    }
    size_t n = 0;
    double total = 0.0;
    for (size_t k = 0; k < count; ++k) {
        double wk = weight != NULL ? weight[k] : 1.0;
        if (!(wk > 0.0) || !isfinite(wk)) {
            continue;
        }
        w[n].raw = wx_noise_raw(mask, &points[3 * k]);
        w[n].weight = wk;
        total += wk;
        n++;
    }
    if (n == 0) {
        for (int k = 0; k < K; ++k) {
            table[k] = -1.0 + 2.0 * (double)k / (double)(K - 1);
        }
        free(w);
        return WX_OK;
    }
    // Ties keep their values apart only by their raw value: any order of
    // equal raw values gives the same table.
    qsort(w, n, sizeof *w, by_raw);
    // Sample s stands for the weight around its own centre, at cumulative
    // fraction (before + weight / 2) / total; quantile c lies between the two
    // samples whose centres bracket it (beyond the ends: the end's value).
    size_t s = 0;
    double before = 0.0; // weight of the samples before s
    double cs = 0.5 * w[0].weight / total;
    for (int k = 0; k < K; ++k) {
        double c = (double)k / (double)(K - 1);
        double cn = 2.0;
        while (s + 1 < n && (cn = (before + w[s].weight + 0.5 * w[s + 1].weight) / total) <= c) {
            before += w[s].weight;
            s++;
            cs = cn;
        }
        if (c <= cs || s + 1 >= n) {
            table[k] = w[s].raw;
        } else {
            table[k] = lerp(w[s].raw, w[s + 1].raw, (c - cs) / (cn - cs));
        }
    }
    table[0] = w[0].raw;
    table[K - 1] = w[n - 1].raw;
    free(w);
    return WX_OK;
}

float wx_noise_remap(const double *table, double raw)
{
    const int K = WX_NOISE_TABLE_SIZE;
    if (!(raw > table[0])) {
        return 0.0f;
    }
    if (!(raw < table[K - 1])) {
        return 1.0f;
    }
    // The last entry <= raw: table[lo] <= raw < table[hi].
    int lo = 0, hi = K - 1;
    while (hi - lo > 1) {
        int mid = lo + (hi - lo) / 2;
        if (table[mid] <= raw) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    double span = table[hi] - table[lo];
    double t = span > 0.0 ? (raw - table[lo]) / span : 0.0;
    return (float)fmin(1.0, fmax(0.0, ((double)lo + t) / (double)(K - 1)));
}

size_t wx_noise_sample_meshes(const wx_mesh_data *const *meshes, int count, size_t samples,
                              double *out)
{
    double total = 0.0;
    for (int pass = 0; pass < 2; ++pass) {
        // Pass 0 sums the area; pass 1 walks it again, dropping sample k at
        // cumulative area (k + 1/2) / samples of the total.
        double cumulative = 0.0;
        size_t k = 0;
        for (int m = 0; m < count; ++m) {
            const wx_mesh_data *d = meshes[m];
            for (int64_t t = 0; d->positions != NULL && t < d->triangle_count; ++t) {
                double v[3][3];
                for (int c = 0; c < 3; ++c) {
                    const float *p = &d->positions[3 * (size_t)d->indices[3 * t + c]];
                    for (int a = 0; a < 3; ++a) {
                        v[c][a] = d->origin[a] + p[a];
                    }
                }
                double e1[3], e2[3];
                for (int a = 0; a < 3; ++a) {
                    e1[a] = v[1][a] - v[0][a];
                    e2[a] = v[2][a] - v[0][a];
                }
                double cx = e1[1] * e2[2] - e1[2] * e2[1], cy = e1[2] * e2[0] - e1[0] * e2[2],
                       cz = e1[0] * e2[1] - e1[1] * e2[0];
                double area = 0.5 * sqrt(cx * cx + cy * cy + cz * cz);
                if (!(area > 0.0) || !isfinite(area)) {
                    continue;
                }
                cumulative += area;
                while (pass == 1 && k < samples &&
                       ((double)k + 0.5) / (double)samples * total < cumulative) {
                    // Uniform in the triangle: sqrt of the first number.
                    uint64_t h = mix((uint64_t)k * 0x9e3779b97f4a7c15ull + 0x2545f491u);
                    double r1 = sqrt((double)(h >> 11) * (1.0 / 9007199254740992.0));
                    double r2 = (double)(mix(h) >> 11) * (1.0 / 9007199254740992.0);
                    double a = 1.0 - r1, b = r1 * (1.0 - r2), c = r1 * r2;
                    for (int x = 0; x < 3; ++x) {
                        out[3 * k + x] = a * v[0][x] + b * v[1][x] + c * v[2][x];
                    }
                    k++;
                }
            }
        }
        if (pass == 0) {
            total = cumulative;
            if (!(total > 0.0)) {
                return 0;
            }
        } else {
            return k;
        }
    }
    return 0;
}
