// stats.h: what a run counts and measures: the simulation's counters and dirt
// ledger, and the seconds of each phase (the pinned keys of --stats,
// docs/design.md section 6).
#ifndef WX_STATS_H
#define WX_STATS_H

#include <stdbool.h>
#include <stdint.h>

#include "core/error.h"
#include "core/limits.h"

/// The ledger of one substance (docs/design.md section 9): exact to rounding,
/// initial_surface + emitted + grown + transferred_in = final_surface +
/// in_flight + escaped + decayed + transferred_out.
typedef struct wx_substance_ledger {
    double initial_surface;
    double emitted;
    double grown;
    double transferred_in;
    double transferred_out;
    double decayed;
    double final_surface;
    double in_flight;
    double escaped;
} wx_substance_ledger;

/// Counters of a simulation (the pinned keys of --stats).
typedef struct wx_sim_stats {
    int64_t particles_emitted;
    /// A tile's run (<Tile>, docs/tiles.md): of the particles emitted, those that
    /// start in the tile itself (not in its halo), so that the tiles' counts add
    /// up to the whole scene's particles_emitted; `tiled` says whether to report it.
    bool tiled;
    int64_t tile_particles;
    int64_t particle_steps;
    int64_t collisions;
    int64_t absorbed;
    int64_t settled;
    int64_t escaped;
    int64_t escaped_without_hit; ///< of the emitters' particles, those that never hit
    int64_t alive;
    int64_t alive_without_hit; ///< of the emitters' particles still flying, those yet to hit
    /// Substance "dirt"'s ledger (docs/design.md section 6); zero when the
    /// scene declares substances without "dirt".
    double dirt_initial_surface;
    double dirt_emitted;
    double dirt_final_surface;
    double dirt_in_flight;
    double dirt_escaped;
    /// Every substance's ledger, in the scene's order, and the iterations done
    /// (each completed by its ageing rules).
    int substance_count;
    char substance_names[WX_MAX_SUBSTANCES][WX_SUBSTANCE_NAME_MAX + 1];
    int dirt_index; ///< substance "dirt", or -1 (the --stats file then has no "dirt")
    wx_substance_ledger substance[WX_MAX_SUBSTANCES];
    int64_t iterations;
} wx_sim_stats;

/// Wall-clock seconds of the parts of a phase: reading its inputs, setting up
/// (the simulation's collider and dirt maps), computing (the steps, the
/// gather's passes) and writing its files.
typedef struct wx_phase_detail {
    double read;
    double setup;
    double compute;
    double write;
} wx_phase_detail;

/// How noisy an output of the adaptive smoothing stays where its radius
/// reached maxRadius with fewer impacts than its noise needs: the figures of
/// the gather's note (docs/mask.md, "Notes it prints"), for --stats.
typedef struct wx_noise_figures {
    char file[WX_OUTPUT_NAME_MAX]; ///< the mask's or the TextureMap's file
    double aim;                    ///< `noise`
    double target_hits;            ///< K: the impacts within a radius the aim needs
    /// The texels smoothed (a TextureMap's: every input camera's own, the
    /// first substance's) and those capped.
    int64_t surface_texels;
    int64_t capped_texels;
    double capped_noise; ///< the capped texels' median noise; 0 when none is capped
} wx_noise_figures;

/// The final gather's wx_noise_figures, one per output smoothed adaptively, in
/// the order written (the mask first).
typedef struct wx_noise_report {
    int count;
    wx_noise_figures *items;
} wx_noise_report;

/// Appends `figures` to `report` (NULL: nothing to do). WX_FAIL when out of
/// memory.
wx_result wx_noise_report_add(wx_noise_report *report, const wx_noise_figures *figures,
                              wx_error *err);

/// Frees the report's figures and empties it.
void wx_noise_report_free(wx_noise_report *report);

/// Wall-clock seconds per phase.
typedef struct wx_phase_times {
    double load;
    double bake;
    double simulate;
    double gather;
    double total;
    wx_phase_detail simulate_detail;
    wx_phase_detail gather_detail;
} wx_phase_times;

#endif
