// dirt_map.c: surface dirt, the particle-surface exchange and Bresenham streaks
// (thesis 3.5, 4.8.4.3, docs/design.md section 4).
#include "sim/dirt_map.h"
#include "core/big_alloc.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "core/limits.h"

// The least contact: the clamp the gather and the bake use for |N . view|
// (docs/mask.md), so a texel seen edge-on still erodes.
#define MIN_CONTACT 1e-3f

static float unit_clamp(float v)
{
    if (!(v > 0.0f)) {
        return 0.0f; // also NaN
    }
    return v < 1.0f ? v : 1.0f;
}

wx_result wx_dirt_map_init(wx_dirt_map *map, int width, int height, int substances,
                           const float *dirt, const float *deposit, const float *erosion,
                           float D, float E, const float *depth, const float *normal,
                           const float view[3], wx_error *err)
{
    memset(map, 0, sizeof *map);
    size_t texels = (size_t)width * (size_t)height;
    size_t S = substances > 0 ? (size_t)substances : 1;
    map->texels = wx_big_malloc(texels * S * sizeof *map->texels);
    if (map->texels == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (dirt map %d x %d)", width,
                       height);
    }
    map->width = width;
    map->height = height;
    map->substances = (int)S;
    map->depth = depth;
    for (size_t s = 0; s < S; ++s) {
        size_t plane = s * texels;
        for (size_t t = 0; t < texels; ++t) {
            wx_dirt_texel *x = &map->texels[t * S + s];
            x->contact = 1.0f;
            if (normal != NULL) {
                const float *n = normal + 3 * t;
                float c = fabsf(n[0] * view[0] + n[1] * view[1] + n[2] * view[2]);
                x->contact = c >= MIN_CONTACT ? (c < 1.0f ? c : 1.0f) : MIN_CONTACT; // NaN too
            }
            float v = dirt != NULL ? dirt[plane + t] : 0.0f;
            x->dirt = isfinite(v) ? v : 0.0;
            x->deposit = unit_clamp(D * (deposit != NULL ? deposit[plane + t] : 0.0f));
            x->erosion = unit_clamp(E * (erosion != NULL ? erosion[plane + t] : 0.0f));
            x->hits = 0.0f;
        }
    }
    return WX_OK;
}

void wx_dirt_map_free(wx_dirt_map *map)
{
    free(map->texels);
    memset(map, 0, sizeof *map);
}

double wx_dirt_map_total(const wx_dirt_map *map, int s)
{
    double sum = 0.0;
    size_t texels = (size_t)map->width * (size_t)map->height;
    size_t S = (size_t)map->substances;
    for (size_t t = 0; t < texels; ++t) {
        sum += map->texels[t * S + (size_t)s].dirt;
    }
    return sum;
}

// The share of a particle's weight an exchange at texel t spends: the texel's
// strongest rate, deposit or erosion, over the substances.
static float exchange_share(const wx_dirt_texel *t, int S)
{
    float f = 0.0f;
    for (int s = 0; s < S; ++s) {
        f = t[s].deposit > f ? t[s].deposit : f;
        f = t[s].erosion > f ? t[s].erosion : f;
    }
    return f;
}

void wx_dirt_map_exchange(wx_dirt_map *map, uint32_t texel, double *load, float *weight)
{
    int S = map->substances;
    wx_dirt_texel *t = &map->texels[(size_t)texel * (size_t)S];
    for (int s = 0; s < S; ++s) {
        double dep = t[s].deposit * load[s];
        double ero = t[s].erosion * t[s].contact * t[s].dirt;
        load[s] += ero - dep;
        t[s].dirt += dep - ero;
    }
    float spent = exchange_share(t, S) * *weight;
    t->hits += spent;
    *weight -= spent;
}

void wx_dirt_map_deposit_all(wx_dirt_map *map, uint32_t texel, double *load, float *weight)
{
    int S = map->substances;
    wx_dirt_texel *t = &map->texels[(size_t)texel * (size_t)S];
    for (int s = 0; s < S; ++s) {
        t[s].dirt += load[s];
        load[s] = 0.0;
    }
    t->hits += *weight;
    *weight = 0.0f;
}

// Bresenham's walk (thesis 3.5, Algorithm 1, generalised to every octant).
typedef struct line_walk {
    int x, y, x1, y1;
    int dx, dy, sx, sy, err;
    bool done;
} line_walk;

static void line_begin(line_walk *w, int x0, int y0, int x1, int y1)
{
    w->x = x0;
    w->y = y0;
    w->x1 = x1;
    w->y1 = y1;
    w->dx = abs(x1 - x0);
    w->dy = -abs(y1 - y0);
    w->sx = x0 < x1 ? 1 : -1;
    w->sy = y0 < y1 ? 1 : -1;
    w->err = w->dx + w->dy;
    w->done = false;
}

// The current texel is (w->x, w->y); moves to the next one.
static void line_next(line_walk *w)
{
    if (w->x == w->x1 && w->y == w->y1) {
        w->done = true;
        return;
    }
    int e2 = 2 * w->err;
    if (e2 >= w->dy) {
        w->err += w->dy;
        w->x += w->sx;
    }
    if (e2 <= w->dx) {
        w->err += w->dx;
        w->y += w->sy;
    }
}

static bool has_surface(const wx_dirt_map *map, size_t texel)
{
    return map->depth == NULL || isfinite(map->depth[texel]);
}

void wx_dirt_map_exchange_line(wx_dirt_map *map, uint32_t from, uint32_t to, double *load,
                               float *weight)
{
    int W = map->width;
    int x0 = (int)(from % (uint32_t)W), y0 = (int)(from / (uint32_t)W);
    int x1 = (int)(to % (uint32_t)W), y1 = (int)(to / (uint32_t)W);
    line_walk w;
    // First pass: how many surface texels share the exchange.
    int n = 0;
    line_begin(&w, x0, y0, x1, y1);
    for (line_next(&w); !w.done; line_next(&w)) {
        n += has_surface(map, (size_t)w.y * (size_t)W + (size_t)w.x);
    }
    if (n == 0) {
        wx_dirt_map_exchange(map, to, load, weight);
        return;
    }
    int S = map->substances;
    double p[WX_MAX_SUBSTANCES], change[WX_MAX_SUBSTANCES];
    for (int s = 0; s < S; ++s) {
        p[s] = load[s];
        change[s] = 0.0;
    }
    double share = 1.0 / n;
    float hit_share = *weight / (float)n, spent = 0.0f;
    line_begin(&w, x0, y0, x1, y1);
    for (line_next(&w); !w.done; line_next(&w)) {
        size_t texel = (size_t)w.y * (size_t)W + (size_t)w.x;
        if (!has_surface(map, texel)) {
            continue;
        }
        wx_dirt_texel *t = &map->texels[texel * (size_t)S];
        for (int s = 0; s < S; ++s) {
            double dep = t[s].deposit * p[s] * share;
            double ero = t[s].erosion * t[s].contact * t[s].dirt * share;
            t[s].dirt += dep - ero;
            change[s] += ero - dep;
        }
        float part = exchange_share(t, S) * hit_share;
        t->hits += part;
        spent += part;
    }
    for (int s = 0; s < S; ++s) {
        load[s] = p[s] + change[s];
    }
    *weight -= spent;
}
