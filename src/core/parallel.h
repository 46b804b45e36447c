// parallel.h: the one parallel primitive of the program (Box2D v3's
// b2ParallelFor): a deterministic parallel-for over index ranges.
//
// A pool keeps `threads - 1` worker threads asleep between calls; the calling
// thread is worker 0 and works too. wx_pool_for cuts [0, count) into ranges of
// `grain` items that the workers claim in turn from a shared counter, so a slow
// range never holds up the others. Results are deterministic as long as what a
// range computes does not depend on which worker runs it (each range writes its
// own part of the output); the caller merges in index order. A NULL pool, one
// thread, or one range runs everything on the calling thread (the serial
// fallback), and so does a pool whose threads could not be started.
#ifndef WX_PARALLEL_H
#define WX_PARALLEL_H

#include <stdint.h>

#include "core/error.h"

/// Number of online processors (at least 1): the default thread count.
int wx_cpu_count(void);

/// Work on items [begin, end) by worker `worker` (0: the calling thread).
typedef void wx_range_fn(int64_t begin, int64_t end, int worker, void *context);

typedef struct wx_pool wx_pool;

/// Starts a pool of `threads` workers (the caller counts as one; `threads` <= 1
/// gives a pool that runs serially). WX_FAIL when out of memory; a thread that
/// cannot start only makes the pool smaller.
wx_result wx_pool_create(int threads, wx_pool **out, wx_error *err);

/// Stops the threads and frees the pool (NULL is fine).
void wx_pool_destroy(wx_pool *pool);

/// Workers of the pool, the calling thread included (1 for NULL).
int wx_pool_threads(const wx_pool *pool);

/// Runs fn over [0, count) in ranges of `grain` (>= 1) items and returns when
/// every range is done. One call at a time per pool.
void wx_pool_for(wx_pool *pool, int64_t count, int64_t grain, wx_range_fn *fn, void *context);

/// wx_pool_for on a pool made for this one call (threads started and stopped).
void wx_parallel_for(int threads, int64_t count, int64_t grain, wx_range_fn *fn, void *context);

#endif
