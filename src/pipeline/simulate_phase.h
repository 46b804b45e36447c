// simulate_phase.h: the `simulate` phase: every input camera's maps read once,
// the simulation run on them for the scene's steps, and a dirt map per input
// camera written into the output folder (<camera>_dirt.exr).
#ifndef WX_SIMULATE_PHASE_H
#define WX_SIMULATE_PHASE_H

#include "core/error.h"
#include "model/maps.h"
#include "model/scene.h"
#include "model/stats.h"
#include "pipeline/pipeline.h"
#include "sim/simulate.h"

struct wx_textures;     // pipeline/texture_phase.h
struct wx_mask_context; // pipeline/masks_phase.h

/// Writes <camera>_dirt.exr for every input camera into the output folder: R
/// the simulated dirt, G deposit and B erosion as in the input dirt map (the
/// camera's `maps`, those the simulation ran on), initialDirt the dirt it
/// started from, and that map's header attributes (WTCMatrix, CTWMatrix and
/// cameraName set from the camera when it has none).
wx_result wx_write_dirt_maps(const wx_scene *scene, const wx_run_def *opts, const wx_sim *sim,
                             const wx_maps *maps, wx_error *err);

/// The `gather` phase from the simulation's state now, without files in between:
/// the mask (and its preview) that wx_gather_scene writes after
/// wx_write_dirt_maps wrote this state, the same bytes. `maps` are the input
/// cameras' maps the simulation runs on (one per input camera, scene order):
/// their depth and normal are borrowed, the dirt planes made from `sim`; the
/// output camera's maps are read. The mask only, as wx_gather_scene (the
/// viewer's G).
wx_result wx_gather_simulation(const wx_scene *scene, const wx_run_def *opts, const wx_sim *sim,
                               const wx_maps *maps, wx_error *err);

/// The `simulate` phase on maps already in memory (one per input camera, scene
/// order, as wx_load_simulation_maps reads them): runs scene->steps steps per
/// iteration and writes opts->out_dir/<camera>_dirt.exr for each input camera.
/// Frames of image sequences (`every`) write the mask and the TextureMaps of
/// `textures` (may be NULL), with the derived masks' context `masks` kept over
/// the frames (may be NULL: one per frame; gather_phase.h). Fills `stats` and
/// the setup, compute and write times of `detail` (either may be NULL), and
/// leaves in each maps[c].dirt the simulated dirt as written (impact, deposit
/// and erosion released): what the gather reads next.
wx_result wx_simulate_maps(const wx_scene *scene, const wx_run_def *opts, wx_maps *maps,
                           const wx_maps *out_maps, const struct wx_textures *textures,
                           struct wx_mask_context *masks, wx_sim_stats *stats,
                           wx_phase_detail *detail, wx_error *err);

/// The `simulate` phase: loads every input camera's maps from the scene's
/// paths, runs scene->steps steps (progress bar unless opts->quiet), writes
/// opts->out_dir/<camera>_dirt.exr for each input camera and fills `stats`.
wx_result wx_simulate_scene(const wx_scene *scene, const wx_run_def *opts,
                            wx_sim_stats *stats, wx_error *err);

/// The simulation of a rank other than 0 in an MPI run (docs/scale-out.md),
/// once rank 0 has released it (core/dist.h): reads the maps rank 0's run
/// reads (the scene's, and those it baked into opts->out_dir), creates the same
/// simulation and steps it with rank 0's, each rank its share of the particles.
/// Writes nothing: rank 0 writes the outputs.
wx_result wx_simulate_follow(wx_scene *scene, const wx_run_def *opts, wx_error *err);

#endif
