// cli.h: what the files of the `weathering` command line share (cli/): the
// parsed arguments, the commands main.c dispatches to, and the helpers two
// commands use.
#ifndef WX_CLI_H
#define WX_CLI_H

#include <stdbool.h>
#include <stdint.h>

#include "core/error.h"
#include "core/usage.h"
#include "model/scene.h"
#include "pipeline/pipeline.h"

typedef struct cli_args {
    const char *command;
    const char *scene_path;
    const char *out_dir; // NULL: out/<scene name>/
    const char *stats_path;
    uint64_t seed;
    bool seed_set;
    int threads; // 0: all cores
    bool quiet;
    // init, and run on a mesh (docs/presets.md).
    const char *preset;   // NULL: rain
    const char *init_out; // -o SCENE.xml
    int resolution;       // 0: 1024
    const char *units;    // NULL: m
    bool force;
    // run MESH: the scene generated in memory, loaded as scene_path's file
    // and written there once the run's checks pass.
    const char *scene_text;
    // tiles (docs/tiles.md): --tiles NX NZ (0: not given), --halo M, --slurm.
    int tiles_x, tiles_z;
    double halo;
    bool halo_set;
    bool slurm;
} cli_args;

/// The commands (main.c's table): each returns the exit status.
int command_info(const cli_args *args); // info.c
int command_bake(const cli_args *args); // phases.c
int command_simulate(const cli_args *args);
int command_gather(const cli_args *args);
int command_init(const cli_args *args); // mesh.c
int command_run(const cli_args *args);
int command_split(const cli_args *args); // split.c
int command_tiles(const cli_args *args); // tiles.c
int command_merge(const cli_args *args);

/// A usage error: the message and the hint to --help on stderr; returns 2.
static inline int usage_error(const char *fmt, const char *detail)
{
    return wx_usage_error("weathering", fmt, detail);
}

/// Loads the scene and fills the run options from it and the command line
/// (phases.c).
int cli_load_scene(const cli_args *args, wx_scene *scene, wx_run_def *opts);

/// Prints the error, if any, on stderr; returns r (phases.c).
int cli_report(wx_result r, const wx_error *err);

/// Runs the phases in `phases` in order, in one process; a phase that is not
/// run reads what an earlier command left in the output folder (phases.c).
int cli_run_phases(const cli_args *args, unsigned phases);

/// True for a scene file (NAME.xml but not an Ogre NAME.mesh.xml) (mesh.c).
bool cli_is_scene_file(const char *path);

#endif
