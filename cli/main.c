// main.c: the `weathering` command line (docs/design.md section 6).
//
//   weathering COMMAND SCENE.xml [--out DIR] [--seed N] [--threads N] [--stats FILE.json] [-q]
//   weathering init MESH [--preset P] [-o SCENE.xml] [--resolution PX] [--units U] [--force]
//   weathering run MESH --preset P [options]      (docs/presets.md)
//   weathering split FILE.exr [--out DIR]
//   weathering tiles SCENE.xml --tiles NX NZ [--halo M] [--out DIR] [--slurm]
//   weathering merge DIR [--out DIR2]
//
// Exit status: 0 success, 2 bad usage or bad input (one message naming the file,
// and the line for XML), 1 any other failure.
//
// This file reads the arguments, dispatches to the commands (info.c,
// phases.c, mesh.c, split.c, tiles.c) and catches the interrupts.
#include "cli.h"

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/atomic_file.h"
#include "core/dist.h"
#include "core/limits.h"
#include "core/usage.h"
#include "pipeline/preset.h"

#define WX_VERSION "0.1.0"

typedef int (*command_fn)(const cli_args *args);

typedef struct command {
    const char *name;
    command_fn run;
    const char *summary;
} command;

static const command commands[] = {
    { "run", command_run, "bake what needs baking, simulate, gather: the whole job" },
    { "bake", command_bake, "render the maps of <View> cameras from the scene's meshes" },
    { "simulate", command_simulate, "fly the particles; write <camera>_dirt.exr" },
    { "gather", command_gather, "turn the dirt maps into the mask and the TextureMaps" },
    { "info", command_info, "validate a scene and print what it holds" },
    { "init", command_init, "write a commented scene for a mesh from a preset (MESH, not SCENE)" },
    { "split", command_split, "write each channel of an EXR as a file of its own (FILE.exr)" },
    { "tiles", command_tiles, "cut a scene into tile scenes, a job each (--tiles NX NZ)" },
    { "merge", command_merge, "join the tiles' masks and TextureMaps (DIR, not SCENE)" },
};
enum { COMMAND_COUNT = sizeof commands / sizeof commands[0] };

static void print_usage(FILE *out)
{
    fprintf(out,
            "usage: weathering COMMAND SCENE.xml [options]\n"
            "       weathering init MESH [--preset P] [-o SCENE.xml] [--resolution PX] [--units U] [--force]\n"
            "       weathering run MESH --preset P [options]\n"
            "       weathering split FILE.exr [--out DIR]\n"
            "       weathering tiles SCENE.xml --tiles NX NZ [--halo M] [--out DIR] [--slurm]\n"
            "       weathering merge DIR [--out DIR2]\n"
            "\n"
            "Particle-driven weathering masks: dirt-carrying particles collide against\n"
            "depth maps of a model and leave a dirt mask for compositing.\n"
            "\n"
            "commands:\n");
    for (int i = 0; i < COMMAND_COUNT; ++i) {
        fprintf(out, "  %-10s %s\n", commands[i].name, commands[i].summary);
    }
    fprintf(out,
            "\n"
            "options:\n"
            "  --out DIR          output folder (default: out/<scene name>/)\n"
            "  --seed N           random seed (default: the scene's Simulation seed)\n"
            "  --threads N        worker threads (default: all cores)\n"
            "  --stats FILE.json  write run statistics as JSON\n"
            "  -q, --quiet        no progress bars or notes on stderr\n"
            "  --preset P         init, run MESH: rain (default), dust, soot, moss, rust or\n"
            "                     old_paint\n"
            "  -o SCENE.xml       init: the scene to write (default: MESH's name .xml here)\n"
            "  --resolution PX    init, run MESH: texels across the largest frame (1024)\n"
            "  --units U          init, run MESH: the mesh's unit: m (default), cm, mm, in, ft\n"
            "  --force            init: replace an existing scene file\n"
            "  --tiles NX NZ      tiles: tiles along x and z (1 to 1000 each)\n"
            "  --halo M           tiles: world units around a tile that shelter it (0)\n"
            "  --slurm            tiles: also write a Slurm job array and its merge job\n"
            "  -h, --help         this help\n"
            "  --version          print the version\n"
            "\n"
            "exit status: 0 success, 2 bad usage or bad input, 1 other failure\n"
            "documentation: docs/user-guide.md\n");
}

// Takes the value of an option given as "--opt VALUE" or "--opt=VALUE".
static const char *option_value(int argc, char **argv, int *i, const char *name, bool *missing)
{
    size_t len = strlen(name);
    const char *arg = argv[*i];
    if (arg[len] == '=') {
        return arg + len + 1;
    }
    if (*i + 1 >= argc) {
        *missing = true;
        return NULL;
    }
    *i += 1;
    return argv[*i];
}

static bool is_option(const char *arg, const char *name)
{
    size_t len = strlen(name);
    return strncmp(arg, name, len) == 0 && (arg[len] == '\0' || arg[len] == '=');
}

// Returns -1 when parsing succeeded and the program should go on, else an exit status.
static int parse_args(int argc, char **argv, cli_args *args)
{
    memset(args, 0, sizeof *args);
    for (int i = 1; i < argc; ++i) {
        const char *arg = argv[i];
        bool missing = false;
        if (strcmp(arg, "-h") == 0 || strcmp(arg, "--help") == 0) {
            print_usage(stdout);
            return 0;
        }
        if (strcmp(arg, "--version") == 0) {
            printf("weathering %s\n", WX_VERSION);
            return 0;
        }
        if (strcmp(arg, "-q") == 0 || strcmp(arg, "--quiet") == 0) {
            args->quiet = true;
        } else if (is_option(arg, "--out")) {
            args->out_dir = option_value(argc, argv, &i, "--out", &missing);
            if (!missing && args->out_dir[0] == '\0') {
                return usage_error("%s needs a folder name", "--out");
            }
            if (!missing && strlen(args->out_dir) >= WX_PATH_MAX) {
                return usage_error("--out: a folder name of at most %s characters", "4095");
            }
        } else if (is_option(arg, "--stats")) {
            args->stats_path = option_value(argc, argv, &i, "--stats", &missing);
            if (!missing && args->stats_path[0] == '\0') {
                return usage_error("%s needs a file name", "--stats");
            }
            if (!missing && strlen(args->stats_path) >= WX_PATH_MAX) {
                return usage_error("--stats: a file name of at most %s characters", "4095");
            }
        } else if (is_option(arg, "--seed")) {
            const char *v = option_value(argc, argv, &i, "--seed", &missing);
            if (!missing && !wx_parse_whole(v, 0, UINT64_MAX, &args->seed)) {
                return usage_error("--seed takes a whole number from 0 to 2^64-1, not '%s'", v);
            }
            args->seed_set = true;
        } else if (is_option(arg, "--threads")) {
            const char *v = option_value(argc, argv, &i, "--threads", &missing);
            uint64_t n = 0;
            if (!missing && !wx_parse_whole(v, 1, 1024, &n)) {
                return usage_error("--threads takes a whole number from 1 to 1024, not '%s'", v);
            }
            args->threads = (int)n;
        } else if (is_option(arg, "--preset")) {
            args->preset = option_value(argc, argv, &i, "--preset", &missing);
            if (!missing && wx_preset_find(args->preset) < 0) {
                return usage_error("unknown preset '%s' (presets: rain, dust, soot, moss, rust, "
                                   "old_paint)",
                                   args->preset);
            }
        } else if (strcmp(arg, "-o") == 0 || is_option(arg, "--output")) {
            args->init_out = option_value(argc, argv, &i, arg[1] == 'o' ? "-o" : "--output",
                                          &missing);
            if (!missing && (args->init_out[0] == '\0' || strlen(args->init_out) >= WX_PATH_MAX)) {
                return usage_error("%s needs a file name", "-o");
            }
        } else if (is_option(arg, "--resolution")) {
            const char *v = option_value(argc, argv, &i, "--resolution", &missing);
            uint64_t n = 0;
            if (!missing && !wx_parse_whole(v, 16, 16384, &n)) {
                return usage_error("--resolution takes a whole number from 16 to 16384, not '%s'",
                                   v);
            }
            args->resolution = (int)n;
        } else if (is_option(arg, "--units")) {
            args->units = option_value(argc, argv, &i, "--units", &missing);
            if (!missing && !(wx_unit_metres(args->units) > 0.0)) {
                return usage_error("--units takes m, cm, mm, in or ft, not '%s'", args->units);
            }
        } else if (strcmp(arg, "--force") == 0) {
            args->force = true;
        } else if (strcmp(arg, "--tiles") == 0) {
            uint64_t nx = 0, nz = 0;
            if (i + 2 >= argc) {
                return usage_error("%s needs two whole numbers: NX NZ", "--tiles");
            }
            if (!wx_parse_whole(argv[i + 1], 1, 1000, &nx) ||
                !wx_parse_whole(argv[i + 2], 1, 1000, &nz)) {
                return usage_error("--tiles takes two whole numbers from 1 to 1000, not '%s'",
                                   argv[i + 1]);
            }
            args->tiles_x = (int)nx;
            args->tiles_z = (int)nz;
            i += 2;
        } else if (is_option(arg, "--halo")) {
            const char *v = option_value(argc, argv, &i, "--halo", &missing);
            char *end = NULL;
            double h = missing ? 0.0 : strtod(v, &end);
            if (!missing && (end == v || *end != '\0' || !(h >= 0.0) || !(h < 1e30))) {
                return usage_error("--halo takes a distance of 0 or more, not '%s'", v);
            }
            args->halo = h;
            args->halo_set = true;
        } else if (strcmp(arg, "--slurm") == 0) {
            args->slurm = true;
        } else if (arg[0] == '-' && arg[1] != '\0') {
            return usage_error("unknown option '%s'", arg);
        } else if (args->command == NULL) {
            args->command = arg;
        } else if (args->scene_path == NULL) {
            args->scene_path = arg;
        } else {
            return usage_error("unexpected argument '%s'", arg);
        }
        if (missing) {
            return usage_error("%s needs a value", arg);
        }
    }
    if (args->command == NULL) {
        print_usage(stderr);
        return WX_BAD_INPUT;
    }
    return -1;
}

// --- interrupts -------------------------------------------------------------------

// SIGINT, SIGTERM, SIGHUP: remove the temporaries still being written and exit
// with 128 + the signal (130 for Ctrl-C). Finished outputs are already under
// their final names (atomic rename); no output is ever half there.
static void on_interrupt(int sig)
{
    wx_temp_interrupt();
    static const char message[] = "\nweathering: interrupted; temporary files removed\n";
    ssize_t ignored = write(STDERR_FILENO, message, sizeof message - 1);
    (void)ignored;
    _exit(128 + sig);
}

static void install_interrupt_handlers(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_interrupt;
    sigfillset(&sa.sa_mask); // no second signal inside the handler
    const int signals[] = { SIGINT, SIGTERM, SIGHUP };
    for (size_t i = 0; i < sizeof signals / sizeof signals[0]; ++i) {
        struct sigaction old;
        // nohup: an ignored SIGHUP stays ignored. SIGINT is caught even when the
        // shell started us in the background with it ignored: `kill -INT` on a
        // background run means "stop it".
        if (signals[i] == SIGHUP && sigaction(SIGHUP, NULL, &old) == 0 &&
            old.sa_handler == SIG_IGN) {
            continue;
        }
        sigaction(signals[i], &sa, NULL);
    }
}

static int dispatch(const cli_args *orig)
{
    const cli_args args = *orig;
    for (int i = 0; i < COMMAND_COUNT; ++i) {
        if (strcmp(args.command, commands[i].name) == 0) {
            if (args.scene_path == NULL) {
                return usage_error(strcmp(args.command, "init") == 0    ? "%s needs a mesh file"
                                   : strcmp(args.command, "split") == 0 ? "%s needs an EXR file"
                                   : strcmp(args.command, "merge") == 0 ? "%s needs a folder"
                                                                        : "%s needs a scene file",
                                   args.command);
            }
            bool mesh_options = args.preset != NULL || args.init_out != NULL ||
                                args.resolution > 0 || args.units != NULL || args.force;
            bool takes_them = strcmp(args.command, "init") == 0 ||
                              (strcmp(args.command, "run") == 0 && !cli_is_scene_file(args.scene_path));
            if (mesh_options && !takes_them) {
                return usage_error("--preset, -o, --resolution, --units and --force are for "
                                   "`init MESH` and `run MESH` (%s was given a scene)",
                                   args.command);
            }
            bool tile_options = args.tiles_x > 0 || args.halo_set || args.slurm;
            if (tile_options && strcmp(args.command, "tiles") != 0) {
                return usage_error("--tiles, --halo and --slurm are for `tiles` (not %s)",
                                   args.command);
            }
            return commands[i].run(&args);
        }
    }
    return usage_error("unknown command '%s'", args.command);
}

// --- ranks (MPI) ------------------------------------------------------------------

// A rank other than 0 of an MPI run (docs/scale-out.md): silent; it waits for
// rank 0 to check the scene and bake, then joins the simulation of `run` or
// `simulate` (cli_run_phases) or, when rank 0 runs none, ends. Rank 0 reports.
static int follow(cli_args *args)
{
    if (freopen("/dev/null", "w", stdout) == NULL) {
        return WX_FAIL;
    }
    args->quiet = true;
    if (wx_dist_wait() != WX_DIST_JOIN) {
        return 0;
    }
    int status = dispatch(args);
    // This rank failed in the simulation (its message on stderr): none may
    // wait for it.
    return status != 0 ? wx_dist_abort(status) : 0;
}

int main(int argc, char **argv)
{
    install_interrupt_handlers();
    if (!wx_dist_init(&argc, &argv)) {
        fprintf(stderr, "weathering: MPI could not start\n");
        return WX_FAIL;
    }
    cli_args args;
    int status = parse_args(argc, argv, &args); // every rank alike
    if (status < 0 && wx_dist_rank() > 0) {
        status = follow(&args);
    } else if (status < 0) {
        status = dispatch(&args);
        // The other ranks wait for rank 0 at most once: released here when the
        // command did not start a simulation.
        if (wx_dist_released() != WX_DIST_JOIN) {
            wx_dist_release(status);
        }
    }
    if (status != 0 && wx_dist_released() == WX_DIST_JOIN) {
        wx_dist_abort(status); // rank 0 failed in the simulation: none may wait for it
    }
    wx_dist_finalize();
    return status;
}
