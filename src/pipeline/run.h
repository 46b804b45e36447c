// run.h: the phases of a run (bake, simulate, gather) driven in one process, as
// the command line runs them: every check first, then the phases, each input
// read once.
#ifndef WX_RUN_H
#define WX_RUN_H

#include "core/error.h"
#include "model/scene.h"
#include "model/stats.h"
#include "pipeline/pipeline.h"

/// What a run did: the simulation's counters and the seconds of each phase.
typedef struct wx_run_report {
    wx_sim_stats stats;
    wx_phase_times times; ///< times.load: the caller's scene loading, plus the checks here
    /// The final gather's noise figures; the caller frees them
    /// (wx_noise_report_free), whatever the result.
    wx_noise_report noise;
} wx_run_report;

/// Runs the phases in `phases` in order, in one process; a phase that is not run
/// is read from what an earlier command left in the output folder. Everything
/// that can be refused is refused before any work: the geometry (when some
/// camera is baked), the memory estimate, the outputs and --stats
/// (wx_check_outputs). Each input file is read once: the maps the simulation
/// loads (and the dirt it leaves) are what the gather reads. A run in which
/// particles fly but none hits a surface ends with a warning. On failure the
/// output folder is removed again when this run made it and it is empty.
wx_result wx_run_phases(wx_scene *scene, const wx_run_def *opts, unsigned phases,
                        wx_run_report *report, wx_error *err);

#endif
