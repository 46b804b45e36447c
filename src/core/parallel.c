// parallel.c: a pool of threads and the parallel-for over index ranges
// (parallel.h).
#include "core/parallel.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdlib.h>
#include <unistd.h>

int wx_cpu_count(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n >= 1 ? (int)n : 1;
}

typedef struct pool_worker {
    wx_pool *pool;
    int index;
    pthread_t thread;
} pool_worker;

struct wx_pool {
    int threads; ///< workers, the calling thread included
    pool_worker *workers;
    pthread_mutex_t lock;
    pthread_cond_t start, done;
    uint64_t generation; ///< one per wx_pool_for call
    int pending;         ///< worker threads still in the current call
    bool quit;
    // The current call.
    int64_t count, grain, ranges;
    atomic_int_fast64_t next; ///< the next range to claim
    wx_range_fn *fn;
    void *context;
};

// Claims ranges until none is left.
static void take_ranges(wx_pool *pool, int worker)
{
    for (;;) {
        int64_t r = atomic_fetch_add_explicit(&pool->next, 1, memory_order_relaxed);
        if (r >= pool->ranges) {
            return;
        }
        int64_t begin = r * pool->grain;
        int64_t end = pool->count - begin < pool->grain ? pool->count : begin + pool->grain;
        pool->fn(begin, end, worker, pool->context);
    }
}

static void *worker_main(void *arg)
{
    pool_worker *w = arg;
    wx_pool *pool = w->pool;
    uint64_t seen = 0;
    pthread_mutex_lock(&pool->lock);
    for (;;) {
        while (pool->generation == seen && !pool->quit) {
            pthread_cond_wait(&pool->start, &pool->lock);
        }
        if (pool->quit) {
            break;
        }
        seen = pool->generation;
        pthread_mutex_unlock(&pool->lock);
        take_ranges(pool, w->index);
        pthread_mutex_lock(&pool->lock);
        if (--pool->pending == 0) {
            pthread_cond_signal(&pool->done);
        }
    }
    pthread_mutex_unlock(&pool->lock);
    return NULL;
}

wx_result wx_pool_create(int threads, wx_pool **out, wx_error *err)
{
    *out = NULL;
    wx_pool *pool = calloc(1, sizeof *pool);
    int n = threads > 1 ? threads : 1;
    pool_worker *workers = pool != NULL ? calloc((size_t)n, sizeof *workers) : NULL;
    if (workers == NULL) {
        free(pool);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (threads)");
    }
    pool->workers = workers;
    pthread_mutex_init(&pool->lock, NULL);
    pthread_cond_init(&pool->start, NULL);
    pthread_cond_init(&pool->done, NULL);
    atomic_init(&pool->next, 0);
    pool->threads = 1;
    for (int t = 1; t < n; ++t) {
        workers[t].pool = pool;
        workers[t].index = t;
        if (pthread_create(&workers[t].thread, NULL, worker_main, &workers[t]) != 0) {
            break; // fewer threads: the others take more ranges
        }
        pool->threads = t + 1;
    }
    *out = pool;
    return WX_OK;
}

void wx_pool_destroy(wx_pool *pool)
{
    if (pool == NULL) {
        return;
    }
    pthread_mutex_lock(&pool->lock);
    pool->quit = true;
    pthread_cond_broadcast(&pool->start);
    pthread_mutex_unlock(&pool->lock);
    for (int t = 1; t < pool->threads; ++t) {
        pthread_join(pool->workers[t].thread, NULL);
    }
    pthread_mutex_destroy(&pool->lock);
    pthread_cond_destroy(&pool->start);
    pthread_cond_destroy(&pool->done);
    free(pool->workers);
    free(pool);
}

int wx_pool_threads(const wx_pool *pool)
{
    return pool != NULL ? pool->threads : 1;
}

void wx_pool_for(wx_pool *pool, int64_t count, int64_t grain, wx_range_fn *fn, void *context)
{
    if (count <= 0) {
        return;
    }
    grain = grain >= 1 ? grain : 1;
    int64_t ranges = (count + grain - 1) / grain;
    if (pool == NULL || pool->threads <= 1 || ranges == 1) {
        for (int64_t begin = 0; begin < count; begin += grain) {
            fn(begin, count - begin < grain ? count : begin + grain, 0, context);
        }
        return;
    }
    pool->count = count;
    pool->grain = grain;
    pool->ranges = ranges;
    pool->fn = fn;
    pool->context = context;
    atomic_store_explicit(&pool->next, 0, memory_order_relaxed);
    pthread_mutex_lock(&pool->lock);
    pool->pending = pool->threads - 1;
    pool->generation++;
    pthread_cond_broadcast(&pool->start);
    pthread_mutex_unlock(&pool->lock);
    take_ranges(pool, 0);
    pthread_mutex_lock(&pool->lock);
    while (pool->pending > 0) {
        pthread_cond_wait(&pool->done, &pool->lock);
    }
    pthread_mutex_unlock(&pool->lock);
}

void wx_parallel_for(int threads, int64_t count, int64_t grain, wx_range_fn *fn, void *context)
{
    wx_pool *pool = NULL;
    int64_t ranges = grain >= 1 ? (count + grain - 1) / grain : count;
    if (threads > 1 && ranges > 1) {
        // Out of memory: pool stays NULL and the loop runs serially.
        wx_pool_create(threads < ranges ? threads : (int)ranges, &pool, NULL);
    }
    wx_pool_for(pool, count, grain, fn, context);
    wx_pool_destroy(pool);
}
