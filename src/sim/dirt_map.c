// dirt_map.c: surface dirt, the particle-surface exchange and Bresenham streaks
// (thesis 3.5, 4.8.4.3, docs/design.md section 4).
#include "sim/dirt_map.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

static float unit_clamp(float v)
{
    if (!(v > 0.0f)) {
        return 0.0f; // also NaN
    }
    return v < 1.0f ? v : 1.0f;
}

wx_result wx_dirt_map_init(wx_dirt_map *map, int width, int height, const float *dirt,
                           const float *deposit, const float *erosion, float D, float E,
                           const float *depth, wx_error *err)
{
    memset(map, 0, sizeof *map);
    size_t texels = (size_t)width * (size_t)height;
    map->texels = malloc(texels * sizeof *map->texels);
    if (map->texels == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (dirt map %d x %d)", width,
                       height);
    }
    map->width = width;
    map->height = height;
    map->depth = depth;
    for (size_t t = 0; t < texels; ++t) {
        float s = dirt != NULL ? dirt[t] : 0.0f;
        map->texels[t].dirt = isfinite(s) ? s : 0.0;
        map->texels[t].deposit = unit_clamp(D * (deposit != NULL ? deposit[t] : 0.0f));
        map->texels[t].erosion = unit_clamp(E * (erosion != NULL ? erosion[t] : 0.0f));
        map->texels[t].hits = 0.0f;
    }
    return WX_OK;
}

void wx_dirt_map_free(wx_dirt_map *map)
{
    free(map->texels);
    memset(map, 0, sizeof *map);
}

double wx_dirt_map_total(const wx_dirt_map *map)
{
    double sum = 0.0;
    size_t texels = (size_t)map->width * (size_t)map->height;
    for (size_t t = 0; t < texels; ++t) {
        sum += map->texels[t].dirt;
    }
    return sum;
}

void wx_dirt_map_exchange(wx_dirt_map *map, uint32_t texel, double *load)
{
    wx_dirt_texel *t = &map->texels[texel];
    double dep = t->deposit * *load;
    double ero = t->erosion * t->dirt;
    *load += ero - dep;
    t->dirt += dep - ero;
    t->hits += 1.0f;
}

void wx_dirt_map_deposit_all(wx_dirt_map *map, uint32_t texel, double *load)
{
    map->texels[texel].dirt += *load;
    *load = 0.0;
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

int wx_bresenham(int x0, int y0, int x1, int y1, int *out, int max)
{
    line_walk w;
    int n = 0;
    for (line_begin(&w, x0, y0, x1, y1); !w.done; line_next(&w)) {
        if (out != NULL && n < max) {
            out[2 * n] = w.x;
            out[2 * n + 1] = w.y;
        }
        n++;
    }
    return n;
}

static bool has_surface(const wx_dirt_map *map, size_t texel)
{
    return map->depth == NULL || isfinite(map->depth[texel]);
}

void wx_dirt_map_exchange_line(wx_dirt_map *map, uint32_t from, uint32_t to, double *load)
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
        wx_dirt_map_exchange(map, to, load);
        return;
    }
    double p = *load, share = 1.0 / n, change = 0.0;
    float hit_share = 1.0f / (float)n;
    line_begin(&w, x0, y0, x1, y1);
    for (line_next(&w); !w.done; line_next(&w)) {
        size_t texel = (size_t)w.y * (size_t)W + (size_t)w.x;
        if (!has_surface(map, texel)) {
            continue;
        }
        wx_dirt_texel *t = &map->texels[texel];
        double dep = t->deposit * p * share;
        double ero = t->erosion * t->dirt * share;
        t->dirt += dep - ero;
        t->hits += hit_share;
        change += ero - dep;
    }
    *load = p + change;
}
