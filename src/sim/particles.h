// particles.h: the live particles as a structure of arrays (thesis 4.8.3), and the
// counter-based random stream every particle draws from.
//
// The arrays the step loop streams through (position, velocity, 1/mass) are kept
// apart from the ones only a collision touches (load, identity, collision count,
// last slide). Dead particles are removed in O(1) by moving the last one into
// their slot. Every array holds `capacity` entries, a multiple of
// WX_PARTICLE_BLOCK, so the step loop can run whole blocks past `count`.
//
// While every particle has the same mass (one emitter, or emitters of one mass:
// the common case) there is no 1/mass array: `inv_mass` is NULL and the block
// loop reads `inv_mass_block`, 16 copies of the shared value. The first particle
// of another mass creates the array.
#ifndef WX_PARTICLES_H
#define WX_PARTICLES_H

#include <stdbool.h>
#include <stdint.h>

#include "core/error.h"

/// Particles are stepped in blocks of this many (arrays are padded to it).
#define WX_PARTICLE_BLOCK 16

/// last_slide value of a particle whose previous step was not a slide hit.
#define WX_NO_SLIDE UINT32_MAX

typedef struct wx_particles {
    int64_t count;
    int64_t capacity;
    // Hot: read and written by every step.
    float *x, *y, *z;
    float *vx, *vy, *vz;
    float *inv_mass; ///< 1/mass per particle, or NULL while all share inv_mass_block[0]
    float inv_mass_block[WX_PARTICLE_BLOCK]; ///< the shared 1/mass, once per lane
    // Cold: touched on emission, collision and removal.
    int substances;           ///< loads per particle, >= 1 (set before the first reserve)
    double *load;             ///< substance s of particle i at load[i * substances + s]
    uint64_t *id;             ///< emitter index << 48 | serial number within it
    uint32_t *collisions_left; ///< hits before the particle settles (>= 1 while alive)
    /// Where a slide hit of the previous step was, numbered over the texels of
    /// all input maps (the simulation numbers them), or WX_NO_SLIDE: the step
    /// loop resets it for every particle that does not collide.
    uint32_t *last_slide;
    /// The share of the particle not yet left on a surface, 1 at emission: each
    /// exchange leaves the share of the load it deposits (docs/mask.md: the
    /// `hits` a gather counts are these shares, so a particle counts once
    /// however often it hits).
    float *weight;
} wx_particles;

/// Bytes stored per particle slot (all arrays), with a 1/mass array and one
/// substance; each further substance adds one double.
#define WX_PARTICLE_BYTES (7 * 4 + 8 + 8 + 4 + 4 + 4)

/// Bytes stored per particle slot now: WX_PARTICLE_BYTES less the 1/mass array
/// while all particles share one mass, plus 8 per substance beyond the first.
static inline int wx_particles_slot_bytes(const wx_particles *p)
{
    int extra = p->substances > 1 ? 8 * (p->substances - 1) : 0;
    return WX_PARTICLE_BYTES + extra - (p->inv_mass == NULL ? (int)sizeof(float) : 0);
}

/// 1/mass of particle i.
static inline float wx_particle_inv_mass(const wx_particles *p, int64_t i)
{
    return p->inv_mass != NULL ? p->inv_mass[i] : p->inv_mass_block[0];
}

/// Frees every array; the struct is zeroed.
void wx_particles_free(wx_particles *p);

/// Makes room for at least `needed` particles (growing by half again). Returns
/// false when out of memory (the particles are unchanged).
bool wx_particles_reserve(wx_particles *p, int64_t needed);

/// Appends one particle carrying load[0..substances) (capacity must be
/// reserved). Returns its index, or -1 when out of memory (a first particle of
/// a new mass needs the 1/mass array).
int64_t wx_particles_push(wx_particles *p, const float pos[3], const float vel[3], float mass,
                          const double *load, uint64_t id, uint32_t max_collisions);

/// Removes particle i by moving the last particle into its slot.
void wx_particles_remove(wx_particles *p, int64_t i);

/// The particle id of serial number `serial` of emitter `emitter`.
static inline uint64_t wx_particle_id(uint32_t emitter, uint64_t serial)
{
    return ((uint64_t)emitter << 48) | (serial & ((UINT64_C(1) << 48) - 1));
}

/// SplitMix64 finaliser: a bijective 64-bit mix.
static inline uint64_t wx_mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * UINT64_C(0xbf58476d1ce4e5b9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94d049bb133111eb);
    return z ^ (z >> 31);
}

/// Counter-based random stream: a uniform float in [0, 1) that depends only on
/// the seed, the particle id and the counter (no state, so any thread, any
/// order, gives the same number).
static inline float wx_particle_random(uint64_t seed, uint64_t id, uint64_t counter)
{
    uint64_t h = wx_mix64(seed ^ wx_mix64(id ^ wx_mix64(counter + UINT64_C(0x9e3779b97f4a7c15))));
    return (float)(h >> 40) * (1.0f / 16777216.0f);
}

/// Counters of a particle's stream: two draws at emission, two per collision.
enum {
    WX_RANDOM_EMIT_0 = 0,
    WX_RANDOM_EMIT_1 = 1,
    WX_RANDOM_COLLISION = 2, ///< + 2 * collision number (+ 0 absorption, + 1 bounce)
};

/// Counters of a box emitter's start (three for the position, two for the
/// direction), far above every collision's.
#define WX_RANDOM_EMIT_BOX (UINT64_C(1) << 40)

#endif
