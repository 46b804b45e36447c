// emitter.h: particle emitters (thesis 4.8.2, docs/design.md section 3): how many
// particles an emitter has emitted by a given time, and where and how fast each
// one starts.
//
// Emission is exact: by time t an emitter has emitted floor(rate * (t - start))
// particles (t clipped to its end), whatever the time step. A particle's start
// depends only on the seed and its id (emitter index, serial number), never on
// which thread or step created it.
#ifndef WX_EMITTER_H
#define WX_EMITTER_H

#include <stdint.h>

#include "model/scene.h"

/// Particles emitter `e` has emitted by time t: floor(rate * (min(t, end) - start)),
/// 0 before start. A relative 1e-12 guards against decimal time steps landing just
/// below an integer (1000 * (29 * 0.01) is 289.99999999999997 in binary). A
/// count beyond int64_t (rate="1e300") is INT64_MAX.
int64_t wx_emitter_count_at(const wx_emitter *e, double t);

/// A unit direction uniform over the sphere, from two uniforms in [0, 1).
void wx_uniform_sphere(float u1, float u2, float d[3]);

/// A unit direction uniform over the upper (+Y) hemisphere, from two uniforms.
void wx_uniform_hemisphere(float u1, float u2, float d[3]);

/// A unit direction uniform over the solid angle of the cone of half-angle
/// `spread` radians around the unit vector `axis` (the axis itself for 0),
/// from two uniforms: cos(theta) uniform in [cos(spread), 1], phi in [0, 2 pi).
void wx_uniform_cone(const float axis[3], float spread, float u1, float u2, float d[3]);

/// A serial number no particle reaches (2^48 - 1): the shift of the sequence.
#define WX_EMIT_SHIFT_SERIAL ((UINT64_C(1) << 48) - 1)

/// The particle's `dimensions` (1 to 3) numbers in [0, 1): point number
/// `serial` (the low 48 bits of id) of the low-discrepancy sequence R_d,
/// shifted at random per seed and emitter. A steady rain then covers a surface
/// evenly instead of with Poisson clumps (the noise between seeds drops,
/// docs/physics.md), and the particle's start still depends only on the seed
/// and its id.
void wx_emitter_uniforms(uint64_t seed, uint64_t id, int dimensions, double *u);

/// Start position and velocity of the particle with id `id` (see wx_particle_id):
/// PointEmitter: the centre, speed times a uniform direction; HemisphereEmitter:
/// c + radius*d with d uniform on the upper hemisphere, velocity -speed*d;
/// BoxEmitter (docs/design.md section 8): a point uniform in [min, max],
/// velocity speed times a direction uniform in the cone of `spread` degrees
/// around `dir`. The start (and a point or hemisphere emitter's direction) from
/// wx_emitter_uniforms; a box's direction from the particle's random numbers.
void wx_emitter_sample(const wx_emitter *e, uint64_t seed, uint64_t id, float pos[3],
                       float vel[3]);

#endif
