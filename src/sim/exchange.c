// exchange.c: the simulation's step spread over ranks (docs/scale-out.md,
// docs/design.md section 16). Each rank steps its share of the particles by
// index, then the ranks swap what the stepping changed: the particles' state
// (position, velocity, collisions left, last slide) and the step's records
// (events, deaths), gathered rank after rank, hence in particle order. Every
// rank then applies every event and removes every death itself, in that
// order, exactly as one process applies its chunks: the maps, the loads and
// the statistics are the same on every rank and for every rank count.
#include <string.h>

#include "core/array.h"
#include "core/dist.h"
#include "sim/solver_internal.h"

// Rank r's share of the particles: whole blocks, in rank order. Whole blocks
// because the step kernel writes whole blocks (padding lanes too): a share
// that ended inside a block would overwrite the next rank's first particles.
static void share_of(const wx_sim *sim, int r, int64_t *begin, int64_t *end)
{
    int64_t n = sim->particles.count;
    int64_t blocks = (n + WX_PARTICLE_BLOCK - 1) / WX_PARTICLE_BLOCK;
    int64_t per = (blocks + sim->ranks - 1) / sim->ranks * WX_PARTICLE_BLOCK;
    *begin = r * per < n ? r * per : n;
    *end = (r + 1) * per < n ? (r + 1) * per : n;
}

static int64_t share_size(const wx_sim *sim, int r)
{
    int64_t begin, end;
    share_of(sim, r, &begin, &end);
    return end - begin;
}

void sim_share(wx_sim *sim)
{
    share_of(sim, sim->ranks > 1 ? wx_dist_rank() : 0, &sim->own_begin, &sim->own_end);
}

enum { AGREE = 6 }; // sim_agree's numbers per rank (rank_counts holds 6 per rank)

wx_result sim_agree(wx_sim *sim, wx_result r, wx_error *err)
{
    int64_t mine[AGREE] = { r,
                            sim->view_count,
                            sim->slide_base[sim->view_count],
                            sim->substances,
                            sim->emitter_count,
                            (int64_t)(sim->seed & INT64_MAX) };
    int64_t *all = sim->rank_counts;
    wx_dist_allgather_i64(mine, AGREE, all);
    if (r != WX_OK) {
        return r; // this rank's own message
    }
    for (int k = 0; k < sim->ranks; ++k) {
        if (all[k * AGREE] != WX_OK) {
            return wx_fail(err, WX_CAUSE_INTERNAL, "simulation: rank %d of %d could not start", k,
                           sim->ranks);
        }
        if (memcmp(&all[k * AGREE + 1], &mine[1], (AGREE - 1) * sizeof *mine) != 0) {
            return wx_fail(err, WX_CAUSE_INTERNAL,
                           "simulation: rank %d of %d has other maps, substances, emitters or "
                           "seed than rank %d",
                           k, sim->ranks, wx_dist_rank());
        }
    }
    return WX_OK;
}

enum { EVENTS, DEATHS, FAILED, COUNTS };

// A rank's part of the exchange, in 8-byte words: its particles' moved state
// (MOVED arrays of 4-byte values), then its events, then its deaths.
enum { MOVED = 8, WORD = 8 };
_Static_assert(sizeof(sim_event) % WORD == 0, "events are whole words");

static int64_t part_words(int64_t particles, int64_t events, int64_t deaths)
{
    return (particles * MOVED * 4 + WORD - 1) / WORD +
           events * (int64_t)(sizeof(sim_event) / WORD) + deaths;
}

// The arrays of the particles' state that the step kernel writes (step.c);
// loads and weights change only when the events are applied, on every rank.
static void moved_arrays(wx_particles *P, uint32_t *moved[MOVED])
{
    _Static_assert(sizeof *P->x == 4 && sizeof *P->last_slide == 4, "4-byte particle fields");
    void *arrays[MOVED] = {
        P->x, P->y, P->z, P->vx, P->vy, P->vz, P->collisions_left, P->last_slide
    };
    for (int k = 0; k < MOVED; ++k) {
        moved[k] = arrays[k];
    }
}

wx_result sim_exchange(wx_sim *sim, wx_error *err)
{
    int R = sim->ranks;
    int me = wx_dist_rank();
    int64_t mine[COUNTS] = { 0, 0, 0 };
    for (int64_t c = 0; c < sim->chunk_count; ++c) {
        mine[EVENTS] += sim->chunks[c].event_count;
        mine[DEATHS] += sim->chunks[c].dead_count;
    }
    for (int t = 0; t < sim->thread_count; ++t) {
        mine[FAILED] |= sim->workers[t].failed ? 1 : 0;
    }
    // Every rank's counts (rank r's at gathered[r * COUNTS + k]), then each
    // rank's part in words.
    int64_t *gathered = sim->rank_counts;
    int64_t *words_of = gathered + R * COUNTS;
    wx_dist_allgather_i64(mine, COUNTS, gathered);
    int64_t events = 0, deaths = 0, words = 0, offset = 0;
    bool failed = false;
    for (int r = 0; r < R; ++r) {
        const int64_t *g = &gathered[r * COUNTS];
        words_of[r] = part_words(share_size(sim, r), g[EVENTS], g[DEATHS]);
        offset = r == me ? words : offset;
        events += g[EVENTS];
        deaths += g[DEATHS];
        words += words_of[r];
        failed |= g[FAILED] != 0;
    }
    if (failed) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (collision events)");
    }
    sim_chunk *all = &sim->all;
    if (!wx_array_reserve((void **)&all->events, &all->event_capacity, events + 1,
                          sizeof *all->events, 4096) ||
        !wx_array_reserve((void **)&all->dead, &all->dead_capacity, deaths + 1, sizeof *all->dead,
                          1024) ||
        !wx_array_reserve((void **)&sim->exchange, &sim->exchange_capacity, words + 1,
                          sizeof *sim->exchange, 4096)) {
        // The others are already on their way to the gather below: this rank
        // cannot tell them, so the job ends (rare: the records are a fraction
        // of the particles' memory).
        wx_dist_abort(WX_FAIL);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (collision events)");
    }
    // This rank's part, in place after those of the ranks before it.
    wx_particles *P = &sim->particles;
    uint32_t *moved[MOVED];
    moved_arrays(P, moved);
    int64_t own = sim->own_end - sim->own_begin;
    unsigned char *part = (unsigned char *)(sim->exchange + offset);
    for (int k = 0; k < MOVED; ++k) {
        memcpy(part + (size_t)k * (size_t)own * 4, moved[k] + sim->own_begin, (size_t)own * 4);
    }
    part = (unsigned char *)(sim->exchange + offset + part_words(own, 0, 0));
    for (int64_t c = 0; c < sim->chunk_count; ++c) {
        const sim_chunk *ch = &sim->chunks[c];
        if (ch->event_count > 0) {
            memcpy(part, ch->events, (size_t)ch->event_count * sizeof *ch->events);
            part += (size_t)ch->event_count * sizeof *ch->events;
        }
    }
    for (int64_t c = 0; c < sim->chunk_count; ++c) {
        const sim_chunk *ch = &sim->chunks[c];
        if (ch->dead_count > 0) {
            memcpy(part, ch->dead, (size_t)ch->dead_count * sizeof *ch->dead);
            part += (size_t)ch->dead_count * sizeof *ch->dead;
        }
    }
    wx_result r = wx_dist_allgatherv(NULL, sim->exchange, words_of, WORD, err);
    if (r != WX_OK) {
        return r;
    }
    // Every part back: the particles into their places, the records after
    // those of the ranks before (rank order is particle order).
    all->event_count = 0;
    all->dead_count = 0;
    int64_t begin = 0, at = 0;
    for (int q = 0; q < R; ++q) {
        const int64_t *g = &gathered[q * COUNTS];
        int64_t n = share_size(sim, q);
        const unsigned char *from = (const unsigned char *)(sim->exchange + at);
        for (int k = 0; k < MOVED && q != me; ++k) {
            memcpy(moved[k] + begin, from + (size_t)k * (size_t)n * 4, (size_t)n * 4);
        }
        from = (const unsigned char *)(sim->exchange + at + part_words(n, 0, 0));
        if (g[EVENTS] > 0) {
            memcpy(all->events + all->event_count, from, (size_t)g[EVENTS] * sizeof *all->events);
        }
        from += (size_t)g[EVENTS] * sizeof *all->events;
        if (g[DEATHS] > 0) {
            memcpy(all->dead + all->dead_count, from, (size_t)g[DEATHS] * sizeof *all->dead);
        }
        all->event_count += g[EVENTS];
        all->dead_count += g[DEATHS];
        begin += n;
        at += words_of[q];
    }
    return WX_OK;
}
