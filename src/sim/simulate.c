// simulate.c: the particle solver (thesis 4.8.2) with the projected-maps
// collider (4.8.4.1), the mechanical reaction (4.8.4.2) and the dirt exchange
// (4.8.4.3), as pinned in docs/design.md section 4; docs/physics.md explains the
// choices.
//
// One step:
//  1. in parallel, the threads take chunks of 8192 (by default) consecutive
//     particles in turn (whoever is free takes the next) and step them, a block
//     of WX_PARTICLE_BLOCK at a time: forces and the Euler step (vectorised),
//     the coarse collision test (vectorised), then for the few segments it does
//     not clear, the swept test and the reaction. Dirt is not touched there:
//     each collision is recorded as an event of its chunk, each death in the
//     chunk's list;
//  2. in chunk order, hence particle order, the events exchange dirt with the
//     maps. One thread does this (the calling one), while the others step: it
//     applies each chunk as soon as that chunk and every one before it are
//     done, so this serial work overlaps the parallel phase and only the last
//     chunks' events are left when the stepping ends;
//  3. dead particles are removed, highest index first (swap with the last);
//  4. emitters emit up to the new time.
#include "sim/simulate.h"

#include <math.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim/collider.h"
#include "sim/emitter.h"
#include "sim/force_field.h"
#include "sim/particles.h"
#include "core/array.h"
#include "core/parallel.h"

enum {
    DEFAULT_HIT_CAPACITY = 4096,
    PSEUDO_EMITTER = 0xFFFF, ///< emitter index of particles added by wx_sim_spawn
    DEFAULT_CHUNK = 8192,    ///< particles a thread takes at a time (a multiple of the block)
    CHUNKS_PER_THREAD = 4,   ///< the fewest chunks a thread gets while the particles allow
};

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

static const uint32_t lane_bit[WX_PARTICLE_BLOCK] = {
    1u << 0, 1u << 1, 1u << 2,  1u << 3,  1u << 4,  1u << 5,  1u << 6,  1u << 7,
    1u << 8, 1u << 9, 1u << 10, 1u << 11, 1u << 12, 1u << 13, 1u << 14, 1u << 15,
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
    bool failed; ///< out of memory in this step
    uint32_t credit[WX_MAX_INPUT_CAMERAS]; ///< lanes each camera cleared first
} sim_worker;

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
    int *input_camera; ///< scene camera index of each input camera
    const wx_maps *maps; ///< per input camera, every layer (the collider's)
    /// Views: one per layer of each input camera, camera by camera (layer k of
    /// input camera c is view view_base[c] + k; docs/design.md section 14).
    /// Every array below that is "per view" is indexed by them; with one layer
    /// a camera's view is the camera.
    int view_count;
    int view_base[WX_MAX_INPUT_CAMERAS + 1];
    wx_maps *views; ///< borrowed layer views of `maps` (wx_maps_layer_view)
    wx_dirt_map *dirt; ///< per view
    int substances;     ///< loads per particle, substances per texel
    /// Ageing (docs/design.md section 9): per input camera, the amounts the
    /// surface would hold without the particles, aged like the real ones
    /// (NULL without rules: the initial planes are that), and the area each
    /// texel grows on (NULL without Grow rules).
    double **baseline;
    float **grow_area;
    const float **surface_of; ///< the maps' surface planes (NULL entries: none)
    const wx_surface **surfaces; ///< the scene's <Surface>s by global index (the rules')
    int64_t iterations_done;
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
    wx_pool *pool; ///< the threads (core/parallel.h)
};

// --- per-thread recording -------------------------------------------------------

static bool push_event(sim_worker *w, const sim_event *e)
{
    sim_chunk *ch = w->chunk;
    if (!wx_array_reserve((void **)&ch->events, &ch->event_capacity, ch->event_count + 1,
                          sizeof *ch->events, 256)) {
        w->failed = true;
        return false;
    }
    ch->events[ch->event_count++] = *e;
    return true;
}

static void push_candidate(sim_worker *w, const sim_candidate *c)
{
    if (!wx_array_reserve((void **)&w->cands, &w->cand_capacity, w->cand_count + 1,
                          sizeof *w->cands, 1024)) {
        w->failed = true;
        return;
    }
    w->cands[w->cand_count++] = *c;
}

static void push_dead(sim_worker *w, int64_t index, bool escaped)
{
    sim_chunk *ch = w->chunk;
    if (!wx_array_reserve((void **)&ch->dead, &ch->dead_capacity, ch->dead_count + 1,
                          sizeof *ch->dead, 256)) {
        w->failed = true;
        return;
    }
    ch->dead[ch->dead_count++] = index << 1 | (escaped ? 1 : 0);
}

// --- the step of one particle range ------------------------------------------

static inline bool inside_box(const wx_sim *sim, const float p[3])
{
    return p[0] >= sim->bbox_lo[0] && p[0] <= sim->bbox_hi[0] && p[1] >= sim->bbox_lo[1] &&
           p[1] <= sim->bbox_hi[1] && p[2] >= sim->bbox_lo[2] && p[2] <= sim->bbox_hi[2];
}

// Forces and the semi-implicit Euler step of one block (docs/design.md section 4; the
// thesis' position formula, 3.2, has a typo): a = g + F/m, v += dt a, x += dt v.
WX_HOT static void integrate_block(const wx_forces *restrict forces, float t, float dt,
                                   const float *restrict x, const float *restrict y,
                                   const float *restrict z, const float *restrict vx,
                                   const float *restrict vy, const float *restrict vz,
                                   const float *restrict inv_mass, float *restrict nx,
                                   float *restrict ny, float *restrict nz, float *restrict nvx,
                                   float *restrict nvy, float *restrict nvz,
                                   const float *restrict lo, const float *restrict hi,
                                   int *restrict inside)
{
    enum { B = WX_PARTICLE_BLOCK };
    float fx[B], fy[B], fz[B];
    wx_forces_block(forces, t, x, y, z, fx, fy, fz);
    float gx = forces->gravity[0], gy = forces->gravity[1], gz = forces->gravity[2];
    for (int k = 0; k < B; ++k) {
        nvx[k] = vx[k] + dt * (gx + fx[k] * inv_mass[k]);
        nvy[k] = vy[k] + dt * (gy + fy[k] * inv_mass[k]);
        nvz[k] = vz[k] + dt * (gz + fz[k] * inv_mass[k]);
        nx[k] = x[k] + dt * nvx[k];
        ny[k] = y[k] + dt * nvy[k];
        nz[k] = z[k] + dt * nvz[k];
        inside[k] = (nx[k] >= lo[0]) & (nx[k] <= hi[0]) & (ny[k] >= lo[1]) & (ny[k] <= hi[1]) &
                    (nz[k] >= lo[2]) & (nz[k] <= hi[2]);
    }
}

// A segment the coarse test did not clear: the swept test, and on a hit the
// Russian roulette, the reaction and the event.
static void collide_one(wx_sim *sim, sim_worker *w, int64_t i, const float p0[3],
                        const float p1[3], const float v[3])
{
    wx_particles *P = &sim->particles;
    wx_hit hit;
    hit.layer = 0;
    if (!wx_collider_sweep(&sim->collider, p0, p1, &hit)) {
        // The Euler step stands (already stored); a step without a hit ends a streak.
        P->last_slide[i] = WX_NO_SLIDE;
        if (!inside_box(sim, p1)) {
            push_dead(w, i, true);
        }
        return;
    }
    // Russian roulette on the impact map (thesis 4.8.4.2, Algorithm 2).
    uint32_t left = P->collisions_left[i];
    uint64_t counter = WX_RANDOM_COLLISION + 2 * (uint64_t)left;
    float r_absorb = wx_particle_random(sim->seed, P->id[i], counter);
    float r_bounce = wx_particle_random(sim->seed, P->id[i], counter + 1);
    wx_impact kind = r_absorb < hit.absorption ? WX_IMPACT_ABSORB
                     : r_bounce < hit.bounce   ? WX_IMPACT_BOUNCE
                                               : WX_IMPACT_SLIDE;
    left = left > 0 ? left - 1 : 0;
    P->collisions_left[i] = left;
    bool dies = kind == WX_IMPACT_ABSORB || left == 0;

    sim_event e = { 0 };
    e.index = i;
    e.texel = hit.texel;
    int view = sim->view_base[hit.camera] + hit.layer;
    e.camera = (uint16_t)view;
    e.flags = (uint8_t)kind;
    memcpy(e.point, hit.point, sizeof e.point);
    // Streaks: a slide that follows a slide of the previous step on the same map
    // (last_slide is reset in every step without a hit; unsigned arithmetic puts
    // another map's texels and WX_NO_SLIDE out of range).
    uint32_t base = sim->slide_base[view];
    uint32_t from = P->last_slide[i] - base;
    if (kind == WX_IMPACT_SLIDE && from < sim->slide_base[view + 1] - base) {
        e.flags |= EVENT_LINE;
        e.from = from;
    }
    P->last_slide[i] = kind == WX_IMPACT_SLIDE ? base + hit.texel : WX_NO_SLIDE;
    if (dies) {
        e.flags |= EVENT_DIES;
    }
    if (!push_event(w, &e)) {
        return;
    }
    if (dies) {
        P->x[i] = hit.point[0];
        P->y[i] = hit.point[1];
        P->z[i] = hit.point[2];
        push_dead(w, i, false);
        return;
    }

    // Mechanical reaction (thesis 4.8.4.2): v = vn + vt on the hit normal;
    // bounce v = -R vn, slide v = F vt.
    const float *N = hit.normal;
    float vn = v[0] * N[0] + v[1] * N[1] + v[2] * N[2];
    float after[3];
    for (int k = 0; k < 3; ++k) {
        float normal_part = vn * N[k];
        after[k] = kind == WX_IMPACT_BOUNCE ? -sim->params.resilience * normal_part
                                            : sim->params.friction * (v[k] - normal_part);
    }
    // The particle is put back on the surface, slightly in front of it, and
    // spends the rest of the step at its new velocity (swept too; a second
    // contact in the same step stops it there without a second event).
    float rest = (1.0f - hit.s) * (float)sim->dt;
    float q1[3];
    for (int k = 0; k < 3; ++k) {
        q1[k] = hit.front[k] + rest * after[k];
    }
    float final[3];
    wx_hit again;
    if (!wx_collider_coarse_clear(&sim->collider, hit.front, q1) &&
        wx_collider_sweep(&sim->collider, hit.front, q1, &again)) {
        memcpy(final, again.front, sizeof final);
    } else {
        memcpy(final, q1, sizeof final);
    }
    if (kind == WX_IMPACT_SLIDE) {
        // Adherence pulls a sliding particle onto the surface: v -= A N dt / m.
        float pull = sim->params.adherence * (float)sim->dt * wx_particle_inv_mass(P, i);
        for (int k = 0; k < 3; ++k) {
            after[k] -= pull * N[k];
        }
    }
    P->x[i] = final[0];
    P->y[i] = final[1];
    P->z[i] = final[2];
    P->vx[i] = after[0];
    P->vy[i] = after[1];
    P->vz[i] = after[2];
    if (!inside_box(sim, final)) {
        push_dead(w, i, true);
    }
}

// The other cameras' coarse test on the candidates the first camera left.
static void coarse_rest(wx_sim *sim, sim_worker *w)
{
    enum { B = WX_PARTICLE_BLOCK };
    int rest = sim->input_count > 0 ? sim->input_count - 1 : 0;
    int64_t pending[B];
    int m = 0;
    for (int64_t j = 0; j <= w->cand_count; ++j) {
        if (j < w->cand_count && !(w->cands[j].flags & CAND_CLEAR)) {
            pending[m++] = j;
        }
        if (m == B || (j == w->cand_count && m > 0)) {
            float x0[B], y0[B], z0[B], x1[B], y1[B], z1[B];
            for (int k = 0; k < B; ++k) {
                const sim_candidate *c = &w->cands[pending[k < m ? k : 0]];
                x0[k] = c->p0[0];
                y0[k] = c->p0[1];
                z0[k] = c->p0[2];
                x1[k] = c->p1[0];
                y1[k] = c->p1[1];
                z1[k] = c->p1[2];
            }
            uint32_t outside;
            uint32_t clear = wx_collider_coarse_block(&sim->collider, sim->camera_order + 1, rest,
                                                      w->credit, x0, y0, z0, x1, y1, z1,
                                                      &outside);
            for (int k = 0; k < m; ++k) {
                sim_candidate *c = &w->cands[pending[k]];
                bool out_all = (c->flags & CAND_OUT_A) && ((outside >> k) & 1u);
                if (((clear >> k) & 1u) || out_all) {
                    c->flags |= CAND_CLEAR;
                }
            }
            m = 0;
        }
    }
}

// Steps particles [begin, end) into the records of the worker's chunk (emptied
// by prepare_chunks).
static void step_range(wx_sim *sim, sim_worker *w, int64_t begin, int64_t end)
{
    enum { B = WX_PARTICLE_BLOCK };
    wx_particles *P = &sim->particles;
    float t = (float)((double)sim->step * sim->dt);
    float dt = (float)sim->dt;
    int first = sim->input_count > 0 ? 1 : 0;
    w->cand_count = 0;
    for (int64_t b = begin; b < end; b += B) {
        float ox[B], oy[B], oz[B], nx[B], ny[B], nz[B], nvx[B], nvy[B], nvz[B];
        int inside[B];
        memcpy(ox, P->x + b, sizeof ox);
        memcpy(oy, P->y + b, sizeof oy);
        memcpy(oz, P->z + b, sizeof oz);
        const float *inv_mass = P->inv_mass != NULL ? P->inv_mass + b : P->inv_mass_block;
        integrate_block(&sim->forces, t, dt, ox, oy, oz, P->vx + b, P->vy + b, P->vz + b,
                        inv_mass, nx, ny, nz, nvx, nvy, nvz, sim->bbox_lo, sim->bbox_hi, inside);
        // The camera that cleared most last step, on every lane.
        uint32_t out_a;
        uint32_t clear = wx_collider_coarse_block(&sim->collider, sim->camera_order, first,
                                                  w->credit, ox, oy, oz, nx, ny, nz, &out_a);
        // Every lane takes its Euler step (lanes past the end are padding);
        // the candidates below redo what the collider changes.
        memcpy(P->x + b, nx, sizeof nx);
        memcpy(P->y + b, ny, sizeof ny);
        memcpy(P->z + b, nz, sizeof nz);
        memcpy(P->vx + b, nvx, sizeof nvx);
        memcpy(P->vy + b, nvy, sizeof nvy);
        memcpy(P->vz + b, nvz, sizeof nvz);
        uint32_t outbox = 0;
        for (int k = 0; k < B; ++k) {
            outbox |= -(uint32_t)!inside[k] & lane_bit[k];
        }
        int lanes = end - b < B ? (int)(end - b) : B;
        uint32_t valid = (1u << lanes) - 1u;
        uint32_t special = (~clear | outbox) & valid;
        // A step without a hit ends a streak: reset every lane that cannot hit
        // (padding lanes too); the candidates below reset their own. Written only
        // where set, so the array's lines stay clean.
        uint32_t *last_slide = P->last_slide + b;
        uint32_t sliding = 0;
        for (int k = 0; k < B; ++k) {
            sliding |= (uint32_t)(last_slide[k] != WX_NO_SLIDE) << k;
        }
        sliding &= ~special;
        while (sliding != 0) {
            last_slide[__builtin_ctz(sliding)] = WX_NO_SLIDE;
            sliding &= sliding - 1;
        }
        while (special != 0) {
            int k = __builtin_ctz(special);
            special &= special - 1;
            uint32_t flags = (((clear >> k) & 1u) ? CAND_CLEAR : 0) |
                             (((out_a >> k) & 1u) ? CAND_OUT_A : 0) |
                             (((outbox >> k) & 1u) ? CAND_OUTBOX : 0);
            sim_candidate c = { b + k, { ox[k], oy[k], oz[k] }, { nx[k], ny[k], nz[k] },
                                { nvx[k], nvy[k], nvz[k] }, flags };
            push_candidate(w, &c);
        }
    }
    coarse_rest(sim, w);
    // What is left, in particle order (so events and deaths stay sorted).
    enum { AHEAD = 8 };
    for (int64_t j = 0; j < w->cand_count; ++j) {
        if (j + AHEAD < w->cand_count && !(w->cands[j + AHEAD].flags & CAND_CLEAR)) {
            wx_collider_prefetch(&sim->collider, w->cands[j + AHEAD].p1);
        }
        const sim_candidate *c = &w->cands[j];
        if (!(c->flags & CAND_CLEAR)) {
            collide_one(sim, w, c->index, c->p0, c->p1, c->v);
        } else {
            P->last_slide[c->index] = WX_NO_SLIDE;
            if (c->flags & CAND_OUTBOX) {
                push_dead(w, c->index, true); // a free flight out of the box
            }
        }
    }
}

// --- the dirt exchange -------------------------------------------------------------

static void record_hit(wx_sim *sim, const sim_event *e)
{
    if (sim->hit_capacity == 0) {
        return;
    }
    wx_hit_sample *h = &sim->hits[sim->hit_next];
    memcpy(h->position, e->point, sizeof h->position);
    h->camera = e->camera;
    h->impact = (wx_impact)(e->flags & EVENT_KIND_MASK);
    sim->hit_next = (sim->hit_next + 1) % sim->hit_capacity;
    if (sim->hit_count < sim->hit_capacity) {
        sim->hit_count++;
    }
}

// Dirt exchange (thesis 4.8.4.3 as pinned in docs/design.md section 4) of one chunk's
// events, in particle order.
static void apply_chunk(wx_sim *sim, const sim_chunk *ch)
{
    double *load = sim->particles.load;
    int64_t S = sim->substances;
    for (int64_t k = 0; k < ch->event_count; ++k) {
        if (k + 8 < ch->event_count) {
            const sim_event *ahead = &ch->events[k + 8];
            __builtin_prefetch(&sim->dirt[ahead->camera].texels[(int64_t)ahead->texel * S]);
            __builtin_prefetch(&load[ahead->index * S]);
        }
        const sim_event *e = &ch->events[k];
        wx_dirt_map *map = &sim->dirt[e->camera];
        double *p = &load[e->index * S];
        float *weight = &sim->particles.weight[e->index];
        if (e->flags & EVENT_LINE) {
            wx_dirt_map_exchange_line(map, e->from, e->texel, p, weight);
        } else {
            wx_dirt_map_exchange(map, e->texel, p, weight);
        }
        if (e->flags & EVENT_DIES) {
            wx_dirt_map_deposit_all(map, e->texel, p, weight);
            if ((e->flags & EVENT_KIND_MASK) == WX_IMPACT_ABSORB) {
                sim->stats.absorbed++;
            } else {
                sim->stats.settled++;
            }
        }
        sim->stats.collisions++;
        record_hit(sim, e);
    }
}

// Applies the chunks that are done, in order, up to the first that is not (or,
// with `wait`, up to the last, waiting for each). Only the calling thread of
// wx_sim_step runs this, so the maps, the loads and the statistics have one
// writer, and the order is the particles' whatever thread stepped them.
static void apply_ready(wx_sim *sim, bool wait)
{
    while (sim->applied < sim->chunk_count) {
        const sim_chunk *ch = &sim->chunks[sim->applied];
        if (!atomic_load_explicit(&ch->done, memory_order_acquire)) {
            if (!wait) {
                return;
            }
            sched_yield(); // another thread is finishing this chunk
            continue;
        }
        apply_chunk(sim, ch);
        sim->applied++;
    }
}

// --- the thread pool -----------------------------------------------------------

// Steps chunks [begin, end) on pool worker `worker`; the calling thread (worker
// 0) also applies what is ready after each of its chunks.
static void step_chunks(int64_t begin, int64_t end, int worker, void *context)
{
    wx_sim *sim = context;
    sim_worker *w = &sim->workers[worker];
    int64_t n = sim->particles.count;
    for (int64_t c = begin; c < end; ++c) {
        int64_t first = c * sim->chunk_particles;
        int64_t last = n - first < sim->chunk_particles ? n : first + sim->chunk_particles;
        w->chunk = &sim->chunks[c];
        step_range(sim, w, first, last);
        atomic_store_explicit(&sim->chunks[c].done, 1, memory_order_release);
        if (worker == 0) {
            apply_ready(sim, false);
        }
    }
}

// One chunk record per chunk_particles particles, reset for a new step. Records
// keep their buffers from step to step: after the first steps nothing is
// allocated.
static wx_result prepare_chunks(wx_sim *sim, wx_error *err)
{
    // A small population (an emitter's first steps) goes in smaller chunks, at
    // least CHUNKS_PER_THREAD a thread, so that no thread waits for one long
    // chunk: whole blocks, at most the configured size. Results do not depend
    // on the chunk size (the events are applied in particle order).
    int64_t size = sim->chunk_limit;
    if (sim->thread_count > 1) {
        int64_t parts = (int64_t)sim->thread_count * CHUNKS_PER_THREAD;
        int64_t share = (sim->particles.count + parts - 1) / parts;
        share = (share + WX_PARTICLE_BLOCK - 1) / WX_PARTICLE_BLOCK * WX_PARTICLE_BLOCK;
        size = share < WX_PARTICLE_BLOCK ? WX_PARTICLE_BLOCK : share < size ? share : size;
    }
    sim->chunk_particles = size;
    int64_t count = (sim->particles.count + sim->chunk_particles - 1) / sim->chunk_particles;
    if (count > sim->chunk_capacity) {
        int64_t capacity = count + count / 2;
        sim_chunk *bigger = realloc(sim->chunks, (size_t)capacity * sizeof *bigger);
        if (bigger == NULL) {
            return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (collision events)");
        }
        memset(bigger + sim->chunk_capacity, 0,
               (size_t)(capacity - sim->chunk_capacity) * sizeof *bigger);
        for (int64_t c = sim->chunk_capacity; c < capacity; ++c) {
            atomic_init(&bigger[c].done, 0);
        }
        sim->chunks = bigger;
        sim->chunk_capacity = capacity;
    }
    for (int64_t c = 0; c < count; ++c) {
        sim->chunks[c].event_count = 0;
        sim->chunks[c].dead_count = 0;
        atomic_store_explicit(&sim->chunks[c].done, 0, memory_order_relaxed);
    }
    sim->chunk_count = count;
    sim->applied = 0;
    for (int t = 0; t < sim->thread_count; ++t) {
        sim->workers[t].failed = false;
    }
    return WX_OK;
}

// Steps every particle and applies every event (phases 1 and 2): the pool's
// workers claim chunks in turn, the calling thread applies them in order.
static void run_workers(wx_sim *sim)
{
    wx_pool_for(sim->pool, sim->chunk_count, 1, step_chunks, sim);
    apply_ready(sim, true);
}

// --- the serial phases -----------------------------------------------------------

// The coarse test tries first the camera that cleared most segments in the last
// step (it stops once a block is cleared). Only speed depends on this order.
static void reorder_cameras(wx_sim *sim)
{
    uint64_t credit[WX_MAX_INPUT_CAMERAS] = { 0 };
    for (int t = 0; t < sim->thread_count; ++t) {
        for (int c = 0; c < sim->input_count; ++c) {
            credit[c] += sim->workers[t].credit[c];
            sim->workers[t].credit[c] = 0;
        }
    }
    for (int a = 1; a < sim->input_count; ++a) { // insertion sort, most credit first
        int c = sim->camera_order[a], b = a;
        for (; b > 0 && credit[sim->camera_order[b - 1]] < credit[c]; --b) {
            sim->camera_order[b] = sim->camera_order[b - 1];
        }
        sim->camera_order[b] = c;
    }
}

static void remove_dead(wx_sim *sim)
{
    for (int64_t c = 0; c < sim->chunk_count; ++c) {
        const sim_chunk *ch = &sim->chunks[c];
        for (int64_t k = 0; k < ch->dead_count; ++k) {
            if (ch->dead[k] & 1) {
                int64_t i = ch->dead[k] >> 1;
                sim->stats.escaped++;
                for (int s = 0; s < sim->substances; ++s) {
                    sim->stats.substance[s].escaped +=
                        sim->particles.load[i * sim->substances + s];
                }
                // An emitter's particle that escapes with all its collisions left
                // never hit anything (spawned particles are not counted).
                uint64_t e = sim->particles.id[i] >> 48;
                if (e < (uint64_t)sim->emitter_count &&
                    sim->particles.collisions_left[i] ==
                        (uint32_t)sim->emitters[e].max_collisions) {
                    sim->stats.escaped_without_hit++;
                }
            }
        }
    }
    // Highest index first, so the particle moved into a hole is always alive.
    for (int64_t c = sim->chunk_count - 1; c >= 0; --c) {
        const sim_chunk *ch = &sim->chunks[c];
        for (int64_t k = ch->dead_count - 1; k >= 0; --k) {
            wx_particles_remove(&sim->particles, ch->dead[k] >> 1);
        }
    }
}

static uint32_t max_collisions_of(int value)
{
    return value >= 1 ? (uint32_t)value : 1u;
}

// How many particles emitter `em` has emitted after global step `step`: every
// iteration emits as start and end say, measured from the iteration's start
// (docs/design.md section 9); after the last iteration nothing more.
static int64_t emitted_after(const wx_sim *sim, const wx_emitter *em, int64_t step)
{
    const wx_scene *scene = sim->scene;
    int64_t steps = scene->steps > 0 ? scene->steps : 1;
    int64_t iterations = scene->iterations > 1 ? scene->iterations : 1;
    int64_t done = step > 0 ? (step - 1) / steps : 0; // whole iterations before this step's
    if (done >= iterations) {
        done = iterations - 1;
        step = iterations * steps;
    }
    int64_t per_iteration = done > 0 ? wx_emitter_count_at(em, (double)steps * sim->dt) : 0;
    return done * per_iteration + wx_emitter_count_at(em, (double)(step - done * steps) * sim->dt);
}

static wx_result emit(wx_sim *sim, int64_t step, wx_error *err)
{
    for (int e = 0; e < sim->emitter_count; ++e) {
        const wx_emitter *em = &sim->emitters[e];
        int64_t target = emitted_after(sim, em, step);
        int64_t count = target - sim->emitted[e];
        if (count <= 0) {
            continue;
        }
        if (!wx_particles_reserve(&sim->particles, sim->particles.count + count)) {
            return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (%lld particles)",
                                (long long)(sim->particles.count + count));
        }
        for (int64_t k = 0; k < count; ++k) {
            uint64_t id = wx_particle_id((uint32_t)e, (uint64_t)(sim->emitted[e] + k));
            float pos[3], vel[3];
            wx_emitter_sample(em, sim->seed, id, pos, vel);
            double load[WX_MAX_SUBSTANCES];
            for (int s = 0; s < sim->substances; ++s) {
                load[s] = em->load[s];
            }
            if (wx_particles_push(&sim->particles, pos, vel, em->mass, load, id,
                                  max_collisions_of(em->max_collisions)) < 0) {
                sim->emitted[e] += k;
                sim->stats.particles_emitted += k;
                return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (particle masses)");
            }
            for (int s = 0; s < sim->substances; ++s) {
                sim->stats.substance[s].emitted += em->load[s];
            }
        }
        sim->emitted[e] = target;
        sim->stats.particles_emitted += count;
    }
    return WX_OK;
}

// --- ageing -----------------------------------------------------------------------

// Runs `rules` on one texel's amounts a[] (and its baseline b[], may be NULL),
// in order, each seeing the result of the one before (docs/design.md section 9);
// `area` is the surface the texel grows on.
static void run_rules(const wx_rule *rules, int count, double *a, double *b, double area,
                      wx_substance_ledger *ledger)
{
    for (int k = 0; k < count; ++k) {
        const wx_rule *r = &rules[k];
        int s = r->substance;
        switch (r->kind) {
        case WX_RULE_TRANSFER: {
            double t = (double)r->rate * a[s];
            a[s] -= t;
            a[r->to] += t;
            ledger[s].transferred_out += t;
            ledger[r->to].transferred_in += t;
            if (b != NULL) {
                double tb = (double)r->rate * b[s];
                b[s] -= tb;
                b[r->to] += tb;
            }
            break;
        }
        case WX_RULE_DECAY: {
            double d = (double)r->rate * a[s];
            a[s] -= d;
            ledger[s].decayed += d;
            if (b != NULL) {
                b[s] -= (double)r->rate * b[s];
            }
            break;
        }
        case WX_RULE_GROW: {
            double g = (double)r->amount * area;
            a[s] += g;
            ledger[s].grown += g;
            if (b != NULL) {
                b[s] += g;
            }
            break;
        }
        }
    }
}

// After an iteration's last step: the global rules, then the texel's own
// surface's, on every surface texel of every input camera, in texel order (one
// thread: the ledger's sums are the same for any thread count).
static void age(wx_sim *sim)
{
    const wx_scene *scene = sim->scene;
    bool surface_rules = wx_scene_has_surface_rules(scene);
    if (scene->rule_count == 0 && !surface_rules) {
        return;
    }
    // Surface rules by global surface index.
    const wx_surface **by_index = sim->surfaces;
    const int known = wx_scene_surface_count(scene);
    int S = sim->substances;
    for (int c = 0; c < sim->view_count; ++c) {
        wx_dirt_map *map = &sim->dirt[c];
        size_t n = (size_t)map->width * (size_t)map->height;
        const float *depth = map->depth;
        const float *surface = sim->surface_of[c];
        const float *area = sim->grow_area[c];
        double *baseline = sim->baseline[c];
        for (size_t t = 0; t < n; ++t) {
            if (depth != NULL && !isfinite(depth[t])) {
                continue;
            }
            wx_dirt_texel *x = &map->texels[t * (size_t)S];
            double a[WX_MAX_SUBSTANCES];
            for (int s = 0; s < S; ++s) {
                a[s] = x[s].dirt;
            }
            double *b = baseline != NULL ? &baseline[t * (size_t)S] : NULL;
            double grow = area != NULL ? (double)area[t] : 0.0;
            run_rules(scene->rules, scene->rule_count, a, b, grow, sim->stats.substance);
            int id = surface != NULL ? (int)surface[t] - 1 : -1;
            if (id >= 0 && id < known) {
                run_rules(by_index[id]->rules, by_index[id]->rule_count, a, b, grow,
                          sim->stats.substance);
            }
            for (int s = 0; s < S; ++s) {
                x[s].dirt = a[s];
            }
        }
    }
}

wx_result wx_sim_step(wx_sim *sim, wx_error *err)
{
    int64_t n = sim->particles.count;
    if (n > 0) {
        wx_result r = prepare_chunks(sim, err);
        if (r != WX_OK) {
            return r;
        }
        run_workers(sim);
        for (int t = 0; t < sim->thread_count; ++t) {
            if (sim->workers[t].failed) {
                return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (collision events)");
            }
        }
        sim->stats.particle_steps += n;
        remove_dead(sim);
        reorder_cameras(sim);
    }
    sim->step++;
    wx_result r = emit(sim, sim->step, err);
    const wx_scene *scene = sim->scene;
    if (r == WX_OK && scene->steps > 0 && sim->step % scene->steps == 0 &&
        sim->iterations_done < (scene->iterations > 1 ? scene->iterations : 1)) {
        age(sim);
        sim->iterations_done++;
    }
    return r;
}

int64_t wx_sim_iterations_done(const wx_sim *sim)
{
    return sim->iterations_done;
}

// --- creation --------------------------------------------------------------------

wx_sim_def wx_default_sim_def(const wx_scene *scene)
{
    wx_sim_def config;
    memset(&config, 0, sizeof config);
    config.seed = scene->seed;
    return config;
}

static wx_result start_pool(wx_sim *sim, wx_error *err)
{
    wx_result r = wx_pool_create(sim->thread_count, &sim->pool, err);
    if (r != WX_OK) {
        return r;
    }
    sim->thread_count = wx_pool_threads(sim->pool); // fewer when a thread could not start
    sim->workers = calloc((size_t)sim->thread_count, sizeof *sim->workers);
    if (sim->workers == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (threads)");
    }
    return WX_OK;
}

// The input camera of view v.
static int view_camera(const wx_sim *sim, int v)
{
    int c = 0;
    while (c + 1 < sim->input_count && sim->view_base[c + 1] <= v) {
        c++;
    }
    return c;
}

// View c's ageing state: the baseline (amounts without the particles)
// when the scene has rules, and the area Grow multiplies: the bake's record of
// the area the camera owns or, for maps the bake did not write, the area every
// surface texel covers (texel area / |N.view|, clamped as the bake clamps it).
static wx_result setup_ageing(wx_sim *sim, int c, wx_error *err)
{
    const wx_scene *scene = sim->scene;
    const wx_maps *m = &sim->views[c];
    size_t n = (size_t)m->width * (size_t)m->height;
    int S = sim->substances;
    sim->surface_of[c] = m->surface;
    if (scene->rule_count == 0 && !wx_scene_has_surface_rules(scene)) {
        return WX_OK;
    }
    sim->baseline[c] = malloc((n > 0 ? n : 1) * (size_t)S * sizeof(double));
    if (sim->baseline[c] == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (ageing)");
    }
    for (size_t t = 0; t < n * (size_t)S; ++t) {
        sim->baseline[c][t] = sim->dirt[c].texels[t].dirt;
    }
    if (!wx_scene_has_grow(scene)) {
        return WX_OK;
    }
    if (m->area != NULL) {
        sim->grow_area[c] = m->area;
        return WX_OK;
    }
    float *area = malloc((n > 0 ? n : 1) * sizeof *area);
    if (area == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (ageing)");
    }
    const wx_camera *cam = &scene->cameras[sim->input_camera[view_camera(sim, c)]].camera;
    float view[3], fw, fh;
    wx_camera_view_dir(cam, view);
    wx_camera_frame_size(cam, &fw, &fh);
    float texel_area = (fw / (float)m->width) * (fh / (float)m->height);
    for (size_t t = 0; t < n; ++t) {
        const float *nn = &m->normal[3 * t];
        float cosine = fabsf(nn[0] * view[0] + nn[1] * view[1] + nn[2] * view[2]);
        area[t] = wx_depth_is_empty(m->depth[t]) ? 0.0f : texel_area / fmaxf(cosine, 1e-3f);
    }
    sim->grow_area[c] = area;
    return WX_OK;
}

wx_result wx_sim_create(const wx_scene *scene, const wx_sim_def *config, wx_sim **out,
                        wx_error *err)
{
    *out = NULL;
    wx_sim *sim = calloc(1, sizeof *sim);
    if (sim == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (simulation)");
    }
    sim->scene = scene;
    sim->seed = config->seed;
    sim->dt = scene->time_step;
    sim->params = scene->collider;
    for (int k = 0; k < 3; ++k) {
        sim->bbox_lo[k] = scene->bbox_center[k] - 0.5f * scene->bbox_size;
        sim->bbox_hi[k] = scene->bbox_center[k] + 0.5f * scene->bbox_size;
    }
    sim->emitter_count = scene->emitter_count;
    sim->emitters = scene->emitters;
    sim->substances = scene->substance_count > 1 ? scene->substance_count : 1;
    sim->particles.substances = sim->substances;
    sim->stats.substance_count = sim->substances;
    sim->thread_count = config->threads > 0 ? config->threads : wx_cpu_count();
    sim->hit_capacity = config->hit_capacity > 0 ? config->hit_capacity : DEFAULT_HIT_CAPACITY;
    int64_t chunk = config->chunk_particles > 0 ? config->chunk_particles : DEFAULT_CHUNK;
    sim->chunk_limit = (chunk + WX_PARTICLE_BLOCK - 1) / WX_PARTICLE_BLOCK * WX_PARTICLE_BLOCK;
    sim->chunk_particles = sim->chunk_limit;

    wx_result r = WX_OK;
    if (!(sim->dt > 0.0) || !isfinite(sim->dt)) {
        r = wx_fail(err, WX_CAUSE_BAD_VALUE, "%s: the time step must be positive", scene->path);
    } else if (scene->emitter_count >= PSEUDO_EMITTER) {
        r = wx_fail(err, WX_CAUSE_TOO_MANY, "%s: too many emitters (%d)", scene->path,
                         scene->emitter_count);
    }
    if (r == WX_OK) {
        sim->emitted = calloc((size_t)(scene->emitter_count + 1), sizeof *sim->emitted);
        sim->input_camera = calloc((size_t)(scene->camera_count + 1), sizeof *sim->input_camera);
        sim->hits = calloc((size_t)sim->hit_capacity, sizeof *sim->hits);
        if (sim->emitted == NULL || sim->input_camera == NULL || sim->hits == NULL) {
            r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (simulation)");
        }
    }
    if (r == WX_OK) {
        for (int c = 0; c < scene->camera_count; ++c) {
            if (!scene->cameras[c].is_output) {
                sim->input_camera[sim->input_count++] = c;
            }
        }
        for (int c = 0; c < WX_MAX_INPUT_CAMERAS; ++c) {
            sim->camera_order[c] = c;
        }
        r = wx_forces_init(&sim->forces, scene->fields, scene->field_count, sim->seed, err);
    }
    if (r == WX_OK && config->maps == NULL && sim->input_count > 0) {
        r = wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "simulation: no maps for the %d input cameras",
                    sim->input_count);
    }
    sim->maps = config->maps;
    wx_camera *cameras = NULL;
    if (r == WX_OK) {
        for (int c = 0; c < sim->input_count; ++c) {
            sim->view_base[c] = sim->view_count;
            sim->view_count += wx_maps_layers(&sim->maps[c]);
        }
        sim->view_base[sim->input_count] = sim->view_count;
        int V = sim->view_count;
        cameras = calloc((size_t)(sim->input_count + 1), sizeof *cameras);
        sim->views = calloc((size_t)(V + 1), sizeof *sim->views);
        sim->dirt = calloc((size_t)(V + 1), sizeof *sim->dirt);
        sim->baseline = calloc((size_t)(V + 1), sizeof *sim->baseline);
        sim->grow_area = calloc((size_t)(V + 1), sizeof *sim->grow_area);
        sim->surface_of = calloc((size_t)(V + 1), sizeof *sim->surface_of);
        sim->surfaces = wx_scene_surfaces_by_index(scene);
        for (int c = 0; sim->views != NULL && c < sim->input_count; ++c) {
            for (int k = 0; k < wx_maps_layers(&sim->maps[c]); ++k) {
                wx_maps_layer_view(&sim->maps[c], k, &sim->views[sim->view_base[c] + k]);
            }
        }
        if (cameras == NULL || sim->views == NULL || sim->dirt == NULL || sim->baseline == NULL ||
            sim->grow_area == NULL || sim->surface_of == NULL || sim->surfaces == NULL) {
            r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (simulation)");
        }
    }
    if (r == WX_OK) {
        for (int c = 0; c < sim->input_count; ++c) {
            cameras[c] = scene->cameras[sim->input_camera[c]].camera;
        }
        r = wx_collider_init(&sim->collider, cameras, sim->maps, sim->input_count,
                             config->nearest_depth, err);
    }
    free(cameras);
    if (r == WX_OK) {
        uint64_t total = 0;
        for (int c = 0; c < sim->view_count; ++c) {
            sim->slide_base[c] = (uint32_t)total;
            total += (uint64_t)sim->views[c].width * (uint64_t)sim->views[c].height;
            if (total >= WX_NO_SLIDE) {
                r = wx_fail(err, WX_CAUSE_MAP_SIZE,
                            "the input maps hold %llu texels or more in all (the "
                            "simulation numbers at most %llu)",
                            (unsigned long long)total, (unsigned long long)WX_NO_SLIDE - 1);
                break;
            }
        }
        sim->slide_base[sim->view_count] = (uint32_t)total;
    }
    for (int c = 0; r == WX_OK && c < sim->view_count; ++c) {
        const wx_maps *m = &sim->views[c];
        if (wx_maps_substances(m) != sim->substances) {
            r = wx_fail(err, WX_CAUSE_BAD_ARGUMENT,
                        "simulation: the maps of camera '%s' hold %d substances, the scene %d",
                        scene->cameras[sim->input_camera[view_camera(sim, c)]].name,
                        wx_maps_substances(m),
                        sim->substances);
            break;
        }
        // The collider's copy of a one-layer camera's depth (empty texels
        // +inf); a layered camera's copy is reordered (its solids' outline),
        // so its views read their own planes.
        int cam = view_camera(sim, c);
        const float *depth = wx_maps_layers(&sim->maps[cam]) > 1 ? m->depth
                                                                 : sim->collider.cameras[cam].depth;
        r = wx_dirt_map_init(&sim->dirt[c], m->width, m->height, sim->substances, m->dirt,
                             m->deposit, m->erosion, scene->collider.deposit,
                             scene->collider.erosion, depth, err);
        if (r == WX_OK) {
            for (int s = 0; s < sim->substances; ++s) {
                sim->stats.substance[s].initial_surface += wx_dirt_map_total(&sim->dirt[c], s);
            }
            r = setup_ageing(sim, c, err);
        }
    }
    if (r == WX_OK) {
        r = start_pool(sim, err);
    }
    if (r != WX_OK) {
        wx_sim_destroy(sim);
        return r;
    }
    *out = sim;
    return WX_OK;
}

void wx_sim_destroy(wx_sim *sim)
{
    if (sim == NULL) {
        return;
    }
    wx_pool_destroy(sim->pool);
    if (sim->workers != NULL) {
        for (int t = 0; t < sim->thread_count; ++t) {
            free(sim->workers[t].cands);
        }
        free(sim->workers);
    }
    for (int64_t c = 0; c < sim->chunk_capacity; ++c) {
        free(sim->chunks[c].events);
        free(sim->chunks[c].dead);
    }
    free(sim->chunks);
    if (sim->dirt != NULL) {
        for (int c = 0; c < sim->view_count; ++c) {
            wx_dirt_map_free(&sim->dirt[c]);
        }
        free(sim->dirt);
    }
    for (int c = 0; c < sim->view_count; ++c) {
        if (sim->baseline != NULL) {
            free(sim->baseline[c]);
        }
        if (sim->grow_area != NULL && sim->grow_area[c] != NULL &&
            (sim->views == NULL || sim->grow_area[c] != sim->views[c].area)) {
            free(sim->grow_area[c]);
        }
    }
    free(sim->views);
    free(sim->baseline);
    free(sim->grow_area);
    free(sim->surface_of);
    free(sim->surfaces);
    wx_collider_free(&sim->collider);
    wx_forces_free(&sim->forces);
    wx_particles_free(&sim->particles);
    free(sim->emitted);
    free(sim->input_camera);
    free(sim->hits);
    free(sim);
}

// --- access -----------------------------------------------------------------------

int64_t wx_sim_step_count(const wx_sim *sim)
{
    return sim->step;
}

double wx_sim_time(const wx_sim *sim)
{
    return (double)sim->step * sim->dt;
}

void wx_sim_particles(const wx_sim *sim, wx_particle_view *view)
{
    const wx_particles *P = &sim->particles;
    view->count = P->count;
    view->x = P->x;
    view->y = P->y;
    view->z = P->z;
    view->vx = P->vx;
    view->vy = P->vy;
    view->vz = P->vz;
    view->load = P->load;
}

int wx_sim_recent_hits(const wx_sim *sim, wx_hit_sample *out, int max)
{
    int n = sim->hit_count < max ? sim->hit_count : max;
    // The newest n, oldest first.
    int first = sim->hit_next - n;
    if (first < 0) {
        first += sim->hit_capacity;
    }
    for (int k = 0; k < n; ++k) {
        out[k] = sim->hits[(first + k) % sim->hit_capacity];
    }
    return n;
}

void wx_sim_get_stats(const wx_sim *sim, wx_sim_stats *stats)
{
    *stats = sim->stats;
    stats->alive = sim->particles.count;
    // Of the emitters' particles still flying, those that have hit nothing yet.
    stats->alive_without_hit = 0;
    for (int64_t i = 0; i < sim->particles.count; ++i) {
        uint64_t e = sim->particles.id[i] >> 48;
        stats->alive_without_hit += e < (uint64_t)sim->emitter_count &&
                                    sim->particles.collisions_left[i] ==
                                        (uint32_t)sim->emitters[e].max_collisions;
    }
    stats->iterations = sim->iterations_done;
    int S = sim->substances;
    for (int s = 0; s < S; ++s) {
        wx_substance_ledger *l = &stats->substance[s];
        l->final_surface = 0.0;
        for (int c = 0; c < sim->view_count; ++c) {
            l->final_surface += wx_dirt_map_total(&sim->dirt[c], s);
        }
        l->in_flight = 0.0;
        for (int64_t i = 0; i < sim->particles.count; ++i) {
            l->in_flight += sim->particles.load[i * S + s];
        }
    }
    int d = sim->scene->dirt_substance;
    stats->dirt_index = d;
    for (int s = 0; s < S; ++s) {
        snprintf(stats->substance_names[s], sizeof stats->substance_names[s], "%s",
                 sim->scene->substances[s]);
    }
    const wx_substance_ledger *dirt = d >= 0 && d < S ? &stats->substance[d] : NULL;
    stats->dirt_initial_surface = dirt != NULL ? dirt->initial_surface : 0.0;
    stats->dirt_emitted = dirt != NULL ? dirt->emitted : 0.0;
    stats->dirt_final_surface = dirt != NULL ? dirt->final_surface : 0.0;
    stats->dirt_in_flight = dirt != NULL ? dirt->in_flight : 0.0;
    stats->dirt_escaped = dirt != NULL ? dirt->escaped : 0.0;
}

const double *wx_sim_baseline(const wx_sim *sim, int input)
{
    return sim->baseline[input];
}

int wx_sim_input_count(const wx_sim *sim)
{
    return sim->view_count;
}

int wx_sim_camera_views(const wx_sim *sim, int camera, int *first)
{
    *first = sim->view_base[camera];
    return sim->view_base[camera + 1] - sim->view_base[camera];
}

int wx_sim_view_camera(const wx_sim *sim, int view, int *layer)
{
    int c = view_camera(sim, view);
    if (layer != NULL) {
        *layer = view - sim->view_base[c];
    }
    return c;
}

const wx_dirt_map *wx_sim_dirt_map(const wx_sim *sim, int input)
{
    return &sim->dirt[input];
}

int wx_sim_particle_bytes(const wx_sim *sim)
{
    return wx_particles_slot_bytes(&sim->particles);
}

wx_result wx_sim_spawn(wx_sim *sim, const float position[3], const float velocity[3],
                       float mass, double load, int max_collisions, wx_error *err)
{
    if (!(mass > 0.0f) || !isfinite(mass)) {
        return wx_fail(err, WX_CAUSE_BAD_VALUE, "particle mass must be positive");
    }
    if (!wx_particles_reserve(&sim->particles, sim->particles.count + 1)) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (particles)");
    }
    uint64_t id = wx_particle_id(PSEUDO_EMITTER, sim->spawned);
    double loads[WX_MAX_SUBSTANCES] = { load };
    if (wx_particles_push(&sim->particles, position, velocity, mass, loads, id,
                          max_collisions_of(max_collisions)) < 0) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (particle masses)");
    }
    sim->spawned++;
    sim->stats.particles_emitted++;
    sim->stats.substance[0].emitted += load;
    return WX_OK;
}
