// emitter.c: point and hemisphere emitters (thesis 4.8.2, docs/design.md section 3).
#include "sim/emitter.h"

#include <math.h>

#include "sim/particles.h"

int64_t wx_emitter_count_at(const wx_emitter *e, double t)
{
    double until = t < e->end ? t : e->end;
    double span = until - e->start;
    if (!(span > 0.0) || !(e->rate > 0.0)) {
        return 0;
    }
    double n = e->rate * span;
    return (int64_t)floor(n + 1e-12 * n + 1e-12);
}

void wx_uniform_sphere(float u1, float u2, float d[3])
{
    // Archimedes: the height is uniform on [-1, 1] for a uniform point on the sphere.
    float y = 1.0f - 2.0f * u1;
    float r = sqrtf(fmaxf(0.0f, 1.0f - y * y));
    float phi = 6.2831853071795865f * u2;
    d[0] = r * cosf(phi);
    d[1] = y;
    d[2] = r * sinf(phi);
}

void wx_uniform_hemisphere(float u1, float u2, float d[3])
{
    // Height uniform on (0, 1]: never exactly horizontal.
    float y = 1.0f - u1;
    float r = sqrtf(fmaxf(0.0f, 1.0f - y * y));
    float phi = 6.2831853071795865f * u2;
    d[0] = r * cosf(phi);
    d[1] = y;
    d[2] = r * sinf(phi);
}

void wx_emitter_sample(const wx_emitter *e, uint64_t seed, uint64_t id, float pos[3],
                       float vel[3])
{
    float u1 = wx_particle_random(seed, id, WX_RANDOM_EMIT_0);
    float u2 = wx_particle_random(seed, id, WX_RANDOM_EMIT_1);
    float d[3];
    if (e->kind == WX_EMITTER_HEMISPHERE) {
        // thesis 4.8.2 samples a cube and rejects; the direct map is uniform too.
        wx_uniform_hemisphere(u1, u2, d);
        for (int k = 0; k < 3; ++k) {
            pos[k] = e->center[k] + e->radius * d[k];
            vel[k] = -e->speed * d[k];
        }
    } else {
        wx_uniform_sphere(u1, u2, d);
        for (int k = 0; k < 3; ++k) {
            pos[k] = e->center[k];
            vel[k] = e->speed * d[k];
        }
    }
}
