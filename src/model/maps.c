// maps.c: the memory of a camera's maps (maps.h).
#include "model/maps.h"

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
    free(maps->dirt_attrs);
    memset(maps, 0, sizeof *maps);
}
