// pilot.h: a small run that `info` flies before any real work, to say what
// share of a run's particles would leave the bounding box without hitting
// anything (issue 15), and what share would still fly at the end: the
// emitters thinned to about WX_PILOT_PARTICLES particles over all the
// iterations, the baked cameras rendered in memory at most WX_PILOT_SIDE texels
// a side, the same steps, iterations and physics, nothing written.
#ifndef WX_PILOT_H
#define WX_PILOT_H

#include <stdint.h>

#include "core/error.h"
#include "model/geometry.h"
#include "model/scene.h"
#include "pipeline/pipeline.h"

#define WX_PILOT_PARTICLES 20000
#define WX_PILOT_SIDE 256

/// What the pilot saw.
typedef struct wx_pilot_report {
    int64_t particles;           ///< flown
    int64_t collisions;
    int64_t escaped_without_hit; ///< left the bounding box without a hit
    int64_t alive;               ///< still flying at the end
    double seconds;
} wx_pilot_report;

/// Flies the pilot of `scene` (emitters and at least one input camera needed;
/// with none, the report is zero). `geometry` is what wx_geometry_load
/// imported (used up: its arrays are released as the bake uploads them); it
/// may be empty when no camera is baked.
wx_result wx_pilot_run(const wx_scene *scene, const wx_run_def *opts, wx_geometry *geometry,
                       wx_pilot_report *report, wx_error *err);

#endif
