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
