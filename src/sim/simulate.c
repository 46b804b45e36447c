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
//
// With several ranks (MPI, docs/scale-out.md) each rank steps only its share
// of the particles in phase 1, and phase 2 waits for the exchange (exchange.c)
// that gives every rank every rank's moved particles, events and deaths: every
// rank then applies them all, in the same particle order.
//
// The step kernel (phase 1) is in step.c, the ageing rules in ageing.c; this
// file runs the pool, applies the events in order, emits, and creates the
// solver.
#include "sim/simulate.h"

#include <math.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/dist.h"
#include "sim/solver_internal.h"

enum {
    DEFAULT_HIT_CAPACITY = 4096,
    PSEUDO_EMITTER = 0xFFFF, ///< emitter index of particles added by wx_sim_spawn
    DEFAULT_CHUNK = 8192,    ///< particles a thread takes at a time (a multiple of the block)
    CHUNKS_PER_THREAD = 4,   ///< the fewest chunks a thread gets while the particles allow
};

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
    int64_t n = sim->own_end; // this rank's share: all of them with one rank
    for (int64_t c = begin; c < end; ++c) {
        int64_t first = sim->own_begin + c * sim->chunk_particles;
        int64_t last = n - first < sim->chunk_particles ? n : first + sim->chunk_particles;
        w->chunk = &sim->chunks[c];
        sim_step_range(sim, w, first, last);
        atomic_store_explicit(&sim->chunks[c].done, 1, memory_order_release);
        if (worker == 0 && sim->ranks == 1) {
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
    sim_share(sim);
    int64_t particles = sim->own_end - sim->own_begin;
    int64_t size = sim->chunk_limit;
    if (sim->thread_count > 1) {
        int64_t parts = (int64_t)sim->thread_count * CHUNKS_PER_THREAD;
        int64_t share = (particles + parts - 1) / parts;
        share = (share + WX_PARTICLE_BLOCK - 1) / WX_PARTICLE_BLOCK * WX_PARTICLE_BLOCK;
        size = share < WX_PARTICLE_BLOCK ? WX_PARTICLE_BLOCK : share < size ? share : size;
    }
    sim->chunk_particles = size;
    int64_t count = (particles + sim->chunk_particles - 1) / sim->chunk_particles;
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

// Steps this rank's particles and, with one rank, applies every event (phases
// 1 and 2): the pool's workers claim chunks in turn, the calling thread applies
// them in order.
static void run_workers(wx_sim *sim)
{
    wx_pool_for(sim->pool, sim->chunk_count, 1, step_chunks, sim);
    if (sim->ranks == 1) {
        apply_ready(sim, true);
    }
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

// The deaths of the step's records `chunks[0, count)` (in particle order).
static void remove_dead(wx_sim *sim, const sim_chunk *chunks, int64_t count)
{
    for (int64_t c = 0; c < count; ++c) {
        const sim_chunk *ch = &chunks[c];
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
    for (int64_t c = count - 1; c >= 0; --c) {
        const sim_chunk *ch = &chunks[c];
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
    const wx_tile_def *tile = &sim->scene->tile;
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
        int64_t pushed = 0;
        for (int64_t k = 0; k < count; ++k) {
            uint64_t id = wx_particle_id((uint32_t)e, (uint64_t)(sim->emitted[e] + k));
            float pos[3], vel[3];
            wx_emitter_sample(em, sim->seed, id, pos, vel);
            // A tile flies only the particles that start within its halo; the
            // others are drawn all the same, so every particle keeps its index
            // (and random stream) of the whole scene (docs/tiles.md).
            if (!wx_tile_keeps(tile, pos[0], pos[2])) {
                continue;
            }
            double load[WX_MAX_SUBSTANCES];
            for (int s = 0; s < sim->substances; ++s) {
                load[s] = em->load[s];
            }
            if (wx_particles_push(&sim->particles, pos, vel, em->mass, load, id,
                                  max_collisions_of(em->max_collisions)) < 0) {
                sim->emitted[e] += k;
                sim->stats.particles_emitted += pushed;
                return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (particle masses)");
            }
            pushed++;
            if (tile->present && wx_tile_owns(tile, pos[0], pos[2])) {
                sim->stats.tile_particles++;
            }
            for (int s = 0; s < sim->substances; ++s) {
                sim->stats.substance[s].emitted += em->load[s];
            }
        }
        sim->emitted[e] = target;
        sim->stats.particles_emitted += pushed;
    }
    return WX_OK;
}

// --- the step ---------------------------------------------------------------------

wx_result wx_sim_step(wx_sim *sim, wx_error *err)
{
    int64_t n = sim->particles.count;
    if (n > 0) {
        // Every rank takes this branch and the same calls below (collectives).
        wx_result r = prepare_chunks(sim, err);
        if (r != WX_OK && sim->ranks == 1) {
            return r;
        }
        if (r != WX_OK) { // told to the other ranks by the exchange
            sim->chunk_count = 0;
            sim->workers[0].failed = true;
        } else {
            run_workers(sim);
        }
        if (sim->ranks > 1) {
            // Every rank's records, then all of them applied here in order.
            r = sim_exchange(sim, err);
            if (r != WX_OK) {
                return r;
            }
            apply_chunk(sim, &sim->all);
        }
        for (int t = 0; t < sim->thread_count; ++t) {
            if (sim->workers[t].failed) {
                return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (collision events)");
            }
        }
        sim->stats.particle_steps += n;
        if (sim->ranks > 1) {
            remove_dead(sim, &sim->all, 1);
        } else {
            remove_dead(sim, sim->chunks, sim->chunk_count);
        }
        reorder_cameras(sim);
    }
    sim->step++;
    wx_result r = emit(sim, sim->step, err);
    const wx_scene *scene = sim->scene;
    if (r == WX_OK && scene->steps > 0 && sim->step % scene->steps == 0 &&
        sim->iterations_done < (scene->iterations > 1 ? scene->iterations : 1)) {
        r = sim_age(sim, err);
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
    // A tile's particles escape where they leave its halo: beyond it the tile's
    // cropped cameras know less than the whole scene's, and what flies there
    // lands in another tile (docs/tiles.md).
    wx_scene_particle_box(scene, sim->bbox_lo, sim->bbox_hi);
    sim->emitter_count = scene->emitter_count;
    sim->emitters = scene->emitters;
    sim->substances = scene->substance_count > 1 ? scene->substance_count : 1;
    sim->particles.substances = sim->substances;
    sim->stats.substance_count = sim->substances;
    sim->stats.tiled = scene->tile.present;
    sim->thread_count = config->threads > 0 ? config->threads : wx_cpu_count();
    sim->hit_capacity = config->hit_capacity > 0 ? config->hit_capacity : DEFAULT_HIT_CAPACITY;
    int64_t chunk = config->chunk_particles > 0 ? config->chunk_particles : DEFAULT_CHUNK;
    sim->chunk_limit = (chunk + WX_PARTICLE_BLOCK - 1) / WX_PARTICLE_BLOCK * WX_PARTICLE_BLOCK;
    sim->chunk_particles = sim->chunk_limit;
    sim->ranks = config->distributed ? wx_dist_size() : 1;

    wx_result r = WX_OK;
    if (!(sim->dt > 0.0) || !isfinite(sim->dt)) {
        r = wx_fail(err, WX_CAUSE_BAD_VALUE, "%s: the time step must be positive", scene->path);
    } else if (scene->emitter_count >= PSEUDO_EMITTER) {
        r = wx_fail(err, WX_CAUSE_TOO_MANY, "%s: too many emitters (%d)", scene->path,
                         scene->emitter_count);
    }
    if (sim->ranks > 1) {
        sim->rank_counts = calloc((size_t)sim->ranks * 6, sizeof *sim->rank_counts);
        if (sim->rank_counts == NULL) {
            wx_dist_abort(WX_FAIL); // the other ranks would wait in sim_agree
        }
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
    bool shared = config->shared_collider != NULL && !config->nearest_depth;
    if (r == WX_OK) {
        for (int c = 0; c < sim->input_count; ++c) {
            cameras[c] = scene->cameras[sim->input_camera[c]].camera;
        }
        r = shared ? wx_collider_view(&sim->collider, config->shared_collider, sim->maps, err)
                   : wx_collider_init(&sim->collider, cameras, sim->maps, sim->input_count,
                                      config->nearest_depth, err);
    }
    if (r == WX_OK && scene->tile.present && !shared) {
        // The tile's cameras are cut to where its particles live.
        const double lo[3] = { sim->bbox_lo[0], sim->bbox_lo[1], sim->bbox_lo[2] };
        const double hi[3] = { sim->bbox_hi[0], sim->bbox_hi[1], sim->bbox_hi[2] };
        wx_collider_frame_box(&sim->collider, lo, hi);
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
                        scene->cameras[sim->input_camera[sim_view_camera(sim, c)]].name,
                        wx_maps_substances(m), sim->substances);
            break;
        }
        // The collider's copy of a one-layer camera's depth (empty texels
        // +inf); a layered camera's copy is reordered (its solids' outline),
        // so its views read their own planes.
        int cam = sim_view_camera(sim, c);
        const float *depth = wx_maps_layers(&sim->maps[cam]) > 1 ? m->depth
                                                                 : sim->collider.cameras[cam].depth;
        // Each texel's contact, |N . view| (docs/physics.md, "Dirt exchange").
        const float *back = sim->collider.cameras[cam].back;
        float bl = sqrtf(back[0] * back[0] + back[1] * back[1] + back[2] * back[2]);
        float view[3] = { 0.0f, 0.0f, 0.0f };
        for (int k = 0; k < 3 && bl > 0.0f; ++k) {
            view[k] = back[k] / bl;
        }
        r = wx_dirt_map_init(&sim->dirt[c], m->width, m->height, sim->substances, m->dirt,
                             m->deposit, m->erosion, scene->collider.deposit,
                             scene->collider.erosion, depth, bl > 0.0f ? m->normal : NULL, view,
                             err);
        if (r == WX_OK) {
            for (int s = 0; s < sim->substances; ++s) {
                sim->stats.substance[s].initial_surface += wx_dirt_map_total(&sim->dirt[c], s);
            }
            r = sim_setup_ageing(sim, c, err);
        }
    }
    if (r == WX_OK) {
        r = start_pool(sim, err);
    }
    if (sim->ranks > 1) {
        r = sim_agree(sim, r, err);
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
    free(sim->all.events);
    free(sim->all.dead);
    free(sim->rank_counts);
    free(sim->exchange);
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
    sim_surface_free(sim->surface);
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
    int c = sim_view_camera(sim, view);
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
