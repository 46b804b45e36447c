// pipeline.h: the phases of a run (bake, simulate, gather) and what they share:
// the run options of the command line, the output folder rules of DESIGN
// section 6, and the statistics written by --stats.
#ifndef WX_PIPELINE_H
#define WX_PIPELINE_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "maps.h"
#include "scene.h"

/// Options shared by every phase (command line: --out, --seed, --threads, -q, --stats).
typedef struct wx_run_options {
    char out_dir[WX_PATH_MAX]; ///< the output folder; exists once wx_output_prepare ran
    uint64_t seed;             ///< the scene's seed unless --seed was given
    int threads;               ///< worker threads, >= 1 (default: all cores)
    bool quiet;                ///< -q: no progress bars, no notes on stderr
    const char *stats_path;    ///< --stats FILE.json, or NULL
} wx_run_options;

/// Counters of a simulation (the pinned keys of --stats).
typedef struct wx_sim_stats {
    int64_t particles_emitted;
    int64_t particle_steps;
    int64_t collisions;
    int64_t absorbed;
    int64_t settled;
    int64_t escaped;
    int64_t alive;
    double dirt_initial_surface;
    double dirt_emitted;
    double dirt_final_surface;
    double dirt_in_flight;
    double dirt_escaped;
} wx_sim_stats;

/// Wall-clock seconds per phase.
typedef struct wx_phase_times {
    double load;
    double bake;
    double simulate;
    double gather;
    double total;
} wx_phase_times;

/// Default run options for a scene: out/<scene name>/ (the name made safe: see
/// wx_default_out_name), the scene's seed, all cores.
void wx_run_options_default(const wx_scene *scene, wx_run_options *opts);

/// The default output folder's name for a scene name: the name with every
/// character but letters, digits, '_', '-' and '.' replaced by '_', leading dots
/// too, so that out/NAME always lies inside out/ ("..": "__"; "": "scene").
void wx_default_out_name(const char *scene_name, char *out, size_t cap);

/// Number of online processors (at least 1).
int wx_cpu_count(void);

/// The phases of a run, as bits.
enum {
    WX_PHASE_BAKE = 1 << 0,
    WX_PHASE_SIMULATE = 1 << 1,
    WX_PHASE_GATHER = 1 << 2,
    WX_PHASE_ALL = 7,
};

/// Longest plain file name the program writes into an output folder.
#define WX_OUTPUT_NAME_MAX 320

/// The plain names of the files a run writes into its output folder.
typedef struct wx_output_names {
    int count;
    char (*names)[WX_OUTPUT_NAME_MAX];
} wx_output_names;

/// Lists every file that the phases in `phases` write for `scene`: the maps
/// `bake` writes (<camera>_depth.exr ... for each <View> camera without map
/// files), the dirt map `simulate` writes for each input camera
/// (<camera>_dirt.exr), the mask and its preview. WX_FAIL when out of memory.
wx_result wx_output_names_list(const wx_scene *scene, unsigned phases, wx_output_names *out,
                               wx_error *err);

/// Frees the list; the struct is zeroed.
void wx_output_names_free(wx_output_names *names);

/// The preview's name for a mask's: its extension replaced by .png ("mask.exr"
/// -> "mask.png"; "mask" -> "mask.png"; "mask.png" -> "mask.preview.png").
void wx_preview_name(const char *mask_name, char *out, size_t cap);

/// Checks made before any work or any folder: no file the phases will write
/// is an input of the scene (the scene, a map or a mesh it names) or an
/// existing non-regular file (a folder, a FIFO, a symbolic link), and the
/// --stats file, when given, is neither an input nor one of the run's outputs
/// nor an existing non-regular file, and lies in a folder that exists (or in
/// the output folder). WX_BAD_INPUT with the path and the reason.
wx_result wx_check_outputs(const wx_scene *scene, const wx_run_options *opts, unsigned phases,
                           wx_error *err);

/// Creates the output folder (and its parents), checks it is a folder, and
/// removes the temporaries that killed runs of this program left there (only
/// ".NAME.tmpPID" where NAME is one of the scene's output names or the --stats
/// file's). `created` (may be NULL) gets the topmost folder this call made, or
/// "" when the folder existed.
wx_result wx_output_prepare(const wx_scene *scene, const wx_run_options *opts,
                            char created[WX_PATH_MAX], wx_error *err);

/// After a failed run: removes the output folder and the parents up to
/// `created` (what wx_output_prepare made) when they are empty.
void wx_output_remove_empty(const char *out_dir, const char *created);

/// Memory a run needs at its peak, estimated before work starts from the scene
/// alone (docs/reliability.md): the program itself, plus the largest of its
/// phases (they run one after the other; each frees what the next does not use).
typedef struct wx_memory_need {
    double baseline_bytes; ///< the program and its libraries (WX_MEMORY_BASELINE)
    double mesh_bytes;     ///< importing the meshes: WX_MESH_BYTES_PER_FILE_BYTE x their files
    double bake_bytes;     ///< the bake: GL context, framebuffer, images being written, meshes
    double sim_map_bytes;  ///< the simulation's maps, collider and dirt (without particles)
    double particles;      ///< particles the emitters emit over the simulation
    double particle_bytes; ///< as if every particle emitted were alive at once
    double gather_bytes;   ///< the gather: the maps it reads, its planes, the files it writes
    double total_bytes;    ///< baseline + the largest phase
    const char *phase;     ///< the largest phase: "bake", "simulate" or "gather"
    int camera_line;       ///< scene line of the camera with the largest maps
    int emitter_line;      ///< scene line of the emitter with the most particles
    int mesh_line;         ///< scene line of the largest mesh file
} wx_memory_need;

/// The program's own memory before any scene data (code, libraries, heaps).
#define WX_MEMORY_BASELINE (64.0 * 1024.0 * 1024.0)
/// The GL context and llvmpipe's own buffers in the bake.
#define WX_BAKE_CONTEXT_BYTES (40.0 * 1024.0 * 1024.0)
/// Bytes per byte of mesh file while Assimp imports it (measured: about 18 for
/// OBJ; binary formats hold fewer bytes per triangle).
#define WX_MESH_BYTES_PER_FILE_BYTE 32.0
/// Bytes per texel of the bake's float framebuffer (RGBA32F x 2, R32F, depth).
#define WX_BAKE_FRAMEBUFFER_BYTES_PER_TEXEL 40.0
/// Bytes per texel of the images of one baked camera (depth 1, normal 3, impact
/// 3, dirt 3 floats; an output camera only depth and normal). Two cameras' sets
/// are alive while one is written and the next rendered.
#define WX_BAKE_INPUT_IMAGE_BYTES_PER_TEXEL 40.0
#define WX_BAKE_OUTPUT_IMAGE_BYTES_PER_TEXEL 16.0
/// Bytes per input texel in the simulation: the maps (depth, normal, impact,
/// dirt: 9 floats), the collider's depth and pyramid (5), the dirt in double (16).
#define WX_SIM_BYTES_PER_INPUT_TEXEL 57.0
/// Bytes per texel of the dirt map being written (4 floats).
#define WX_SIM_WRITE_BYTES_PER_TEXEL 16.0
/// Bytes per particle: WX_PARTICLE_BYTES with room for the arrays to double as
/// they grow, plus the per-step events and candidates of the workers.
#define WX_BYTES_PER_PARTICLE 192.0
/// Bytes per input texel in the gather (depth, normal, dirt) and per output
/// texel (its depth and normal, the mask, the second pass's 5 planes, the
/// preview's sorted values).
#define WX_GATHER_BYTES_PER_INPUT_TEXEL 20.0
#define WX_GATHER_BYTES_PER_OUTPUT_TEXEL 48.0
/// Margin over the measured sizes (allocator rounding, small buffers).
#define WX_MEMORY_MARGIN 1.15

/// Estimates the peak memory of running `phases` (WX_PHASE_*) of the scene: the
/// bake counts when `phases` has it and some camera is baked, the particles when
/// it has the simulation.
void wx_memory_estimate(const wx_scene *scene, unsigned phases, wx_memory_need *need);

/// Bytes this process can still use: the least of MemAvailable, the cgroup's
/// memory.max minus memory.current and RLIMIT_AS / RLIMIT_DATA; < 0 when
/// unknown. $WX_MEMORY_AVAILABLE_MB overrides it (tests, or to insist).
double wx_memory_available(void);

/// Refuses (WX_BAD_INPUT, "scene:LINE: ...") a run whose estimate exceeds the
/// memory available, naming the numbers, before any work starts.
wx_result wx_memory_check(const wx_scene *scene, unsigned phases, wx_error *err);

/// Joins the output folder and a plain file name into `path`. Fails (WX_BAD_INPUT)
/// when the result would be one of the scene's input files (a map or a mesh the
/// scene names, the scene itself): inputs are never overwritten. Maps this
/// program baked into the output folder (maps_in_output) are not inputs.
wx_result wx_output_path(const wx_scene *scene, const wx_run_options *opts, const char *name,
                         char path[WX_PATH_MAX], wx_error *err);

/// True when some camera is given by <View> without map files in the scene:
/// `bake` renders it from the geometry.
bool wx_scene_needs_bake(const wx_scene *scene);

/// For cameras given by <View> without map files in the scene, points their map
/// paths at what `bake` wrote in the output folder (<camera>_depth.exr, ...), and
/// checks those files exist (else: "run `weathering bake` first"); marks them
/// maps_in_output.
wx_result wx_use_baked_maps(wx_scene *scene, const wx_run_options *opts, wx_error *err);

/// Loads the maps of every input camera (scene order; `maps` has
/// scene->input_count entries) as the simulation reads them: depth, normal,
/// impact and, when the camera has one, its dirt map (from the channel
/// initialDirt when an earlier `simulate` wrote it, so a second run starts
/// where the first started). Errors name the camera and the file.
wx_result wx_load_simulation_maps(const wx_scene *scene, wx_maps *maps, wx_error *err);

/// Loads the maps of every input camera as the gather reads them: depth,
/// normal, and the dirt `simulate` left in the output folder
/// (<camera>_dirt.exr); without it the camera's scene dirt map, with a note.
/// A dirt map that holds only the baked initial dirt (never simulated) is used
/// with a note too.
wx_result wx_load_gather_maps(const wx_scene *scene, const wx_run_options *opts, wx_maps *maps,
                              wx_error *err);

/// Writes the --stats JSON atomically.
wx_result wx_write_stats(const char *path, const wx_run_options *opts, const wx_sim_stats *stats,
                         const wx_phase_times *times, wx_error *err);

#endif
