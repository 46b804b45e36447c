// maps.c: the memory of a camera's maps (maps.h).
#include "model/maps.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void wx_maps_free(wx_maps *maps)
{
    free(maps->depth);
    free(maps->normal);
    free(maps->impact);
    free(maps->dirt);
    free(maps->deposit);
    free(maps->erosion);
    free(maps->initial_dirt);
    free(maps->hits);
    free(maps->surface);
    free(maps->area);
    free(maps->owned);
    free(maps->dirt_attrs);
    memset(maps, 0, sizeof *maps);
}

int wx_dirt_channels(const wx_scene *scene, bool simulated, char names[][WX_NAME_MAX])
{
    int n = 0;
    if (scene == NULL || !scene->substances_declared) {
        static const char *const v1[5] = { "R", "G", "B", WX_INITIAL_DIRT_CHANNEL,
                                           WX_HITS_CHANNEL };
        for (int k = 0; k < (simulated ? 5 : 3); ++k) {
            snprintf(names[n++], WX_NAME_MAX, "%s", v1[k]);
        }
    } else {
        static const char *const parts[3] = { "amount", "deposit", "erosion" };
        for (int s = 0; s < scene->substance_count; ++s) {
            for (int k = 0; k < 3; ++k) {
                snprintf(names[n++], WX_NAME_MAX, "%s.%s", scene->substances[s], parts[k]);
            }
        }
        if (simulated) {
            for (int s = 0; s < scene->substance_count; ++s) {
                snprintf(names[n++], WX_NAME_MAX, "%s.initial", scene->substances[s]);
            }
            snprintf(names[n++], WX_NAME_MAX, "%s", WX_HITS_CHANNEL);
        }
    }
    if (scene != NULL && wx_scene_has_surface_rules(scene)) {
        snprintf(names[n++], WX_NAME_MAX, "%s", WX_SURFACE_CHANNEL);
    }
    if (scene != NULL && wx_scene_has_grow(scene)) {
        snprintf(names[n++], WX_NAME_MAX, "%s", WX_AREA_CHANNEL);
    }
    return n;
}

bool wx_layer_channel(char out[WX_NAME_MAX], int layer, const char *channel)
{
    int n = layer > 0 ? snprintf(out, WX_NAME_MAX, "layer%d.%s", layer, channel)
                      : snprintf(out, WX_NAME_MAX, "%s", channel);
    return n > 0 && n < WX_NAME_MAX;
}

void wx_maps_layer_view(const wx_maps *maps, int layer, wx_maps *view)
{
    *view = *maps;
    view->layers = 1;
    size_t n = (size_t)maps->width * (size_t)maps->height;
    size_t k = (size_t)(layer > 0 && layer < wx_maps_layers(maps) ? layer : 0);
    size_t S = (size_t)wx_maps_substances(maps);
    // Offsets of one layer's block in each plane (model/maps.h's layout).
#define WX_LAYER_PLANE(field, per_texel)                                                        \
    view->field = maps->field != NULL ? maps->field + k * (per_texel) * n : NULL
    WX_LAYER_PLANE(depth, 1);
    WX_LAYER_PLANE(normal, 3);
    WX_LAYER_PLANE(impact, 2);
    WX_LAYER_PLANE(dirt, S);
    WX_LAYER_PLANE(deposit, S);
    WX_LAYER_PLANE(erosion, S);
    WX_LAYER_PLANE(initial_dirt, S);
    WX_LAYER_PLANE(hits, 1);
    WX_LAYER_PLANE(surface, 1);
    WX_LAYER_PLANE(area, 1);
    WX_LAYER_PLANE(owned, 1);
#undef WX_LAYER_PLANE
    view->crossing_depth = maps->depth;
    view->crossing_normal = maps->normal;
    view->crossing_layers = wx_maps_layers(maps);
    view->crossing_layer = (int)k;
}

bool wx_crossing_nearer(const float *depth, const float *normal, int layers, int layer,
                        size_t texels, size_t t, float dp, const float n[3])
{
    if (depth == NULL || normal == NULL || layers < 2) {
        return false;
    }
    float own = fabsf(dp - depth[(size_t)layer * texels + t]);
    for (int k = 0; k < layers; ++k) {
        size_t at = (size_t)k * texels + t;
        if (k == layer || wx_depth_is_empty(depth[at])) {
            continue;
        }
        const float *m = normal + 3 * at;
        if (fabsf(dp - depth[at]) < own && n[0] * m[0] + n[1] * m[1] + n[2] * m[2] > 0.0f) {
            return true;
        }
    }
    return false;
}

int wx_layers_outline(const bool *entering, int n, int K, uint8_t *kind, uint8_t *from)
{
    int partner[WX_MAX_LAYERS], stack[WX_MAX_LAYERS], top = 0, tail = -1;
    bool sheet[WX_MAX_LAYERS];
    for (int k = 0; k < n; ++k) {
        partner[k] = -1;
        sheet[k] = false;
        if (entering[k]) {
            stack[top++] = k;
        } else if (top > 0) {
            int e = stack[--top];
            partner[e] = k;
            partner[k] = e;
        } else {
            sheet[k] = true;
        }
    }
    if (top > 0 && n == K) {
        tail = stack[0]; // the outermost solid left open
    }
    for (int i = 0; i < top; ++i) {
        sheet[stack[i]] = stack[i] != tail && n < K;
    }
    int m = 0, start = -1, end = -1;
    for (int k = 0; k < n; ++k) {
        if (start >= 0 && k > end) { // the union of solids so far ends before k
            kind[m] = WX_OUTLINE_ENTER, from[m++] = (uint8_t)start;
            kind[m] = WX_OUTLINE_LEAVE, from[m++] = (uint8_t)end;
            start = -1;
        }
        if (k == tail) {
            kind[m] = WX_OUTLINE_TAIL, from[m++] = (uint8_t)(start >= 0 ? start : k);
            return m;
        }
        if (entering[k] && partner[k] > k) {
            if (start < 0) {
                start = k;
                end = partner[k];
            } else if (partner[k] > end) {
                end = partner[k];
            }
        } else if (sheet[k] && start < 0) {
            kind[m] = WX_OUTLINE_SHEET, from[m++] = (uint8_t)k;
        }
    }
    if (start >= 0) {
        kind[m] = WX_OUTLINE_ENTER, from[m++] = (uint8_t)start;
        kind[m] = WX_OUTLINE_LEAVE, from[m++] = (uint8_t)end;
    }
    if (n == K && m > 0) {
        if (kind[m - 1] == WX_OUTLINE_LEAVE) {
            m--;
            kind[m - 1] = WX_OUTLINE_TAIL;
        } else {
            kind[m - 1] = WX_OUTLINE_TAIL;
        }
    }
    return m;
}

// The outermost solid a texel's crossings leave open (bracket matching, as
// wx_layers_outline): its entering crossing, or -1 when every solid closes.
static int outermost_open(const bool *entering, int n)
{
    int stack[WX_MAX_LAYERS], top = 0;
    for (int k = 0; k < n; ++k) {
        if (entering[k]) {
            stack[top++] = k;
        } else if (top > 0) {
            top--;
        }
    }
    return top > 0 ? stack[0] : -1;
}

void wx_maps_bury(const wx_maps *maps, const float view[3], float sheet, float *depth)
{
    int K = wx_maps_layers(maps);
    size_t texels = (size_t)maps->width * (size_t)maps->height;
    memcpy(depth, maps->depth, (size_t)K * texels * sizeof *depth);
    if (K < 2 || maps->normal == NULL) {
        return;
    }
    for (size_t t = 0; t < texels; ++t) {
        bool entering[WX_MAX_LAYERS], keep[WX_MAX_LAYERS];
        int n = 0;
        while (n < K && !wx_depth_is_empty(maps->depth[(size_t)n * texels + t])) {
            const float *nv = maps->normal + 3 * ((size_t)n * texels + t);
            entering[n] = !(nv[0] * view[0] + nv[1] * view[1] + nv[2] * view[2] > 0.0f);
            keep[n] = false;
            n++;
        }
        // A face between two crossings that close around it is buried
        // whatever follows (an outline of n + 1 layers: no tail). A solid left
        // open is a sheet while the stack has room (its crossings are kept);
        // in a full stack it runs on behind the last layer, as the collider
        // reads it (its tail), and every crossing after its entering face lies
        // inside it: buried too, else a face the collider calls solid (the
        // back of a facade box against the house's core) would be seen.
        uint8_t kind[WX_MAX_LAYERS + 1], from[WX_MAX_LAYERS + 1];
        int m = wx_layers_outline(entering, n, n + 1, kind, from);
        for (int k = 0; k < m; ++k) {
            keep[from[k]] = true;
        }
        int open = n == K ? outermost_open(entering, n) : -1;
        for (int k = open + 1; open >= 0 && k < n; ++k) {
            keep[k] = false;
        }
        // Faces in contact are sealed: a solid's face within a sheet's
        // thickness behind another solid's (a wall behind the glass pane
        // that touches it, a house's underside on the ground it stands on),
        // or behind a pane facing the camera.
        for (int k = 1; k < m; ++k) {
            float gap = maps->depth[(size_t)from[k] * texels + t] -
                        maps->depth[(size_t)from[k - 1] * texels + t];
            bool enters = kind[k] == WX_OUTLINE_ENTER || (int)from[k] == open;
            if (!enters || !(gap < sheet)) {
                continue;
            }
            if (kind[k - 1] == WX_OUTLINE_LEAVE) {
                keep[from[k]] = keep[from[k - 1]] = false;
            } else if (kind[k - 1] == WX_OUTLINE_SHEET && entering[from[k - 1]]) {
                keep[from[k]] = false;
            }
        }
        for (int k = 0; k < n; ++k) {
            if (!keep[k]) {
                depth[(size_t)k * texels + t] = INFINITY;
            }
        }
    }
}
