// pipeline.h: what every phase of a run (bake, simulate, gather) shares: the
// options of the command line (--out, --seed, --threads, -q, --stats); the
// phases themselves as bits are model/naming.h's.
#ifndef WX_PIPELINE_H
#define WX_PIPELINE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "model/naming.h" // the phases as bits (WX_PHASE_*)
#include "model/scene.h"

/// Options shared by every phase (command line: --out, --seed, --threads, -q, --stats).
typedef struct wx_run_def {
    char out_dir[WX_PATH_MAX]; ///< the output folder; exists once wx_output_prepare ran
    uint64_t seed;             ///< the scene's seed unless --seed was given
    int threads;               ///< worker threads, >= 1 (default: all cores)
    bool quiet;                ///< -q: no progress bars, no notes on stderr
    const char *stats_path;    ///< --stats FILE.json, or NULL
    /// `run MESH`: the text of the scene generated in memory, written to the
    /// scene's path (OUT/scene.xml) once every check passed, or NULL.
    const char *scene_text;
} wx_run_def;

/// Default run options for a scene: out/<scene name>/ (the name made safe: see
/// wx_default_out_name), the scene's seed, all cores.
wx_run_def wx_default_run_def(const wx_scene *scene);

/// The default output folder's name for a scene name: the name with every
/// character but letters, digits, '_', '-' and '.' replaced by '_', leading dots
/// too, so that out/NAME always lies inside out/ ("..": "__"; "": "scene").
void wx_default_out_name(const char *scene_name, char *out, size_t cap);

#endif
