// simulate.h: the particle simulation (thesis 4.8.2-4.8.4.3, docs/design.md
// section 4):
// emitters, force fields, the semi-implicit Euler step, the projected-maps
// collider, the mechanical reaction and the dirt exchange, with a ledger that
// proves no dirt is created or lost.
//
// Steps run on a persistent pool of threads. Each particle's step is a pure
// function of its own state, the maps and its own random stream (seed, particle
// id, collision count), and every dirt update is applied afterwards in particle
// order: one seed gives byte-identical results for any number of threads.
//
// The same object drives the simulate phase (pipeline/simulate_phase.c) and the
// viewer (create, step, read particles and recent hits, destroy). It takes its
// maps in memory and touches no file.
#ifndef WX_SIMULATE_H
#define WX_SIMULATE_H

#include <stdbool.h>
#include <stdint.h>

#include "core/error.h"
#include "model/maps.h"
#include "model/scene.h"
#include "model/stats.h"
#include "sim/dirt_map.h"

typedef struct wx_sim wx_sim;

typedef struct wx_sim_def {
    uint64_t seed;       ///< random seed (default: the scene's)
    int threads;         ///< worker threads, 0 = one per core (default)
    int hit_capacity;    ///< recent hit points kept for the viewer, 0 = 4096 (default)
    bool nearest_depth;  ///< nearest-texel depth (the thesis) instead of bilinear
    /// Particles a thread steps at a time, rounded up to a multiple of
    /// WX_PARTICLE_BLOCK; 0 = 8192 (default). Results do not depend on it.
    int chunk_particles;
    /// One wx_maps per input camera, in scene order (borrowed: must outlive the
    /// simulation; depth, normal and impact needed, dirt planes optional). NULL
    /// only for a scene without input cameras.
    const wx_maps *maps;
    /// Spread the stepping over the ranks of an MPI run (core/dist.h,
    /// docs/scale-out.md): every rank creates its simulation with the same
    /// scene, maps and seed and steps it as often; the results are those of
    /// one process, on every rank. False (default): this process alone.
    bool distributed;
    /// A collider already built over the same cameras and maps, with bilinear
    /// depth and the scene's tile box (a run's derived masks': pipeline/run.c),
    /// which must outlive the simulation: stepped through with the maps'
    /// impact (wx_collider_view) rather than built again. NULL (default):
    /// built here. Ignored with nearest_depth.
    const struct wx_collider *shared_collider;
} wx_sim_def;

/// Default configuration for a scene: its seed, one thread per core.
wx_sim_def wx_default_sim_def(const wx_scene *scene);

/// Creates a simulation of `scene` at time 0 (no particles yet). The scene must
/// outlive the simulation. Errors name the map file or the camera.
wx_result wx_sim_create(const wx_scene *scene, const wx_sim_def *config, wx_sim **out,
                        wx_error *err);

/// Stops the threads and frees everything.
void wx_sim_destroy(wx_sim *sim);

/// Advances one time step: forces, Euler step, collisions, dirt exchange,
/// removal of dead particles, then emission up to the new time. Fails only when
/// out of memory.
wx_result wx_sim_step(wx_sim *sim, wx_error *err);

/// Steps done so far, and the simulated time (steps * time step).
int64_t wx_sim_step_count(const wx_sim *sim);
double wx_sim_time(const wx_sim *sim);

/// Read-only views of the live particles (valid until the next step).
typedef struct wx_particle_view {
    int64_t count;
    const float *x, *y, *z;
    const float *vx, *vy, *vz;
    const double *load;
} wx_particle_view;

void wx_sim_particles(const wx_sim *sim, wx_particle_view *view);

/// Bytes each particle slot takes now (WX_PARTICLE_BYTES, less the 1/mass array
/// while all particles share one mass).
int wx_sim_particle_bytes(const wx_sim *sim);

typedef enum wx_impact {
    WX_IMPACT_ABSORB = 0,
    WX_IMPACT_BOUNCE = 1,
    WX_IMPACT_SLIDE = 2,
} wx_impact;

/// A recent collision, for drawing.
typedef struct wx_hit_sample {
    float position[3]; ///< where the particle entered the surface
    int camera;        ///< view index (wx_sim_view_camera: input camera and layer)
    wx_impact impact;
} wx_hit_sample;

/// Copies up to `max` of the most recent hits, oldest first; returns how many.
int wx_sim_recent_hits(const wx_sim *sim, wx_hit_sample *out, int max);

/// The counters and the dirt ledger so far (final_surface and in_flight are the
/// current surface total and particle loads).
void wx_sim_get_stats(const wx_sim *sim, wx_sim_stats *stats);

/// Iterations completed so far (each ends with the ageing rules; at most the
/// scene's `iterations`).
int64_t wx_sim_iterations_done(const wx_sim *sim);

/// Input camera `input`'s amounts without the particles' exchanges (W*H*S
/// doubles, the dirt map's layout), aged like the real amounts: what the
/// gather must not smooth. NULL when the scene has no ageing rules (the
/// initial amounts are that).
const double *wx_sim_baseline(const wx_sim *sim, int input);

/// The views and their dirt: one view per layer of each input camera, camera
/// by camera, layer 0 first (docs/design.md section 14); with one layer per
/// camera, view k is the scene's k-th input camera.
int wx_sim_input_count(const wx_sim *sim);
const wx_dirt_map *wx_sim_dirt_map(const wx_sim *sim, int input);

/// The views of input camera `camera` (0 = the scene's first): how many (its
/// layers), the first in *first.
int wx_sim_camera_views(const wx_sim *sim, int camera, int *first);

/// The input camera (0 = the scene's first) of view `view`, and its layer.
int wx_sim_view_camera(const wx_sim *sim, int view, int *layer);

/// Adds one particle by hand (the tests, bench_simulate and bench_layers)
/// carrying `load` of the first substance: it counts as emitted. Its random
/// stream is that of a pseudo-emitter after the scene's emitters.
wx_result wx_sim_spawn(wx_sim *sim, const float position[3], const float velocity[3],
                       float mass, double load, int max_collisions, wx_error *err);

#endif
