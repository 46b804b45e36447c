// stats_json.h: the --stats file: the simulation's counters and dirt ledger, the
// seconds of each phase, the thread count and the seed, as JSON with the
// pinned keys of docs/design.md section 6.
#ifndef WX_STATS_JSON_H
#define WX_STATS_JSON_H

#include <stdint.h>

#include "core/error.h"
#include "model/stats.h"

/// Writes the --stats JSON atomically; `noise` (may be NULL or empty) adds the
/// object "noise", one entry per output smoothed adaptively, keyed by its file.
wx_result wx_write_stats(const char *path, const wx_sim_stats *stats, const wx_phase_times *times,
                         const wx_noise_report *noise, int threads, uint64_t seed, wx_error *err);

#endif
