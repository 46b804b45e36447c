// dist.c: the ranks of a distributed run (dist.h): with -DWX_MPI (`make mpi`)
// the calls of Open MPI, otherwise one rank of one. The only file that
// includes <mpi.h>.
#include "core/dist.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>

#ifdef WX_MPI

#include <mpi.h>
#include <time.h>

static bool started;    // MPI_Init ran here (and MPI_Finalize is still to run)
static int rank_of = 0; // this process's rank
static int size_of = 1; // ranks in MPI_COMM_WORLD
static int local_of = 1;

// Waits for a non-blocking operation without holding a core. Open MPI's
// blocking calls spin: a rank waiting while rank 0 bakes, writes a frame or
// gathers (seconds) would take a core from it, and on a machine shared with
// other work every spinning rank slows the one that is behind. So: a short
// spin (a step's exchange between ranks that are level ends there), then
// sleeps growing to a millisecond, testing (which also moves the operation
// on) between them.
static void wait_for(MPI_Request *request)
{
    long pause_ns = 0;
    for (int spins = 0;; ++spins) {
        int done = 0;
        MPI_Test(request, &done, MPI_STATUS_IGNORE);
        if (done) {
            return;
        }
        if (spins < 2000) {
            continue;
        }
        pause_ns = pause_ns == 0 ? 20000 : pause_ns >= 500000 ? 1000000 : 2 * pause_ns;
        struct timespec pause = { 0, pause_ns };
        nanosleep(&pause, NULL);
    }
}

bool wx_dist_init(int *argc, char ***argv)
{
    // Only the calling thread of each rank calls MPI (the simulation's pool
    // threads never do): FUNNELED is all it needs.
    int provided = 0;
    if (MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) {
        return false;
    }
    started = true;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_of);
    MPI_Comm_size(MPI_COMM_WORLD, &size_of);
    MPI_Comm local;
    if (MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &local) ==
        MPI_SUCCESS) {
        MPI_Comm_size(local, &local_of);
        MPI_Comm_free(&local);
    }
    return true;
}

void wx_dist_finalize(void)
{
    if (started) {
        started = false;
        // MPI_Finalize waits for every rank, spinning: the other ranks, done
        // with their share, wait here asleep while rank 0 gathers and writes.
        if (size_of > 1) {
            MPI_Request request;
            MPI_Ibarrier(MPI_COMM_WORLD, &request);
            wait_for(&request);
        }
        MPI_Finalize();
    }
}

int wx_dist_abort(int status)
{
    if (started && size_of > 1) {
        MPI_Abort(MPI_COMM_WORLD, status);
    }
    return status;
}

int wx_dist_rank(void)
{
    return rank_of;
}

int wx_dist_size(void)
{
    return size_of;
}

int wx_dist_local_size(void)
{
    return local_of;
}

int wx_dist_broadcast_int(int value)
{
    if (size_of > 1) {
        MPI_Request request;
        MPI_Ibcast(&value, 1, MPI_INT, 0, MPI_COMM_WORLD, &request);
        wait_for(&request);
    }
    return value;
}

void wx_dist_allgather_i64(const int64_t *mine, int count, int64_t *all)
{
    if (size_of > 1) {
        MPI_Request request;
        MPI_Iallgather(mine, count, MPI_INT64_T, all, count, MPI_INT64_T, MPI_COMM_WORLD, &request);
        wait_for(&request);
    } else {
        memmove(all, mine, (size_t)count * sizeof *all);
    }
}

wx_result wx_dist_allgatherv(const void *mine, void *all, const int64_t *counts, size_t size,
                             wx_error *err)
{
    if (size_of == 1) {
        if (mine != NULL && counts[0] > 0) {
            memmove(all, mine, (size_t)counts[0] * size);
        }
        return WX_OK;
    }
    // Counts and offsets are ints in MPI 3: in items of `size` bytes (one
    // contiguous type), the whole must stay under INT_MAX items.
    int *n = malloc(2 * (size_t)size_of * sizeof *n);
    if (n == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (rank exchange)");
    }
    int *offset = n + size_of;
    int64_t total = 0;
    for (int r = 0; r < size_of; ++r) {
        if (counts[r] < 0 || total + counts[r] > INT_MAX) {
            free(n);
            return wx_fail(err, WX_CAUSE_TOO_MANY,
                           "the ranks' exchange of one step holds more than %d items", INT_MAX);
        }
        n[r] = (int)counts[r];
        offset[r] = (int)total;
        total += counts[r];
    }
    MPI_Datatype item;
    MPI_Type_contiguous((int)size, MPI_BYTE, &item);
    MPI_Type_commit(&item);
    MPI_Request request;
    MPI_Iallgatherv(mine != NULL ? mine : MPI_IN_PLACE, n[rank_of], item, all, n, offset, item,
                    MPI_COMM_WORLD, &request);
    wait_for(&request);
    MPI_Type_free(&item);
    free(n);
    return WX_OK;
}

#else // one rank of one: the normal build

bool wx_dist_init(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    return true;
}

void wx_dist_finalize(void)
{
}

int wx_dist_abort(int status)
{
    return status;
}

int wx_dist_rank(void)
{
    return 0;
}

int wx_dist_size(void)
{
    return 1;
}

int wx_dist_local_size(void)
{
    return 1;
}

int wx_dist_broadcast_int(int value)
{
    return value;
}

void wx_dist_allgather_i64(const int64_t *mine, int count, int64_t *all)
{
    memmove(all, mine, (size_t)count * sizeof *all);
}

wx_result wx_dist_allgatherv(const void *mine, void *all, const int64_t *counts, size_t size,
                             wx_error *err)
{
    (void)err;
    if (mine != NULL && counts[0] > 0) {
        memmove(all, mine, (size_t)counts[0] * size);
    }
    return WX_OK;
}

#endif

// --- the hand-over (either build: with one rank nobody waits) ---------------------

static bool released;
static int released_value;

void wx_dist_release(int value)
{
    if (!released) {
        released = true;
        released_value = value;
        wx_dist_broadcast_int(value);
    }
}

int wx_dist_released(void)
{
    return released ? released_value : 0;
}

int wx_dist_wait(void)
{
    return wx_dist_broadcast_int(0);
}
