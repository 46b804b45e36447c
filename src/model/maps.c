// maps.c: the memory of a camera's maps (maps.h).
#include "model/maps.h"

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
}
