// particles.c: the structure of arrays of live particles (thesis 4.8.3).
#include "sim/particles.h"

#include <stdlib.h>
#include <string.h>

void wx_particles_free(wx_particles *p)
{
    free(p->x);
    free(p->y);
    free(p->z);
    free(p->vx);
    free(p->vy);
    free(p->vz);
    free(p->inv_mass);
    free(p->load);
    free(p->id);
    free(p->collisions_left);
    free(p->last_slide);
    free(p->weight);
    memset(p, 0, sizeof *p);
}

// Grows one array to `capacity` elements of `size` bytes, zeroing the new part.
static bool grow(void **array, int64_t old_capacity, int64_t capacity, size_t size)
{
    if ((uint64_t)capacity > SIZE_MAX / size) {
        return false; // more bytes than an address holds: out of memory, not a wrap
    }
    void *bigger = realloc(*array, (size_t)capacity * size);
    if (bigger == NULL) {
        return false;
    }
    memset((char *)bigger + (size_t)old_capacity * size, 0,
           (size_t)(capacity - old_capacity) * size);
    *array = bigger;
    return true;
}

bool wx_particles_reserve(wx_particles *p, int64_t needed)
{
    if (needed <= p->capacity) {
        return true;
    }
    int64_t capacity = p->capacity + p->capacity / 2;
    if (capacity < needed) {
        capacity = needed;
    }
    if (capacity < 1024) {
        capacity = 1024;
    }
    capacity = (capacity + WX_PARTICLE_BLOCK - 1) / WX_PARTICLE_BLOCK * WX_PARTICLE_BLOCK;
    int64_t old = p->capacity;
    int64_t S = p->substances > 1 ? p->substances : 1;
    // Each array grows on its own: on failure the grown ones are merely larger.
    bool ok = grow((void **)&p->x, old, capacity, sizeof *p->x) &&
              grow((void **)&p->y, old, capacity, sizeof *p->y) &&
              grow((void **)&p->z, old, capacity, sizeof *p->z) &&
              grow((void **)&p->vx, old, capacity, sizeof *p->vx) &&
              grow((void **)&p->vy, old, capacity, sizeof *p->vy) &&
              grow((void **)&p->vz, old, capacity, sizeof *p->vz) &&
              (p->inv_mass == NULL ||
               grow((void **)&p->inv_mass, old, capacity, sizeof *p->inv_mass)) &&
              grow((void **)&p->load, old * S, capacity * S, sizeof *p->load) &&
              grow((void **)&p->id, old, capacity, sizeof *p->id) &&
              grow((void **)&p->collisions_left, old, capacity, sizeof *p->collisions_left) &&
              grow((void **)&p->last_slide, old, capacity, sizeof *p->last_slide) &&
              grow((void **)&p->weight, old, capacity, sizeof *p->weight);
    if (!ok) {
        return false;
    }
    p->capacity = capacity;
    return true;
}

// Makes 1/mass `inv` storable: a new shared value when no particle is alive, else
// the per-particle array (filled with the shared value) if `inv` differs from it.
static bool accept_inv_mass(wx_particles *p, float inv)
{
    if (p->inv_mass != NULL || inv == p->inv_mass_block[0]) {
        return true;
    }
    if (p->count == 0) {
        for (int k = 0; k < WX_PARTICLE_BLOCK; ++k) {
            p->inv_mass_block[k] = inv;
        }
        return true;
    }
    float *all = malloc((size_t)p->capacity * sizeof *all);
    if (all == NULL) {
        return false;
    }
    for (int64_t k = 0; k < p->capacity; ++k) {
        all[k] = p->inv_mass_block[0];
    }
    p->inv_mass = all;
    return true;
}

int64_t wx_particles_push(wx_particles *p, const float pos[3], const float vel[3], float mass,
                          const double *load, uint64_t id, uint32_t max_collisions)
{
    float inv = 1.0f / mass;
    if (!accept_inv_mass(p, inv)) {
        return -1;
    }
    int64_t i = p->count++;
    p->x[i] = pos[0];
    p->y[i] = pos[1];
    p->z[i] = pos[2];
    p->vx[i] = vel[0];
    p->vy[i] = vel[1];
    p->vz[i] = vel[2];
    if (p->inv_mass != NULL) {
        p->inv_mass[i] = inv;
    }
    int S = p->substances > 1 ? p->substances : 1;
    for (int s = 0; s < S; ++s) {
        p->load[i * S + s] = load[s];
    }
    p->id[i] = id;
    p->collisions_left[i] = max_collisions;
    p->last_slide[i] = WX_NO_SLIDE;
    p->weight[i] = 1.0f;
    return i;
}

void wx_particles_remove(wx_particles *p, int64_t i)
{
    int64_t last = --p->count;
    if (i == last) {
        return;
    }
    p->x[i] = p->x[last];
    p->y[i] = p->y[last];
    p->z[i] = p->z[last];
    p->vx[i] = p->vx[last];
    p->vy[i] = p->vy[last];
    p->vz[i] = p->vz[last];
    if (p->inv_mass != NULL) {
        p->inv_mass[i] = p->inv_mass[last];
    }
    int S = p->substances > 1 ? p->substances : 1;
    for (int s = 0; s < S; ++s) {
        p->load[i * S + s] = p->load[last * S + s];
    }
    p->id[i] = p->id[last];
    p->collisions_left[i] = p->collisions_left[last];
    p->last_slide[i] = p->last_slide[last];
    p->weight[i] = p->weight[last];
}
