// world_save.c: saving a world's simulation (world.h, G and --gather): the
// dirt maps written and the mask gathered from the simulation in memory
// (the same bytes as a gather of the dirt maps just written).
#include "world_internal.h"

#include <stdio.h>

#include "pipeline/outputs.h"
#include "pipeline/simulate_phase.h"

wx_result vw_world_gather(vw_world *world, char saved[WX_PATH_MAX], wx_error *err)
{
    snprintf(saved, WX_PATH_MAX, "%s", world->opts.out_dir);
    wx_result r = wx_output_prepare(&world->scene, &world->opts, NULL, err);
    if (r == WX_OK) {
        r = wx_write_dirt_maps(&world->scene, &world->opts, world->sim, world->maps, err);
    }
    if (r != WX_OK || world->scene.output_index < 0) {
        return r;
    }
    const wx_scene_camera *out = &world->scene.cameras[world->scene.output_index];
    r = wx_gather_simulation(&world->scene, &world->opts, world->sim, world->maps, err);
    if (r == WX_OK) {
        r = wx_output_path(&world->scene, &world->opts, out->output_file, saved, err);
    }
    return r;
}
