// dist.h: the ranks of a run spread over processes with MPI (docs/scale-out.md,
// docs/design.md section 16): which rank this process is, how many there are,
// and the few collective operations the simulation's exchange needs.
//
// The program built by `make mpi` (-DWX_MPI) runs them with Open MPI; the
// normal build compiles the same functions without MPI as one rank of one
// (rank 0 of 1: a gather copies, a broadcast returns its argument), so that
// no other file needs to know which build it is in, and the normal build has
// no MPI dependency. Only core/dist.c includes the MPI header (tests/test_layers.c).
//
// Every collective must be called by every rank, in the same order: the
// callers (the simulation's step, the run's hand-over after the bake) are
// written so that all ranks take the same path.
#ifndef WX_DIST_H
#define WX_DIST_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"

/// Starts MPI (MPI_Init) in the MPI build; nothing otherwise. Call once, first
/// thing in main. Returns false when MPI could not start.
bool wx_dist_init(int *argc, char ***argv);

/// Stops MPI (MPI_Finalize) in the MPI build, when it was started.
void wx_dist_finalize(void);

/// Ends every rank of the job with `status` (MPI_Abort) when there is more
/// than one rank; returns `status` otherwise. A rank that fails alone calls it,
/// so that no other rank waits for it in a collective.
int wx_dist_abort(int status);

/// This process's rank (0 ... size - 1) and the number of ranks (1 without MPI).
int wx_dist_rank(void);
int wx_dist_size(void);

/// The ranks on this machine (1 without MPI): how many share its cores.
int wx_dist_local_size(void);

/// Rank 0's `value`, on every rank.
int wx_dist_broadcast_int(int value);

/// The hand-over of a run from rank 0 to the others (docs/scale-out.md): while
/// rank 0 checks the scene and bakes, the other ranks wait (wx_dist_wait);
/// rank 0 then releases them once (wx_dist_release) with WX_DIST_JOIN (join
/// the simulation) or, when it ends without one, its exit status (stop).
/// Later releases do nothing; one rank alone releases no one.
enum { WX_DIST_JOIN = -1 };
void wx_dist_release(int value);

/// On rank 0: the value of its release, or 0 while there was none.
int wx_dist_released(void);

/// On the other ranks: rank 0's release (WX_DIST_JOIN or an exit status).
int wx_dist_wait(void);

/// Every rank's `count` numbers `mine`, into all[rank * count + k] on every rank.
void wx_dist_allgather_i64(const int64_t *mine, int count, int64_t *all);

/// Every rank's counts[rank] items of `size` bytes, one rank after the other
/// from all[0], on every rank. `mine` NULL: this rank's items are already in
/// place in `all` (after those of the ranks before it). WX_FAIL (the message in
/// err) when a part of more than INT_MAX items cannot be sent in one call.
wx_result wx_dist_allgatherv(const void *mine, void *all, const int64_t *counts, size_t size,
                             wx_error *err);

#endif
