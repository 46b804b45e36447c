// solver_internal.h: what the files of the simulation (simulate.c: the
// orchestration, step.c: the step kernel, ageing.c: the ageing rules) share:
// the solver's state and the records the threads hand to the serial phase.
// Private to src/sim/.
#ifndef WX_SOLVER_INTERNAL_H
#define WX_SOLVER_INTERNAL_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "sim/simulate.h"
#include "sim/collider.h"
#include "sim/emitter.h"
#include "sim/force_field.h"
#include "sim/particles.h"
#include "core/parallel.h"

// Event flags: the impact kind in the low bits.
enum {
    EVENT_KIND_MASK = 3,
    EVENT_LINE = 4, ///< slide after a slide: spread over the Bresenham line
    EVENT_DIES = 8, ///< absorbed or at maxCollisions: deposits all it carries
};

// One collision, applied to the dirt maps in the serial phase.
typedef struct sim_event {
    int64_t index;  ///< particle
    uint32_t texel; ///< hit texel
    uint32_t from;  ///< previous slide texel (EVENT_LINE)
    float point[3];
    uint16_t camera; ///< the view (camera and layer) whose dirt map holds the texel
    uint8_t flags;
} sim_event;

// A lane the first pass could not settle: its segment was not cleared by the
// first camera, or it ends out of the box. The other cameras' coarse test runs
// on these, 16 at a time; what is left goes to the swept test, in particle
// order, with the maps' lines prefetched a few candidates ahead.
typedef struct sim_candidate {
    int64_t index;
    float p0[3], p1[3], v[3];
    uint32_t flags;
} sim_candidate;

enum {
    CAND_CLEAR = 1,  ///< certainly no collision
    CAND_OUT_A = 2,  ///< outside the first camera's frame
    CAND_OUTBOX = 4, ///< ends outside the bounding box
};

// The record of one chunk of particles in one step: written by the thread that
// stepped it, read by the one that applies it once `done` says it may.
typedef struct sim_chunk {
    sim_event *events; ///< in increasing particle order
    int64_t event_count, event_capacity;
    int64_t *dead; ///< index << 1 | escaped, in increasing index order
    int64_t dead_count, dead_capacity;
    atomic_int done; ///< set (release) when the chunk's records are complete
} sim_chunk;

// The state of one worker of the pool (wx_pool worker index = array index).
typedef struct sim_worker {
    sim_chunk *chunk; ///< the chunk being stepped
    sim_candidate *cands;
    int64_t cand_count, cand_capacity;
    bool failed;                           ///< out of memory in this step
    uint32_t credit[WX_MAX_INPUT_CAMERAS]; ///< lanes each camera cleared first
} sim_worker;

// surface_automata.c: the surface points and their grids (docs/design.md
// section 15), built the first time a Seed or Spread runs.
typedef struct sim_surface sim_surface;
// Grids kept at once, one per distinct Spread radius.
#define WX_MAX_GRIDS 4

struct wx_sim {
    const wx_scene *scene;
    // Configuration.
    uint64_t seed;
    double dt;
    float bbox_lo[3], bbox_hi[3];
    wx_collider_def params;
    int emitter_count;
    const wx_emitter *emitters;
    int64_t *emitted; ///< per emitter
    uint64_t spawned;
    // World.
    wx_forces forces;
    wx_collider collider;
    int input_count;
    int *input_camera;   ///< scene camera index of each input camera
    const wx_maps *maps; ///< per input camera, every layer (the collider's)
    /// Views: one per layer of each input camera, camera by camera (layer k of
    /// input camera c is view view_base[c] + k; docs/design.md section 14).
    /// Every array below that is "per view" is indexed by them; with one layer
    /// a camera's view is the camera.
    int view_count;
    int view_base[WX_MAX_INPUT_CAMERAS + 1];
    wx_maps *views;    ///< borrowed layer views of `maps` (wx_maps_layer_view)
    wx_dirt_map *dirt; ///< per view
    int substances;    ///< loads per particle, substances per texel
    /// Ageing (docs/design.md section 9): per input camera, the amounts the
    /// surface would hold without the particles, aged like the real ones
    /// (NULL without rules: the initial planes are that), and the area each
    /// texel grows on (NULL without Grow rules).
    double **baseline;
    float **grow_area;
    const float **surface_of;    ///< the maps' surface planes (NULL entries: none)
    const wx_surface **surfaces; ///< the scene's <Surface>s by global index (the rules')
    int64_t iterations_done;
    sim_surface *surface;                   ///< NULL until a Seed or Spread first runs
    int camera_order[WX_MAX_INPUT_CAMERAS]; ///< coarse test order (speed only)
    /// Texel numbering for the particles' last slide: view v's texel t is
    /// slide_base[v] + t; slide_base[view_count] is the total.
    uint32_t slide_base[WX_MAX_INPUT_CAMERAS * WX_MAX_LAYERS + 1];
    // State.
    int64_t step;
    wx_particles particles;
    wx_sim_stats stats; ///< counters and the emitted / escaped / initial ledger
    wx_hit_sample *hits;
    int hit_capacity, hit_next, hit_count;
    // Threads.
    int thread_count;
    sim_worker *workers;
    sim_chunk *chunks;
    int64_t chunk_particles;             ///< particles per chunk in this step
    int64_t chunk_limit;                 ///< the most particles a chunk takes
    int64_t chunk_count, chunk_capacity; ///< chunks of this step, allocated
    int64_t applied;                     ///< chunks whose events are applied
    wx_pool *pool;                       ///< the threads (core/parallel.h)
    // Ranks (core/dist.h, docs/scale-out.md): every rank holds every particle
    // and the same maps, and steps only particles [own_begin, own_end) (whole
    // blocks, its share by index); with more than one rank the step's records
    // of all ranks are gathered (exchange.c) into `all` and applied from there,
    // in particle order as one rank would.
    int ranks;
    int64_t own_begin, own_end;
    sim_chunk all;
    int64_t *rank_counts; ///< exchange.c's counts: 6 per rank (ranks > 1)
    uint64_t *exchange;   ///< exchange.c's buffer: every rank's part of a step
    int64_t exchange_capacity;
};

// The input camera of view v.
static inline int sim_view_camera(const wx_sim *sim, int v)
{
    int c = 0;
    while (c + 1 < sim->input_count && sim->view_base[c + 1] <= v) {
        c++;
    }
    return c;
}

// step.c: steps particles [begin, end) into the records of the worker's chunk
// (emptied by prepare_chunks).
void sim_step_range(wx_sim *sim, sim_worker *w, int64_t begin, int64_t end);

// exchange.c: this rank's share of the particles for the step (own_begin,
// own_end), from the particle count and the rank.
void sim_share(wx_sim *sim);

// exchange.c: with more than one rank, at the end of wx_sim_create on every
// rank: `r` is this rank's result so far. Fails on every rank when any rank
// failed or when the ranks' simulations differ (views, texels, substances,
// emitters, seed).
wx_result sim_agree(wx_sim *sim, wx_result r, wx_error *err);

// exchange.c: with more than one rank, after the step's stepping: every rank's
// moved particles into every rank's arrays, and every rank's events and deaths
// into sim->all, in particle order. Fails on every rank when one ran out of
// memory.
wx_result sim_exchange(wx_sim *sim, wx_error *err);

// ageing.c: view c's ageing state, set up once its dirt map is.
wx_result sim_setup_ageing(wx_sim *sim, int c, wx_error *err);

// ageing.c: the rules after an iteration's last step. WX_FAIL when out of
// memory (the surface automata's points and grids).
wx_result sim_age(wx_sim *sim, wx_error *err);

// point_rules.c: `count` rules on one texel's amounts a[] and baseline b[] (may be
// NULL), `area` the surface it grows on; Seed and Spread are not run here.
void sim_run_rules(const wx_rule *rules, int count, double *a, double *b, double area,
                   wx_substance_ledger *ledger);

// surface_automata.c: every rule, one after the other over the whole surface,
// for a scene with Seed or Spread rules.
wx_result sim_age_automata(wx_sim *sim, wx_error *err);
void sim_surface_free(sim_surface *surface);

#endif
