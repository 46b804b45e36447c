// step.c: the step kernel of the simulation, run by every thread on its
// chunks of particles: forces and the Euler step, the coarse and the swept
// collision tests, the mechanical reaction, and the records (events, deaths)
// the serial phase of simulate.c applies.
#include <math.h>
#include <string.h>

#include "sim/solver_internal.h"
#include "core/array.h"

static const uint32_t lane_bit[WX_PARTICLE_BLOCK] = {
    1u << 0, 1u << 1, 1u << 2,  1u << 3,  1u << 4,  1u << 5,  1u << 6,  1u << 7,
    1u << 8, 1u << 9, 1u << 10, 1u << 11, 1u << 12, 1u << 13, 1u << 14, 1u << 15,
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
WX_HOT static void
integrate_block(const wx_forces *restrict forces, float t, float dt, const float *restrict x,
                const float *restrict y, const float *restrict z, const float *restrict vx,
                const float *restrict vy, const float *restrict vz, const float *restrict inv_mass,
                float *restrict nx, float *restrict ny, float *restrict nz, float *restrict nvx,
                float *restrict nvy, float *restrict nvz, const float *restrict lo,
                const float *restrict hi, int *restrict inside)
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

// Whether segment a -> b meets a surface (then `hit` holds where): the coarse
// test first, the swept test for what it cannot clear.
static bool meets_surface(const wx_collider *collider, const float a[3], const float b[3],
                          wx_hit *hit)
{
    return !wx_collider_coarse_clear(collider, a, b) && wx_collider_sweep(collider, a, b, hit);
}

// Contacts a slide may meet in the rest of one step (rest_of_step).
enum { SLIDE_CONTACTS = 16 };

// The rest of a step after a hit (docs/physics.md, "Mechanical reaction"): from
// `from`, where the hit put the particle back, it moves `time` at velocity `v`,
// swept, and ends at `out`. A contact ends the move there, except on a slide
// (`contacts` > 1): the surface goes on, so does the slide. At each contact the
// rest of the move loses its part into the contact's plane (its normal) and
// goes on from where that contact puts the particle back, for at most
// `contacts` contacts. No contact of the rest of a step makes an event or
// changes the velocity: the next step's hit does.
//
// A contact whose normal says the move does not enter it is a bump of the
// collision surface the normal does not explain (where two cameras' surfaces
// meet, each right to its own precision, the collider takes the innermost).
// It takes nothing off the move, so the slide would meet it again at once:
// the particle goes back a little further in front of it, along that
// contact's normal towards the side its camera sees, 1/100 of that camera's
// texel more at the first such contact in a row and twice as far at each next
// one (where the way there is free), so it climbs a bump of h texels in about
// log2(100 h) contacts.
static void rest_of_step(const wx_sim *sim, const float from[3], float time, const float v[3],
                         int contacts, float out[3])
{
    const wx_collider *collider = &sim->collider;
    float at[3], move[3];
    for (int k = 0; k < 3; ++k) {
        at[k] = from[k];
        move[k] = time * v[k];
    }
    float climb = 0.01f; // texels, the next bump's extra lift
    for (int c = 1;; ++c) {
        float to[3] = { at[0] + move[0], at[1] + move[1], at[2] + move[2] };
        wx_hit again;
        if (!meets_surface(collider, at, to, &again)) {
            memcpy(out, to, sizeof to);
            return;
        }
        if (c >= contacts) {
            memcpy(out, again.front, sizeof again.front);
            return;
        }
        const float *n = again.normal;
        float left = 1.0f - again.s;
        float into = left * (move[0] * n[0] + move[1] * n[1] + move[2] * n[2]);
        for (int k = 0; k < 3; ++k) {
            move[k] = left * move[k] - (into < 0.0f ? into * n[k] : 0.0f);
            at[k] = again.front[k];
        }
        if (into < 0.0f) {
            climb = 0.01f;
            continue;
        }
        float lift[3], up[3];
        wx_collider_bump_lift(&collider->cameras[again.camera], n, climb, lift);
        for (int k = 0; k < 3; ++k) {
            up[k] = at[k] + lift[k];
        }
        // Only where the way there is free: a lift must not carry the
        // particle through a slab or a pane.
        wx_hit above;
        if (!meets_surface(collider, at, up, &above)) {
            memcpy(at, up, sizeof up);
        }
        climb *= 2.0f;
    }
}

// A segment the coarse test did not clear: the swept test, and on a hit the
// Russian roulette, the reaction and the event.
static void collide_one(wx_sim *sim, sim_worker *w, int64_t i, const float p0[3], const float p1[3],
                        const float v[3])
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
    // spends the rest of the step at its new velocity, swept too
    // (rest_of_step).
    float final[3];
    rest_of_step(sim, hit.front, (1.0f - hit.s) * (float)sim->dt, after,
                 kind == WX_IMPACT_SLIDE ? SLIDE_CONTACTS : 1, final);
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
                                                      w->credit, x0, y0, z0, x1, y1, z1, &outside);
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
void sim_step_range(wx_sim *sim, sim_worker *w, int64_t begin, int64_t end)
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
        integrate_block(&sim->forces, t, dt, ox, oy, oz, P->vx + b, P->vy + b, P->vz + b, inv_mass,
                        nx, ny, nz, nvx, nvy, nvz, sim->bbox_lo, sim->bbox_hi, inside);
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
            sim_candidate c = { b + k,
                                { ox[k], oy[k], oz[k] },
                                { nx[k], ny[k], nz[k] },
                                { nvx[k], nvy[k], nvz[k] },
                                flags };
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
