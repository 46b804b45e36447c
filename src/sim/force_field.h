// force_field.h: the force fields of a scene (thesis 3.7, 4.8.2): gravity
// (an acceleration along -Y), wind (a constant force) and Perlin turbulence of
// position and time.
//
// Turbulence: three independent noise fields (one per force component) of the
// 4D point q = f*(x, y, z, t), with t in seconds read as metres (the pattern
// changes on the time scale 1/f). The noise is Perlin's simplex noise in 4D
// (five corners per sample instead of sixteen for 4D gradient noise on a cube
// lattice), with gradients picked by an integer hash of the corner (no
// permutation table: table gathers are slow here, hashing vectorises); one hash
// per corner feeds all three components. Each octave is scaled into [-1, 1]
// (clamped; the clamp is almost never active). Octave o has frequency f*2^o and
// weight 2^-o / sum_k 2^-k (the weights sum to 1), so the turbulence is a
// weighted sum of octaves that attenuates the high frequencies (thesis 3.7) and
// stays in [-1, 1]. The force is strength times that vector.
#ifndef WX_FORCE_FIELD_H
#define WX_FORCE_FIELD_H

#include <stdbool.h>
#include <stdint.h>

#include "core/error.h"
#include "model/scene.h"

#define WX_MAX_OCTAVES 16

/// Forces inlining into a vectorised loop (gcc vectorises only inlined bodies).
#define WX_INLINE static inline __attribute__((always_inline))

/// Hot per-block kernels are compiled for baseline x86-64 (SSE2) and for AVX2+FMA
/// and AVX-512 machines, chosen once at load time (gcc function multiversioning).
/// The choice is fixed for a machine, so results do not depend on thread count.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(WX_NO_CLONES)
#define WX_HOT __attribute__((target_clones("default", "arch=x86-64-v3", "arch=x86-64-v4")))
#else
#define WX_HOT
#endif

/// Whether the hot kernels (WX_HOT) of this build, on this machine, fuse
/// multiply-adds into one rounding. It is what makes a simulation's last bits
/// differ between machines and builds (a baseline x86-64 CPU or an -O1 build
/// does not fuse): same-build, same-machine runs stay identical for any thread
/// count either way. Tests pin the simulation's hash per answer.
bool wx_kernels_fuse_multiply_add(void);

typedef struct wx_turbulence {
    float strength;  ///< force scale (N)
    float frequency; ///< frequency of octave 0 (1/m in space, 1/s in time)
    int octaves;     ///< 1..WX_MAX_OCTAVES
    uint32_t seed;   ///< hash seed (from the scene seed and the field's index)
    float weight[WX_MAX_OCTAVES]; ///< octave weights, sum 1
} wx_turbulence;

/// Every field of a scene folded into what the step needs.
typedef struct wx_forces {
    float gravity[3]; ///< acceleration: sum of Gravity fields along -Y
    float wind[3];    ///< force: sum of Wind fields
    int turbulence_count;
    wx_turbulence *turbulence;
} wx_forces;

/// Builds the forces of `fields`; `seed` decorrelates the turbulence of different
/// seeds. Fails (WX_BAD_INPUT) on an octave count outside 1..WX_MAX_OCTAVES or a
/// non-finite value, WX_FAIL when out of memory.
wx_result wx_forces_init(wx_forces *forces, const wx_field *fields, int count, uint64_t seed,
                         wx_error *err);

/// Frees what wx_forces_init allocated; the struct is zeroed.
void wx_forces_free(wx_forces *forces);

/// Weight of octave `o` of `octaves`: 2^-o / sum_{k<octaves} 2^-k.
float wx_turbulence_weight(int o, int octaves);

/// One octave: the three noise components at the 4D point (x, y, z, t), each in
/// [-1, 1], zero on average (rms about 0.25), smooth in every coordinate.
void wx_noise4(uint32_t seed, float x, float y, float z, float t, float out[3]);

/// Octave o of a turbulence field at point p and time t, unweighted: the noise
/// at frequency f*2^o (with the octave's own seed and lattice offset).
void wx_turbulence_octave(const wx_turbulence *turb, int o, const float p[3], float t,
                          float out[3]);

/// The turbulence force of one field at point p and time t: strength times
/// sum_o weight[o] * octave o (the scalar reference of wx_forces_block).
void wx_turbulence_force(const wx_turbulence *turb, const float p[3], float t, float out[3]);

/// Forces (without gravity, which is an acceleration) on WX_PARTICLE_BLOCK particles
/// at positions x, y, z and time t: wind plus every turbulence field.
void wx_forces_block(const wx_forces *forces, float t, const float *restrict x,
                     const float *restrict y, const float *restrict z, float *restrict fx,
                     float *restrict fy, float *restrict fz);

#endif
