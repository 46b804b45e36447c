// block_rms.h: how much two images of one layout differ at a block size: the
// measure issue 25 asks for when it sets two seeds (the noise) against two
// runs that should agree, used by tests/tools/texture_compare.c and the tests.
// Over the texels both images mark `seen` (every texel when a `seen` plane is
// NULL) and where both values are finite, the values are averaged in blocks of
// k x k texels (a block counts when at least half of it is common); the RMS of
// the blocks' differences is set against the mean of both images over the
// common texels.
#ifndef WX_BLOCK_RMS_H
#define WX_BLOCK_RMS_H

#include <math.h>
#include <stdbool.h>

static inline bool wx_block_common(const float *a, const float *b, const float *seen_a,
                                   const float *seen_b, long i)
{
    bool seen = (seen_a == NULL || seen_a[i] > 0.5f) && (seen_b == NULL || seen_b[i] > 0.5f);
    return seen && isfinite(a[i]) && isfinite(b[i]);
}

/// The mean of both images over their common texels, and how many there are.
static inline double wx_block_mean(const float *a, const float *b, const float *seen_a,
                                   const float *seen_b, int w, int h, long *count)
{
    double sum = 0.0;
    long n = 0;
    for (long i = 0; i < (long)w * h; ++i) {
        if (wx_block_common(a, b, seen_a, seen_b, i)) {
            sum += 0.5 * ((double)a[i] + (double)b[i]);
            n++;
        }
    }
    if (count != NULL) {
        *count = n;
    }
    return n > 0 ? sum / (double)n : 0.0;
}

/// The RMS of the k x k blocks' differences (0 without a block); *blocks gets
/// how many blocks counted (may be NULL).
static inline double wx_block_rms(const float *a, const float *b, const float *seen_a,
                                  const float *seen_b, int w, int h, int k, long *blocks)
{
    double sq = 0.0;
    long counted = 0;
    for (int by = 0; by + k <= h; by += k) {
        for (int bx = 0; bx + k <= w; bx += k) {
            double da = 0.0, db = 0.0;
            int n = 0;
            for (int y = by; y < by + k; ++y) {
                for (int x = bx; x < bx + k; ++x) {
                    long i = (long)y * w + x;
                    if (wx_block_common(a, b, seen_a, seen_b, i)) {
                        da += a[i];
                        db += b[i];
                        n++;
                    }
                }
            }
            if (2 * n >= k * k && n > 0) {
                double d = (da - db) / n;
                sq += d * d;
                counted++;
            }
        }
    }
    if (blocks != NULL) {
        *blocks = counted;
    }
    return counted > 0 ? sqrt(sq / (double)counted) : 0.0;
}

#endif
