// world_masks.c: a world's derived masks (world.h, docs/design.md section 12):
// each mask computed once at the depth samples, on the grid of each layer's
// sampled texels, which mask is shown, and the quantiles both the masks' and
// the deposits' colour scales take (vw_select_kth).
#include "world_internal.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "model/camera.h"

int vw_world_mask_count(const vw_world *world)
{
    return world->scene.mask_count;
}

int vw_world_find_mask(const vw_world *world, const char *name)
{
    for (int m = 0; m < world->scene.mask_count; ++m) {
        if (strcmp(world->scene.masks[m].name, name) == 0) {
            return m;
        }
    }
    return -1;
}

int vw_world_next_mask(const vw_world *world)
{
    int n = world->scene.mask_count;
    return world->mask + 1 < n ? world->mask + 1 : -1;
}

const char *vw_world_mask_kind_name(const vw_world *world, int m)
{
    switch (world->scene.masks[m].kind) {
    case WX_MASK_ACCESSIBILITY: return "accessibility";
    case WX_MASK_EXPOSURE: return "exposure";
    case WX_MASK_CURVATURE: return "curvature";
    case WX_MASK_HEIGHT: return "height";
    case WX_MASK_COMBINE: return "combine";
    case WX_MASK_NOISE:
        return "noise";
    }
    return "mask";
}

bool vw_world_mask_ready(const vw_world *world, int m)
{
    return m < 0 || (m < world->scene.mask_count && world->mask_values[m] != NULL);
}

// The grid of the sampled texels of one layer of a camera (`m`: that layer's
// view of its maps): texel (first + gi * stride, first + gj * stride) at
// gj * cols + gi, as add_layer_points walks them, made into surface points as
// wx_masks_at_camera makes a map's texels.
typedef struct sample_grid {
    int cols, rows, first, stride;
    double *position;
    float *normal;
    unsigned char *valid;
    float texel; ///< the map's texel in world units
} sample_grid;

static void free_grid(sample_grid *g)
{
    free(g->position);
    free(g->normal);
    free(g->valid);
    memset(g, 0, sizeof *g);
}

static bool make_grid(const vw_world *world, int c, const wx_maps *m, sample_grid *g)
{
    const wx_camera *cam = &world->scene.cameras[c].camera;
    memset(g, 0, sizeof *g);
    g->stride = world->sample_stride > 0 ? world->sample_stride : 1;
    g->first = g->stride / 2;
    g->cols = m->width > g->first ? (m->width - g->first + g->stride - 1) / g->stride : 0;
    g->rows = m->height > g->first ? (m->height - g->first + g->stride - 1) / g->stride : 0;
    size_t cells = (size_t)g->cols * (size_t)g->rows;
    g->position = malloc((3 * cells + 1) * sizeof *g->position);
    g->normal = malloc((3 * cells + 1) * sizeof *g->normal);
    g->valid = malloc(cells + 1);
    if (g->position == NULL || g->normal == NULL || g->valid == NULL) {
        free_grid(g);
        return false;
    }
    float frame_w, frame_h;
    wx_camera_frame_size(cam, &frame_w, &frame_h);
    g->texel = frame_w / (float)(m->width > 0 ? m->width : 1);
    for (int gj = 0; gj < g->rows; ++gj) {
        for (int gi = 0; gi < g->cols; ++gi) {
            int i = g->first + gi * g->stride, j = g->first + gj * g->stride;
            size_t t = (size_t)j * (size_t)m->width + (size_t)i;
            size_t q = (size_t)gj * (size_t)g->cols + (size_t)gi;
            float d = m->depth[t];
            const float *n = &m->normal[3 * t];
            g->valid[q] = !wx_depth_is_empty(d) && (n[0] != 0.0f || n[1] != 0.0f || n[2] != 0.0f);
            float uvd[3] = { 0.0f, 0.0f, g->valid[q] ? d : 0.0f }, p[3];
            wx_map_texel_center(m->width, m->height, i, j, &uvd[0], &uvd[1]);
            wx_camera_map_to_world(cam, uvd, p);
            for (int k = 0; k < 3; ++k) {
                g->position[3 * q + k] = p[k];
                g->normal[3 * q + k] = n[k];
            }
        }
    }
    return true;
}

// The grid cell of depth sample `point` of a layer's grid (maps `m`), or -1.
static ptrdiff_t grid_cell(const vw_world *world, const wx_maps *m, const sample_grid *g,
                           int point)
{
    int texel = world->samples[point].texel;
    int i = texel % m->width, j = texel / m->width;
    int gi = (i - g->first) / g->stride, gj = (j - g->first) / g->stride;
    if (i < g->first || j < g->first || gi >= g->cols || gj >= g->rows) {
        return -1;
    }
    return (ptrdiff_t)gj * g->cols + gi;
}

// What each mask up to m is in one evaluation of the grids.
typedef enum mask_role {
    ROLE_SKIP,    ///< not read by m: made a cheap Height (its plane is thrown away)
    ROLE_COMPUTE, ///< m or a mask m reads, not known yet: computed and kept
    ROLE_REUSE,   ///< known and read by m: its plane is the known values
} mask_role;

// The scene as one camera's grid evaluates it: masks up to m in their places
// (an accessibility's directions hash its index), those m does not read made
// cheap, those known turned into a Combine of one term reading their values
// from the extra plane substances[substance_count + k] (exact: their values
// lie in [0, 1], which the Combine's clamp keeps), Curvature's default radius
// wide enough for the samples' spacing.
static void masks_for_grid(const wx_scene *scene, int m, const mask_role role[],
                           const sample_grid *g, wx_scene *copy)
{
    *copy = *scene;
    copy->mask_count = m + 1;
    for (int k = 0; k <= m; ++k) {
        wx_mask_def *md = &copy->masks[k];
        if (role[k] == ROLE_SKIP) {
            md->kind = WX_MASK_HEIGHT;
            md->has_min = md->has_max = true;
            md->min = 0.0f;
            md->max = 1.0f;
        } else if (role[k] == ROLE_REUSE) {
            md->kind = WX_MASK_COMBINE;
            md->scale = 1.0f;
            md->term_count = 1;
            md->terms[0] = (wx_term){ .kind = WX_TERM_SUBSTANCE,
                                      .index = scene->substance_count + k,
                                      .weight = 1.0f };
        } else if (md->kind == WX_MASK_CURVATURE && !(md->radius > 0.0f) && g->stride > 2) {
            md->radius = 2.0f * (float)g->stride * g->texel;
        }
    }
}

float vw_select_kth(float *a, size_t n, size_t k)
{
    ptrdiff_t lo = 0, hi = (ptrdiff_t)n - 1, want = (ptrdiff_t)k;
    while (lo < hi) {
        float pivot = a[lo + (hi - lo) / 2];
        ptrdiff_t i = lo, j = hi;
        while (i <= j) {
            while (a[i] < pivot) {
                i++;
            }
            while (a[j] > pivot) {
                j--;
            }
            if (i <= j) {
                float t = a[i];
                a[i++] = a[j];
                a[j--] = t;
            }
        }
        if (want <= j) {
            hi = j;
        } else if (want >= i) {
            lo = i;
        } else {
            break;
        }
    }
    return a[want];
}

float vw_world_mask_scale(const vw_world *world, int m, const float *values)
{
    if (world->scene.masks[m].kind != WX_MASK_CURVATURE) {
        return 1.0f;
    }
    size_t n = 0;
    float *a = malloc(((size_t)world->point_count + 1) * sizeof *a);
    float largest = 0.0f;
    for (int i = 0; a != NULL && i < world->point_count; ++i) {
        if (!isnan(values[i])) {
            a[n++] = fabsf(values[i]);
            largest = fmaxf(largest, fabsf(values[i]));
        }
    }
    float scale = n > 0 ? vw_select_kth(a, n, (size_t)((double)(n - 1) * 0.99)) : 0.0f;
    free(a);
    scale = scale > 0.0f ? scale : largest;
    return scale > 0.0f ? scale : 1.0f;
}

wx_result vw_world_compute_mask(vw_world *world, int m, wx_error *err)
{
    const wx_scene *scene = &world->scene;
    if (m < 0 || m >= scene->mask_count) {
        return m < 0 ? WX_OK : wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "no mask %d", m + 1);
    }
    if (world->mask_values[m] != NULL) {
        return WX_OK;
    }
    // The masks m reads (a Combine reads masks before it): those not known
    // yet are computed and kept too; known ones are read back, but for
    // Curvature's, which are not in [0, 1] (and cheap to compute again).
    mask_role role[WX_MAX_MASKS] = { ROLE_SKIP };
    role[m] = ROLE_COMPUTE;
    int reused = 0;
    for (int k = m; k >= 0; --k) {
        const wx_mask_def *md = &scene->masks[k];
        if (role[k] == ROLE_SKIP) {
            continue;
        }
        if (k < m && world->mask_values[k] != NULL && md->kind != WX_MASK_CURVATURE) {
            role[k] = ROLE_REUSE; // what it reads is not needed then
            reused++;
            continue;
        }
        role[k] = ROLE_COMPUTE;
        for (int t = 0; md->kind == WX_MASK_COMBINE && t < md->term_count; ++t) {
            const wx_term *term = &md->terms[t];
            if (term->kind == WX_TERM_MASK && term->index >= 0 && term->index < k) {
                role[term->index] = ROLE_COMPUTE;
            }
        }
    }
    wx_result r = WX_OK;
    if (world->mask_context == NULL) {
        wx_mask_context *ctx = calloc(1, sizeof *ctx);
        if (ctx == NULL) {
            return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "masks: out of memory");
        }
        r = wx_mask_context_init(scene, world->maps, false, ctx, err);
        if (r != WX_OK) {
            free(ctx);
            return r;
        }
        world->mask_context = ctx;
    }
    float *values[WX_MAX_MASKS] = { NULL };
    wx_scene *copy = malloc(sizeof *copy);
    bool oom = copy == NULL;
    for (int k = 0; k <= m && !oom; ++k) {
        if (role[k] == ROLE_COMPUTE && world->mask_values[k] == NULL) {
            values[k] = malloc(((size_t)world->point_count + 1) * sizeof *values[k]);
            oom = values[k] == NULL;
            for (int i = 0; !oom && i < world->point_count; ++i) {
                values[k][i] = NAN;
            }
        }
    }
    // Each layer of each camera is a grid of its own (docs/design.md section 14).
    for (int view = 0; view < scene->camera_count * WX_MAX_LAYERS && r == WX_OK && !oom; ++view) {
        int c = view / WX_MAX_LAYERS, layer = view % WX_MAX_LAYERS;
        if (layer >= vw_world_camera_layers(world, c)) {
            continue;
        }
        vw_range range = vw_world_layer_points(world, c, layer);
        wx_maps layer_maps;
        wx_maps_layer_view(&world->maps[world->camera_maps[c]], layer, &layer_maps);
        const wx_maps *maps = &layer_maps;
        if (range.count == 0 || maps->depth == NULL || maps->normal == NULL) {
            continue;
        }
        sample_grid g;
        if (!make_grid(world, c, maps, &g)) {
            oom = true;
            break;
        }
        // One zero plane (what Combine terms on substances read), the planes
        // of masks 0..m, then the known values of the masks reused.
        size_t cells = (size_t)g.cols * (size_t)g.rows;
        float *block = calloc((size_t)(m + 2 + reused) * cells + 1, sizeof *block);
        if (block == NULL) {
            free_grid(&g);
            oom = true;
            break;
        }
        float *planes[WX_MAX_MASKS];
        const float *substances[WX_MAX_SUBSTANCES + WX_MAX_MASKS];
        for (int s = 0; s < WX_MAX_SUBSTANCES + WX_MAX_MASKS; ++s) {
            substances[s] = block;
        }
        float *extra = block + (size_t)(m + 2) * cells;
        for (int k = 0; k <= m; ++k) {
            planes[k] = block + (size_t)(k + 1) * cells;
            if (role[k] != ROLE_REUSE) {
                continue;
            }
            for (int i = range.first; i < range.first + range.count; ++i) {
                ptrdiff_t q = grid_cell(world, maps, &g, i);
                float v = world->mask_values[k][i];
                if (q >= 0 && !isnan(v)) {
                    extra[q] = v;
                }
            }
            substances[scene->substance_count + k] = extra;
            extra += cells;
        }
        masks_for_grid(scene, m, role, &g, copy);
        wx_mask_points points = { .width = g.cols,
                                  .height = g.rows,
                                  .position = g.position,
                                  .normal = g.normal,
                                  .valid = g.valid,
                                  .texel = g.texel };
        r = wx_masks_at_points(copy, &world->opts, world->mask_context, -1, &points,
                               substances, planes, err);
        for (int i = range.first; r == WX_OK && i < range.first + range.count; ++i) {
            ptrdiff_t q = grid_cell(world, maps, &g, i);
            for (int k = 0; q >= 0 && g.valid[q] && k <= m; ++k) {
                if (values[k] != NULL) {
                    values[k][i] = planes[k][q];
                }
            }
        }
        free(block);
        free_grid(&g);
    }
    free(copy);
    if (r == WX_OK && oom) {
        r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "mask %s: out of memory", scene->masks[m].name);
    }
    for (int k = 0; k <= m; ++k) {
        if (r == WX_OK && values[k] != NULL) {
            world->mask_scale[k] = vw_world_mask_scale(world, k, values[k]);
            world->mask_values[k] = values[k];
        } else {
            free(values[k]);
        }
    }
    return r;
}

wx_result vw_world_show_mask(vw_world *world, int m, wx_error *err)
{
    wx_result r = vw_world_compute_mask(world, m, err);
    if (r == WX_OK) {
        world->mask = m < 0 ? -1 : m;
    }
    return r;
}

wx_result vw_world_keep_mask(vw_world *world, const char *name, wx_error *err)
{
    int m = name != NULL ? vw_world_find_mask(world, name) : -1;
    world->mask = -1;
    return vw_world_show_mask(world, m, err);
}

float vw_world_mask_value(const vw_world *world, int point)
{
    if (world->mask < 0 || world->mask_values[world->mask] == NULL) {
        return NAN;
    }
    return world->mask_values[world->mask][point];
}
