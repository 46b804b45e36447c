// tiles.c: `weathering tiles SCENE.xml --tiles NX NZ [--halo M] [--out DIR]
// [--slurm]` and `weathering merge DIR [--out DIR2]` (docs/tiles.md,
// pipeline/tiles.h).
#define _XOPEN_SOURCE 700 // realpath
#include "cli.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/scene_xml.h"
#include "pipeline/tiles.h"

int command_tiles(const cli_args *args)
{
    if (args->tiles_x <= 0) {
        return usage_error("%s needs --tiles NX NZ", "tiles");
    }
    // The default folder: out/<scene name>_tiles/.
    char out_dir[WX_PATH_MAX];
    if (args->out_dir != NULL) {
        snprintf(out_dir, sizeof out_dir, "%s", args->out_dir);
    } else {
        wx_scene scene;
        memset(&scene, 0, sizeof scene);
        wx_error err;
        wx_result r = wx_scene_load(args->scene_path, &scene, &err);
        if (r != WX_OK) {
            return cli_report(r, &err);
        }
        char name[256];
        wx_default_out_name(scene.name, name, sizeof name - 8);
        snprintf(out_dir, sizeof out_dir, "out/%s_tiles", name);
        wx_scene_free(&scene);
    }
    // The job scripts run this very program, wherever it was started from.
    char program[PATH_MAX];
    if (realpath("/proc/self/exe", program) == NULL) {
        snprintf(program, sizeof program, "weathering");
    }
    wx_tiles_def def = { .scene_path = args->scene_path,
                         .nx = args->tiles_x,
                         .nz = args->tiles_z,
                         .halo = args->halo,
                         .out_dir = out_dir,
                         .slurm = args->slurm,
                         .program = program,
                         .quiet = args->quiet };
    wx_error err;
    return cli_report(wx_tiles_write(&def, &err), &err);
}

int command_merge(const cli_args *args)
{
    wx_merge_def def = { .dir = args->scene_path,
                         .out_dir = args->out_dir,
                         .threads = args->threads,
                         .quiet = args->quiet };
    wx_error err;
    return cli_report(wx_merge_tiles(&def, &err), &err);
}
