// outputs.h: the output folder rules of docs/design.md section 6: the names a
// run writes there, the checks that refuse a run before any work (an output
// onto an input or a non-regular file, a bad --stats), the folder's
// preparation (and the removal of killed runs' temporaries) and its removal
// when a failed run leaves it empty.
#ifndef WX_OUTPUTS_H
#define WX_OUTPUTS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "core/error.h"
#include "core/limits.h"
#include "model/scene.h"
#include "pipeline/pipeline.h"

/// The plain names of the files a run writes into its output folder, each
/// once, with a hash set of them (a sequence may hold 100 000 frames).
typedef struct wx_output_names {
    int count;
    char (*names)[WX_OUTPUT_NAME_MAX];
    int64_t capacity;  ///< names allocated
    int *slots;        ///< open addressing: index + 1 of a name, 0 = empty
    int64_t slot_count; ///< a power of two, at least twice count
} wx_output_names;

/// What a path that is not a regular file is, for messages, from its
/// st_mode (lstat's: a link is "a symbolic link"): "a folder", "a FIFO"...
const char *wx_file_kind(unsigned mode);

/// Lists every file that the phases in `phases` write for `scene`: the maps
/// `bake` writes (<camera>_depth.exr ... for each <View> camera without map
/// files), the dirt map `simulate` writes for each input camera
/// (<camera>_dirt.exr), the mask and its preview. WX_FAIL when out of memory.
wx_result wx_output_names_list(const wx_scene *scene, unsigned phases, wx_output_names *out,
                               wx_error *err);

/// Frees the list; the struct is zeroed.
void wx_output_names_free(wx_output_names *names);

/// True when `name` is one of the list's names (constant time).
bool wx_output_names_has(const wx_output_names *names, const char *name);

/// Checks made before any work or any folder: no file the phases will write
/// is an input of the scene (the scene, a map or a mesh it names) or an
/// existing non-regular file (a folder, a FIFO, a symbolic link), and the
/// --stats file, when given, is neither an input nor one of the run's outputs
/// nor an existing non-regular file, and lies in a folder that exists (or in
/// the output folder). WX_BAD_INPUT with the path and the reason.
wx_result wx_check_outputs(const wx_scene *scene, const wx_run_def *opts, unsigned phases,
                           wx_error *err);

/// Creates the output folder (and its parents), checks it is a folder, and
/// removes the temporaries that killed runs of this program left there (only
/// ".NAME.tmpPID" where NAME is one of the scene's output names or the --stats
/// file's). `created` (may be NULL) gets the topmost folder this call made, or
/// "" when the folder existed.
wx_result wx_output_prepare(const wx_scene *scene, const wx_run_def *opts,
                            char created[WX_PATH_MAX], wx_error *err);

/// `run MESH`: writes the generated scene (opts->scene_text) to the scene's
/// path in the output folder; nothing when there is none. wx_check_outputs
/// has made sure it replaces no file but one an earlier `run MESH` generated.
wx_result wx_output_write_scene(const wx_scene *scene, const wx_run_def *opts, wx_error *err);

/// After a failed run: removes the generated scene written by
/// wx_output_write_scene when the run made the output folder (`created` not
/// empty) and the scene is the only file in it, so that the folder goes too.
void wx_output_remove_scene(const wx_scene *scene, const wx_run_def *opts, const char *created);

/// mkdir -p: creates every missing folder of `path`; `created` gets the
/// topmost one made ("" when the folder existed). WX_BAD_INPUT when `path`
/// exists and is not a folder, WX_FAIL when a folder cannot be made.
wx_result wx_make_folders(const char *path, char created[WX_PATH_MAX], wx_error *err);

/// After a failed run: removes the output folder and the parents up to
/// `created` (what wx_output_prepare made) when they are empty.
void wx_output_remove_empty(const char *out_dir, const char *created);

/// Joins the output folder and a plain file name into `path`. Fails (WX_BAD_INPUT)
/// when the result would be one of the scene's input files (a map or a mesh the
/// scene names, the scene itself): inputs are never overwritten. Maps this
/// program baked into the output folder (maps_in_output) are not inputs.
wx_result wx_output_path(const wx_scene *scene, const wx_run_def *opts, const char *name,
                         char path[WX_PATH_MAX], wx_error *err);

/// One output's line in the summary of a run, on `out`: its name, its size in
/// MB and, when it reads as an EXR, its size in texels and its channels.
/// Nothing when opts->out_dir holds no file `name`.
void wx_output_describe(FILE *out, const wx_run_def *opts, const char *name);

/// True when some camera is given by <View> without map files in the scene:
/// `bake` renders it from the geometry.
bool wx_scene_needs_bake(const wx_scene *scene);

/// For cameras given by <View> without map files in the scene, points their map
/// paths at what `bake` wrote in the output folder (<camera>_depth.exr, ...), and
/// checks those files exist (else: "run `weathering bake` first"); marks them
/// maps_in_output.
wx_result wx_use_baked_maps(wx_scene *scene, const wx_run_def *opts, wx_error *err);

#endif
