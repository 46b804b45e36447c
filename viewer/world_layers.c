// world_layers.c: the layers of a world's cameras (world.h, docs/design.md
// section 14): each camera's layers, their depth samples, L's cycle, and
// which camera and layer a view of the simulation is.
#include "world_internal.h"

#include "sim/simulate.h"

int vw_world_camera_layers(const vw_world *world, int c)
{
    return wx_maps_layers(&world->maps[world->camera_maps[c]]);
}

vw_range vw_world_layer_points(const vw_world *world, int c, int layer)
{
    if (layer < 0) {
        return world->camera_points[c];
    }
    if (layer >= vw_world_camera_layers(world, c)) {
        return (vw_range){ world->camera_points[c].first, 0 };
    }
    return world->layer_points[(size_t)c * WX_MAX_LAYERS + (size_t)layer];
}

int vw_world_next_layer(const vw_world *world, int layer)
{
    return world->max_layers > 1 && layer + 1 < world->max_layers ? layer + 1 : -1;
}

int vw_world_view_camera(const vw_world *world, int view, int *layer)
{
    if (layer != NULL) {
        *layer = 0;
    }
    if (world->sim == NULL || view < 0 || view >= wx_sim_input_count(world->sim)) {
        return -1;
    }
    return world->input_camera[wx_sim_view_camera(world->sim, view, layer)];
}
