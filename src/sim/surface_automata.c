// surface_automata.c: the ageing rules that read other surface points
// (docs/design.md section 15): <Seed> starts a substance at random points,
// <Spread> lets it advance along the surface to the points within a radius of
// those that hold it, <Crack> grows a line from each crack tip to its weakest
// neighbour, <Peel> spreads from a crack's edges where it is wet (Gobron's
// surface cellular automata). The surface points
// are the texels of every view (input camera and layer) that own some surface
// (the area the bake records, so a point two cameras see counts once); their
// neighbours are found in world space, through a uniform grid of cells as large
// as the radius, so spreading crosses UV seams, cameras' edges and layers.
//
// Each automaton rule runs over the whole surface before the next rule (it
// reads the state at its start: a synchronous automaton, so the result does
// not depend on the order points are visited), in one thread; its random
// numbers are a hash of (seed, point, iteration, rule), so any thread count
// gives the same bytes.
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim/solver_internal.h"

// A point holds its substance from this share of 1 per square metre on (the
// amount it takes is its area, a float: rounding must not undo it).
#define HOLD_SHARE (1.0 - 1e-6)
// Along the surface: two points are neighbours when their normals are within
// 120 degrees (a box's edge is crossed, the two faces of a thin wall or plate,
// whose normals are opposite, are not), and the chord between them does not
// run along both normals (two surfaces stacked or facing across a gap).
#define NORMAL_AGREEMENT   (-0.5f)
#define CHORD_ALONG_NORMAL 0.8f
// Positions come from single-precision depths and cameras: a neighbour exactly
// `radius` away (a whole number of texels on a plane) must not be lost to
// their rounding.
#define RADIUS_SLACK 1e-4

// A uniform grid over the points, cells `cell` world units wide: the points of
// cell k are order[start[k] .. start[k+1]), found from the cell's coordinates
// through an open-addressing hash table.
typedef struct point_grid {
    double cell;
    int64_t cells;
    int64_t *start;    ///< cells + 1
    int64_t *order;    ///< points, by cell
    int64_t *cell_of;  ///< per point
    uint64_t *keys;    ///< table: packed cell coordinates
    int64_t *slots;    ///< table: cell index, -1 empty
    uint64_t mask;     ///< table size - 1
    uint32_t *holders; ///< per cell, scratch of one Spread
} point_grid;

struct sim_surface {
    int64_t count;
    int *view;           ///< per point
    uint32_t *texel;     ///< per point
    float *pos, *normal; ///< 3 per point, world space
    float *area;         ///< per point: the area it owns (0: it takes no part)
    int *surface;        ///< per point: global <Surface> index, -1 none
    uint8_t *flag;       ///< scratch: holds (bit 0), takes (bit 1)
    /// Per point, bit s: a crack tip of substance s (it held s when the
    /// automata first ran, or took it since, and no Crack has grown from it).
    uint8_t *tip;
    int grid_count;
    point_grid grids[WX_MAX_GRIDS];
};

static uint64_t pack_cell(const float p[3], double cell, int d[3])
{
    uint64_t key = 0;
    for (int k = 0; k < 3; ++k) {
        double q = floor((double)p[k] / cell);
        // Clamped coordinates merge far cells, which stays correct (distances
        // are checked) and only costs time.
        q = fmin(fmax(q, -1048575.0), 1048575.0);
        d[k] = (int)q;
        key = key << 21 | (uint64_t)(d[k] + 1048576);
    }
    return key;
}

static uint64_t key_of(const int d[3])
{
    uint64_t key = 0;
    for (int k = 0; k < 3; ++k) {
        int q = d[k] < -1048576 ? -1048576 : d[k] > 1048575 ? 1048575 : d[k];
        key = key << 21 | (uint64_t)(q + 1048576);
    }
    return key;
}

static int64_t find_cell(const point_grid *g, uint64_t key)
{
    for (uint64_t h = wx_mix64(key) & g->mask;; h = (h + 1) & g->mask) {
        if (g->slots[h] < 0) {
            return -1;
        }
        if (g->keys[h] == key) {
            return g->slots[h];
        }
    }
}

static void grid_free(point_grid *g)
{
    free(g->start);
    free(g->order);
    free(g->cell_of);
    free(g->keys);
    free(g->slots);
    free(g->holders);
    memset(g, 0, sizeof *g);
}

// Builds the grid of cell size `cell` over the surface's points: linear time.
static wx_result grid_build(const sim_surface *sf, double cell, point_grid *g, wx_error *err)
{
    int64_t n = sf->count;
    uint64_t size = 16;
    while (size < 2 * (uint64_t)n + 16) {
        size <<= 1;
    }
    g->cell = cell;
    g->mask = size - 1;
    g->keys = malloc(size * sizeof *g->keys);
    g->slots = malloc(size * sizeof *g->slots);
    g->cell_of = malloc((size_t)(n + 1) * sizeof *g->cell_of);
    g->order = malloc((size_t)(n + 1) * sizeof *g->order);
    g->start = calloc((size_t)n + 2, sizeof *g->start);
    if (g->keys == NULL || g->slots == NULL || g->cell_of == NULL || g->order == NULL ||
        g->start == NULL) {
        grid_free(g);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (spread grid)");
    }
    memset(g->slots, 0xff, size * sizeof *g->slots);
    for (int64_t i = 0; i < n; ++i) {
        int d[3];
        uint64_t key = pack_cell(&sf->pos[3 * i], cell, d);
        uint64_t h = wx_mix64(key) & g->mask;
        while (g->slots[h] >= 0 && g->keys[h] != key) {
            h = (h + 1) & g->mask;
        }
        if (g->slots[h] < 0) {
            g->keys[h] = key;
            g->slots[h] = g->cells++;
        }
        g->cell_of[i] = g->slots[h];
        g->start[g->slots[h] + 1]++;
    }
    for (int64_t k = 0; k < g->cells; ++k) {
        g->start[k + 1] += g->start[k];
    }
    int64_t *fill = malloc((size_t)(g->cells + 1) * sizeof *fill);
    g->holders = malloc((size_t)(g->cells + 1) * sizeof *g->holders);
    if (fill == NULL || g->holders == NULL) {
        free(fill);
        grid_free(g);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (spread grid)");
    }
    memcpy(fill, g->start, (size_t)g->cells * sizeof *fill);
    for (int64_t i = 0; i < n; ++i) {
        g->order[fill[g->cell_of[i]]++] = i;
    }
    free(fill);
    return WX_OK;
}

void sim_surface_free(sim_surface *sf)
{
    if (sf == NULL) {
        return;
    }
    for (int k = 0; k < sf->grid_count; ++k) {
        grid_free(&sf->grids[k]);
    }
    free(sf->view);
    free(sf->texel);
    free(sf->pos);
    free(sf->normal);
    free(sf->area);
    free(sf->surface);
    free(sf->flag);
    free(sf->tip);
    free(sf);
}

// The surface points of every view: world positions from depth and camera.
static wx_result surface_build(wx_sim *sim, sim_surface **out, wx_error *err)
{
    sim_surface *sf = calloc(1, sizeof *sf);
    if (sf == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (surface points)");
    }
    int64_t n = 0;
    for (int c = 0; c < sim->view_count; ++c) {
        const wx_dirt_map *map = &sim->dirt[c];
        size_t texels = (size_t)map->width * (size_t)map->height;
        for (size_t t = 0; t < texels; ++t) {
            n += map->depth == NULL || isfinite(map->depth[t]);
        }
    }
    size_t m = (size_t)n + 1;
    sf->view = malloc(m * sizeof *sf->view);
    sf->texel = malloc(m * sizeof *sf->texel);
    sf->pos = malloc(3 * m * sizeof *sf->pos);
    sf->normal = malloc(3 * m * sizeof *sf->normal);
    sf->area = malloc(m * sizeof *sf->area);
    sf->surface = malloc(m * sizeof *sf->surface);
    sf->flag = malloc(m * sizeof *sf->flag);
    sf->tip = calloc(m, sizeof *sf->tip);
    if (sf->view == NULL || sf->texel == NULL || sf->pos == NULL || sf->normal == NULL ||
        sf->area == NULL || sf->surface == NULL || sf->flag == NULL || sf->tip == NULL) {
        sim_surface_free(sf);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (surface points)");
    }
    const int known = wx_scene_surface_count(sim->scene);
    for (int c = 0; c < sim->view_count; ++c) {
        const wx_dirt_map *map = &sim->dirt[c];
        const wx_maps *v = &sim->views[c];
        const wx_camera *cam =
            &sim->scene->cameras[sim->input_camera[sim_view_camera(sim, c)]].camera;
        for (int j = 0; j < map->height; ++j) {
            for (int i = 0; i < map->width; ++i) {
                size_t t = (size_t)j * (size_t)map->width + (size_t)i;
                float depth = map->depth != NULL ? map->depth[t] : v->depth[t];
                if (map->depth != NULL && !isfinite(depth)) {
                    continue;
                }
                int64_t k = sf->count++;
                float uvd[3];
                wx_map_texel_center(map->width, map->height, i, j, &uvd[0], &uvd[1]);
                uvd[2] = depth;
                wx_camera_map_to_world(cam, uvd, &sf->pos[3 * k]);
                memcpy(&sf->normal[3 * k], &v->normal[3 * t], 3 * sizeof(float));
                sf->view[k] = c;
                sf->texel[k] = (uint32_t)t;
                float a = sim->grow_area[c] != NULL ? sim->grow_area[c][t] : 0.0f;
                sf->area[k] = isfinite(a) && a > 0.0f ? a : 0.0f;
                int id = sim->surface_of[c] != NULL ? (int)sim->surface_of[c][t] - 1 : -1;
                sf->surface[k] = id >= 0 && id < known ? id : -1;
            }
        }
    }
    // What the points hold when the automata first run are crack tips.
    for (int64_t k = 0; k < sf->count; ++k) {
        for (int q = 0; q < sim->substances && sf->area[k] > 0.0f; ++q) {
            const wx_dirt_texel *x =
                &sim->dirt[sf->view[k]].texels[(size_t)sf->texel[k] * (size_t)sim->substances];
            if (x[q].dirt >= HOLD_SHARE * (double)sf->area[k]) {
                sf->tip[k] |= (uint8_t)(1u << q);
            }
        }
    }
    *out = sf;
    return WX_OK;
}

// The grid whose cells are `radius` wide, built the first time it is asked for.
static wx_result grid_for(sim_surface *sf, double radius, point_grid **out, wx_error *err)
{
    for (int k = 0; k < sf->grid_count; ++k) {
        if (sf->grids[k].cell == radius) {
            *out = &sf->grids[k];
            return WX_OK;
        }
    }
    if (sf->grid_count == WX_MAX_GRIDS) {
        // More distinct radii than grids: rebuild the last one (time only).
        grid_free(&sf->grids[--sf->grid_count]);
    }
    wx_result r = grid_build(sf, radius, &sf->grids[sf->grid_count], err);
    if (r == WX_OK) {
        *out = &sf->grids[sf->grid_count++];
    }
    return r;
}

static double *amount_at(wx_sim *sim, const sim_surface *sf, int64_t k, int s)
{
    return &sim->dirt[sf->view[k]].texels[(size_t)sf->texel[k] * (size_t)sim->substances + s].dirt;
}

static double *baseline_at(wx_sim *sim, const sim_surface *sf, int64_t k, int s)
{
    double *b = sim->baseline[sf->view[k]];
    return b != NULL ? &b[(size_t)sf->texel[k] * (size_t)sim->substances + s] : NULL;
}

// Whether point k meets the rule's where/min (any amount of `where` with min 0).
static bool meets_where(wx_sim *sim, const sim_surface *sf, int64_t k, const wx_rule *rule)
{
    if (rule->where < 0) {
        return true;
    }
    double w = *amount_at(sim, sf, k, rule->where);
    return w > 0.0 && w >= (double)rule->min * (double)sf->area[k];
}

static bool holds(wx_sim *sim, const sim_surface *sf, int64_t k, int s)
{
    return *amount_at(sim, sf, k, s) >= HOLD_SHARE * (double)sf->area[k];
}

// Point k takes 1 per square metre of the rule's substance: its area, on the
// real amounts and on the baseline (like Grow: not the particles' doing, so
// the gather keeps it exactly), counted as grown; it becomes a crack tip.
static void take(wx_sim *sim, sim_surface *sf, int64_t k, int s)
{
    sf->tip[k] |= (uint8_t)(1u << s);
    double g = (double)sf->area[k];
    *amount_at(sim, sf, k, s) += g;
    double *b = baseline_at(sim, sf, k, s);
    if (b != NULL) {
        *b += g;
    }
    sim->stats.substance[s].grown += g;
}

// A uniform number in [0, 1) of (seed, point, iteration, rule).
static double draw(const wx_sim *sim, const sim_surface *sf, int64_t k, uint64_t rule_id)
{
    uint64_t point = (uint64_t)sim->slide_base[sf->view[k]] + sf->texel[k];
    uint64_t h = wx_mix64(sim->seed ^ wx_mix64(point ^ wx_mix64((uint64_t)sim->iterations_done ^
                                                                wx_mix64(rule_id + 1))));
    return (double)(h >> 11) * (1.0 / 9007199254740992.0);
}

// A point's flaw for Crack: uniform in [0, 1), a hash of the seed and the
// point alone, so a crack follows the same weak line whatever the iteration.
static double flaw(const wx_sim *sim, const sim_surface *sf, int64_t k)
{
    uint64_t point = (uint64_t)sim->slide_base[sf->view[k]] + sf->texel[k];
    uint64_t h = wx_mix64(sim->seed ^ wx_mix64(point ^ UINT64_C(0xc7ac4f1a3d5b2e69)));
    return (double)(h >> 11) * (1.0 / 9007199254740992.0);
}

static bool in_scope(const sim_surface *sf, int64_t k, int surface)
{
    return sf->area[k] > 0.0f && (surface < 0 || sf->surface[k] == surface);
}

static void run_seed(wx_sim *sim, sim_surface *sf, const wx_rule *rule, int surface,
                     uint64_t rule_id)
{
    int s = rule->substance;
    for (int64_t k = 0; k < sf->count; ++k) {
        if (!in_scope(sf, k, surface) || holds(sim, sf, k, s) || !meets_where(sim, sf, k, rule)) {
            continue;
        }
        double p = -expm1(-(double)rule->density * (double)sf->area[k]);
        if (draw(sim, sf, k, rule_id) < p) {
            take(sim, sf, k, s);
        }
    }
}

// Whether holder j is a neighbour of point i along the surface within `radius`.
static bool neighbours(const sim_surface *sf, int64_t i, int64_t j, double radius)
{
    const float *pi = &sf->pos[3 * i], *pj = &sf->pos[3 * j];
    const float *ni = &sf->normal[3 * i], *nj = &sf->normal[3 * j];
    double d[3] = { (double)pi[0] - pj[0], (double)pi[1] - pj[1], (double)pi[2] - pj[2] };
    double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    double reach = radius * (1.0 + RADIUS_SLACK);
    if (d2 > reach * reach) {
        return false;
    }
    if (ni[0] * nj[0] + ni[1] * nj[1] + ni[2] * nj[2] < NORMAL_AGREEMENT) {
        return false;
    }
    double len = sqrt(d2);
    double ai = fabs(d[0] * ni[0] + d[1] * ni[1] + d[2] * ni[2]);
    double aj = fabs(d[0] * nj[0] + d[1] * nj[1] + d[2] * nj[2]);
    return !(ai > CHORD_ALONG_NORMAL * len && aj > CHORD_ALONG_NORMAL * len);
}

// Whether some point that held the substance at the rule's start lies within
// the radius of point i: the 27 cells around it, those with holders only.
static bool near_holder(const sim_surface *sf, const point_grid *g, int64_t i, double radius)
{
    int c[3];
    pack_cell(&sf->pos[3 * i], g->cell, c);
    for (int dz = -1; dz <= 1; ++dz) {
        for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
                int q[3] = { c[0] + dx, c[1] + dy, c[2] + dz };
                int64_t cell = find_cell(g, key_of(q));
                if (cell < 0 || g->holders[cell] == 0) {
                    continue;
                }
                for (int64_t e = g->start[cell]; e < g->start[cell + 1]; ++e) {
                    int64_t j = g->order[e];
                    if ((sf->flag[j] & 1) && neighbours(sf, i, j, radius)) {
                        return true;
                    }
                }
            }
        }
    }
    return false;
}

// Spread, and Peel (whose sources also hold `from`: a crack's edges).
static wx_result run_spread(wx_sim *sim, sim_surface *sf, const wx_rule *rule, int surface,
                            uint64_t rule_id, wx_error *err)
{
    point_grid *g = NULL;
    wx_result r = grid_for(sf, (double)rule->radius, &g, err);
    if (r != WX_OK) {
        return r;
    }
    int s = rule->substance;
    int from = rule->kind == WX_RULE_PEEL ? rule->to : -1;
    memset(g->holders, 0, (size_t)g->cells * sizeof *g->holders);
    for (int64_t k = 0; k < sf->count; ++k) {
        bool own = sf->area[k] > 0.0f && holds(sim, sf, k, s);
        bool source = own || (sf->area[k] > 0.0f && from >= 0 && holds(sim, sf, k, from));
        sf->flag[k] = (uint8_t)(source | (own << 2));
        g->holders[g->cell_of[k]] += source;
    }
    for (int64_t k = 0; k < sf->count; ++k) {
        if (!in_scope(sf, k, surface) || (sf->flag[k] & 4) || !meets_where(sim, sf, k, rule) ||
            !(draw(sim, sf, k, rule_id) < (double)rule->probability)) {
            continue;
        }
        if (near_holder(sf, g, k, (double)rule->radius)) {
            sf->flag[k] |= 2;
        }
    }
    for (int64_t k = 0; k < sf->count; ++k) {
        if (sf->flag[k] & 2) {
            take(sim, sf, k, s);
        }
    }
    return WX_OK;
}

// Crack: each tip (a point that took the substance since the last Crack) takes
// the weakest point of the annulus [radius / 2, radius] around it that does
// not hold it, when that point's flaw is below `strength` and it meets
// where/min; then it is no longer a tip. Ties go to the lower point index.
static wx_result run_crack(wx_sim *sim, sim_surface *sf, const wx_rule *rule, int surface,
                           wx_error *err)
{
    point_grid *g = NULL;
    wx_result r = grid_for(sf, (double)rule->radius, &g, err);
    if (r != WX_OK) {
        return r;
    }
    int s = rule->substance;
    uint8_t bit = (uint8_t)(1u << s);
    double radius = (double)rule->radius;
    for (int64_t k = 0; k < sf->count; ++k) {
        sf->flag[k] = sf->area[k] > 0.0f && holds(sim, sf, k, s);
    }
    for (int64_t i = 0; i < sf->count; ++i) {
        if (!(sf->tip[i] & bit) || !(sf->flag[i] & 1)) {
            continue;
        }
        sf->tip[i] &= (uint8_t)~bit;
        int c[3];
        pack_cell(&sf->pos[3 * i], g->cell, c);
        int64_t best = -1;
        double weakest = (double)rule->strength;
        for (int dz = -1; dz <= 1; ++dz) {
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    int q[3] = { c[0] + dx, c[1] + dy, c[2] + dz };
                    int64_t cell = find_cell(g, key_of(q));
                    for (int64_t e = cell < 0 ? 0 : g->start[cell];
                         cell >= 0 && e < g->start[cell + 1]; ++e) {
                        int64_t j = g->order[e];
                        if ((sf->flag[j] & 1) || !in_scope(sf, j, surface) ||
                            !neighbours(sf, j, i, radius)) {
                            continue;
                        }
                        const float *pi = &sf->pos[3 * i], *pj = &sf->pos[3 * j];
                        double d2 = 0.0;
                        for (int a = 0; a < 3; ++a) {
                            d2 += ((double)pi[a] - pj[a]) * ((double)pi[a] - pj[a]);
                        }
                        if (d2 < 0.25 * radius * radius) {
                            continue;
                        }
                        double w = flaw(sim, sf, j);
                        if (w < weakest || (w == weakest && best >= 0 && j < best)) {
                            weakest = w;
                            best = j;
                        }
                    }
                }
            }
        }
        if (best >= 0 && meets_where(sim, sf, best, rule)) {
            sf->flag[best] |= 2;
        }
    }
    for (int64_t k = 0; k < sf->count; ++k) {
        if (sf->flag[k] & 2) {
            take(sim, sf, k, s);
        }
    }
    return WX_OK;
}

// One rule over its points: every point for a global rule (surface -1), those
// showing <Surface> `surface` for one of its own.
static wx_result run_one(wx_sim *sim, sim_surface *sf, const wx_rule *rule, int surface,
                         uint64_t rule_id, wx_error *err)
{
    switch (rule->kind) {
    case WX_RULE_SEED:
        run_seed(sim, sf, rule, surface, rule_id);
        return WX_OK;
    case WX_RULE_SPREAD:
    case WX_RULE_PEEL:
        return run_spread(sim, sf, rule, surface, rule_id, err);
    case WX_RULE_CRACK:
        return run_crack(sim, sf, rule, surface, err);
    default:
        break;
    }
    int S = sim->substances;
    for (int64_t k = 0; k < sf->count; ++k) {
        if (surface >= 0 && sf->surface[k] != surface) {
            continue;
        }
        wx_dirt_texel *x = &sim->dirt[sf->view[k]].texels[(size_t)sf->texel[k] * (size_t)S];
        double a[WX_MAX_SUBSTANCES];
        for (int s = 0; s < S; ++s) {
            a[s] = x[s].dirt;
        }
        double *b = baseline_at(sim, sf, k, 0);
        sim_run_rules(rule, 1, a, b, (double)sf->area[k], sim->stats.substance);
        for (int s = 0; s < S; ++s) {
            x[s].dirt = a[s];
        }
    }
    return WX_OK;
}

wx_result sim_age_automata(wx_sim *sim, wx_error *err)
{
    const wx_scene *scene = sim->scene;
    if (sim->surface == NULL) {
        wx_result r = surface_build(sim, &sim->surface, err);
        if (r != WX_OK) {
            return r;
        }
    }
    sim_surface *sf = sim->surface;
    for (int k = 0; k < scene->rule_count; ++k) {
        wx_result r = run_one(sim, sf, &scene->rules[k], -1, (uint64_t)k, err);
        if (r != WX_OK) {
            return r;
        }
    }
    const int known = wx_scene_surface_count(scene);
    for (int id = 0; id < known; ++id) {
        const wx_surface *own = sim->surfaces[id];
        for (int k = 0; k < own->rule_count; ++k) {
            uint64_t rule_id = (uint64_t)(id + 1) << 32 | (uint64_t)k;
            wx_result r = run_one(sim, sf, &own->rules[k], id, rule_id, err);
            if (r != WX_OK) {
                return r;
            }
        }
    }
    return WX_OK;
}
