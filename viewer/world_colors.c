// world_colors.c: a world's colours (world.h): the substance shown and its
// colour, the depth samples tinted by its deposits, and the ramps of the
// derived masks.
#include "world_internal.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "palette.h"
#include "sim/simulate.h"

int vw_world_substance_count(const vw_world *world)
{
    return world->scene.substance_count > 1 ? world->scene.substance_count : 1;
}

void vw_world_show_substance(vw_world *world, int s)
{
    int S = vw_world_substance_count(world);
    s %= S;
    world->substance = s < 0 ? s + S : s;
    float own = 0.0f, any = 0.0f;
    for (int e = 0; e < world->scene.emitter_count; ++e) {
        const float *load = world->scene.emitters[e].load;
        own = fmaxf(own, load[world->substance]);
        for (int k = 0; k < S; ++k) {
            any = fmaxf(any, load[k]);
        }
    }
    world->load_scale = own > 0.0f ? own : any > 0.0f ? any : 1.0f;
}

int vw_world_next_substance(vw_world *world)
{
    vw_world_show_substance(world, world->substance + 1);
    return world->substance;
}

int vw_world_find_substance(const vw_world *world, const char *name)
{
    for (int s = 0; s < world->scene.substance_count; ++s) {
        if (strcmp(world->scene.substances[s], name) == 0) {
            return s;
        }
    }
    return -1;
}

void vw_world_keep_substance(vw_world *world, const char *name)
{
    int s = name != NULL ? vw_world_find_substance(world, name) : -1;
    vw_world_show_substance(world, s >= 0 ? s : 0);
}

const char *vw_world_substance_name(const vw_world *world)
{
    return world->scene.substances[world->substance];
}

void vw_world_substance_color(const vw_world *world, int s, float out[3])
{
    vw_to_float_color(s == world->scene.dirt_substance ? VW_PARTICLE_DIRTY_COLOR
                                                       : VW_SUBSTANCE_COLORS[s % 8],
                      out);
}

bool vw_world_shows_deposits(const vw_world *world)
{
    return world->scene.substances_declared;
}

double vw_world_deposit(const vw_world *world, int point)
{
    const vw_sample *sample = &world->samples[point];
    const wx_dirt_map *map =
        sample->input >= 0 && world->sim != NULL ? wx_sim_dirt_map(world->sim, sample->input)
                                                 : NULL;
    if (map == NULL) {
        return -1.0;
    }
    int S = map->substances > 1 ? map->substances : 1;
    int s = world->substance < S ? world->substance : 0;
    return map->texels[(size_t)sample->texel * (size_t)S + (size_t)s].dirt;
}

float vw_world_deposit_scale(const vw_world *world, const uint32_t *picked, size_t n,
                             float *scratch)
{
    size_t m = 0;
    for (size_t k = 0; k < n; ++k) {
        double a = vw_world_deposit(world, (int)picked[k]);
        if (a > 0.0) {
            scratch[m++] = (float)a;
        }
    }
    if (m == 0) {
        return 0.0f;
    }
    return vw_select_kth(scratch, m, (size_t)((double)(m - 1) * VW_DEPOSIT_QUANTILE));
}

void vw_world_deposit_colors(const vw_world *world, const uint32_t *picked, size_t n,
                             float *scratch, vw_vertex *out)
{
    float scale = vw_world_deposit_scale(world, picked, n, scratch);
    float color[3];
    vw_world_substance_color(world, world->substance, color);
    for (size_t k = 0; k < n; ++k) {
        const int i = (int)picked[k];
        out[k] = world->points[i];
        double a = scale > 0.0f ? vw_world_deposit(world, i) : 0.0;
        if (!(a > 0.0)) {
            continue;
        }
        float t = sqrtf(a < scale ? (float)a / scale : 1.0f);
        float shade = world->samples[i].shade;
        for (int c = 0; c < 3; ++c) {
            out[k].color[c] += t * (color[c] * shade - out[k].color[c]);
        }
    }
}

// --- mask ramps -----------------------------------------------------------------------

// Piecewise linear through `count` evenly spaced stops, t in [0, 1].
static void ramp(const uint8_t (*stops)[3], int count, float t, float out[3])
{
    t = t > 0.0f ? (t < 1.0f ? t : 1.0f) : 0.0f;
    float x = t * (float)(count - 1);
    int k = (int)x;
    k = k < count - 1 ? k : count - 2;
    float f = x - (float)k;
    for (int c = 0; c < 3; ++c) {
        float a = (float)stops[k][c] / 255.0f, b = (float)stops[k + 1][c] / 255.0f;
        out[c] = (1.0f - f) * a + f * b; // the stops exactly at f = 0 and 1
    }
}

void vw_world_mask_color(const vw_world *world, float value, float out[3])
{
    int m = world->mask;
    if (m >= 0 && world->scene.masks[m].kind == WX_MASK_CURVATURE) {
        float scale = world->mask_scale[m] > 0.0f ? world->mask_scale[m] : 1.0f;
        ramp(VW_CURVATURE_RAMP, VW_CURVATURE_RAMP_COUNT, 0.5f + 0.5f * value / scale, out);
    } else {
        ramp(VW_MASK_RAMP, VW_MASK_RAMP_COUNT, value, out);
    }
}

void vw_world_mask_colors(const vw_world *world, const uint32_t *picked, size_t n,
                          vw_vertex *out)
{
    for (size_t k = 0; k < n; ++k) {
        const int i = (int)picked[k];
        out[k] = world->points[i];
        float v = vw_world_mask_value(world, i);
        if (!isnan(v)) {
            vw_world_mask_color(world, v, out[k].color);
        }
    }
}
