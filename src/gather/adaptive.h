// adaptive.h: the gather's smoothing when <OutputMap> gives no radius: a
// kernel whose radius follows the local density of impacts (docs/mask.md,
// "Adaptive smoothing"; docs/design.md section 5.2).
//
// What it smooths is what the particles changed, never the initial dirt (exact
// from the bake): delta = first-pass dirt - first-pass initial dirt, per unit
// area. Every target texel p with a surface is a sample with a radius h_p, the
// distance within which the target holds K = 1.5 / noise^2 impacts (photon
// mapping's k-nearest estimate; 1.5 because the cone kernel's effective count
// is 2/3 of the disc's), between one texel and max_radius. The estimate at q is
// the mean of the samples whose kernels reach it (a sample-point estimate):
//
//     out_q = initial_q + sum_p w_p K_p(q) delta_p / sum_p w_p K_p(q),
//     K_p(q) = (1 - r_pq / h_p) * max(0, N_p . N_q) * [q lies on p's tangent plane],
//     w_p = 1 / h_p^2   (each kernel weighs the same in all),
//
// r_pq the world distance between the two points. A dense region keeps its
// detail (small h), a sparse one becomes smooth (large h), a constant change
// stays constant up to every border, and nothing crosses a crease (the
// normals), a depth jump (the distance and the plane test) or a shadow edge: a
// texel with no impact of its own beside an empty half-disc where its
// density would have put 12 impacts is clean, and neither gives nor takes;
// nor does a kernel reach past a clean texel on its way (a sample gives
// nothing to a texel when a clean texel lies on the line of texels between
// them), so a thin clean band stops the capped kernels of a sparse side.
//
// Computed as a gather over q, in rows on the pool: the same result for any
// number of threads.
#ifndef WX_ADAPTIVE_H
#define WX_ADAPTIVE_H

#include <stdint.h>

#include "core/error.h"
#include "core/parallel.h"

/// Bins of capped_noise_bins (wx_noise_bin): 0.1% to 6 550%.
#define WX_NOISE_BINS            512
#define WX_NOISE_BIN_LOW         0.001
#define WX_NOISE_BINS_PER_OCTAVE 32

/// The inputs, views into memory the caller owns. Planes are width*height, row 0
/// at the top; texels without a surface have depth +inf (model/maps.h).
typedef struct wx_adaptive_def {
    int width, height;
    const float *depth;   ///< the target's depth d
    const float *normal;  ///< interleaved unit normals
    const float *total;   ///< first pass: dirt per unit area
    const float *initial; ///< first pass: initial dirt per unit area
    /// First pass: impacts per unit area; negative where no input camera sees
    /// the surface point (a gap: its clean texels stop no kernel).
    const float *hits;
    /// World offset of one texel step in i (right) and j (down), and of one unit
    /// of depth (the viewing direction, a unit vector for orthographic targets).
    double step_i[3], step_j[3], step_d[3];
    float noise;          ///< relative standard deviation aimed at, > 0
    float max_radius;     ///< world units, at least one texel
    wx_pool *pool;        ///< may be NULL: serial
} wx_adaptive_def;

/// What the smoothing chose, for --stats and the tests.
typedef struct wx_adaptive_stats {
    double target_hits;     ///< K
    double median_radius;   ///< over the texels that hold what the particles changed (world units)
    double max_radius_used; ///< largest radius given to such a texel
    /// Such texels whose K impacts lie beyond max_radius, with some impact
    /// within it (a surface no impact comes near is not noisy, only unreached).
    int64_t capped;
    /// The noise those texels keep (relative standard deviation, as `noise`:
    /// noise x sqrt(K' / the impacts within max_radius)), the median over
    /// them; 0 when none is capped.
    double capped_noise;
    /// The same texels counted by their noise (wx_noise_bin), so that several
    /// gathers' capped texels (a TextureMap's input cameras) give one median.
    int64_t capped_noise_bins[WX_NOISE_BINS];
} wx_adaptive_stats;

/// The bin of a noise (relative standard deviation) in capped_noise_bins:
/// bins a 32nd of an octave wide (2.2%) from 0.1%, the first and the last
/// holding everything below and above.
int wx_noise_bin(double noise);

/// The median noise of the texels counted in bins (the geometric middle of its
/// bin); 0 when the bins are empty.
double wx_noise_bins_median(const int64_t bins[WX_NOISE_BINS]);

/// Writes the smoothed mask (dirt per unit area: the initial dirt exactly plus
/// the smoothed change) into out[width*height]; 0 where there is no surface.
/// WX_FAIL when out of memory.
wx_result wx_adaptive_smooth(const wx_adaptive_def *def, float *out, wx_adaptive_stats *stats,
                             wx_error *err);

#endif
