// big_alloc.c: large blocks marked for transparent huge pages (big_alloc.h).
#define _DEFAULT_SOURCE // madvise and MADV_HUGEPAGE (Linux)
#include "core/big_alloc.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#define HUGE_PAGE ((uintptr_t)2 << 20)

// Marks the 2 MiB pages that lie wholly inside [p, p + bytes). A refusal (no
// THP in the kernel, or THP "never") leaves the block as it was: a hint only.
static void advise_huge(void *p, size_t bytes)
{
#ifdef MADV_HUGEPAGE
    uintptr_t begin = ((uintptr_t)p + HUGE_PAGE - 1) & ~(HUGE_PAGE - 1);
    uintptr_t end = ((uintptr_t)p + bytes) & ~(HUGE_PAGE - 1);
    if (end > begin) {
        (void)madvise((void *)begin, end - begin, MADV_HUGEPAGE);
    }
#else
    (void)p;
    (void)bytes;
#endif
}

// A large block starts on a huge page (glibc takes the alignment from the
// mapping it makes for the block: address space, no memory), and its tail is
// rounded up to a whole huge page when that adds at most an eighth to it: a
// map of 1024 x 930 floats (3.6 MiB) is then two huge pages, where it would
// be one and 460 small ones. The memory a run holds grows by that eighth at
// most (the memory estimate's margin covers it).
static void *aligned_block(size_t bytes)
{
    size_t whole = (bytes + HUGE_PAGE - 1) & ~(size_t)(HUGE_PAGE - 1);
    size_t length = whole - bytes <= bytes / 8 ? whole : bytes;
    void *p = NULL;
    if (posix_memalign(&p, (size_t)HUGE_PAGE, length) != 0) {
        return NULL;
    }
    advise_huge(p, length);
    return p;
}

void *wx_big_malloc(size_t bytes)
{
    return bytes >= WX_BIG_ALLOC_MIN ? aligned_block(bytes) : malloc(bytes > 0 ? bytes : 1);
}

void *wx_big_calloc(size_t count, size_t size)
{
    if (size != 0 && count > SIZE_MAX / size) {
        return NULL;
    }
    // calloc's own zeroes: a block that large is a fresh mapping, whose pages
    // the kernel zeroes when they are first touched, so a block used sparsely
    // holds memory only where it is used. The hint covers its whole huge pages.
    size_t bytes = count * size;
    void *p = calloc(count > 0 ? count : 1, size > 0 ? size : 1);
    if (p != NULL && bytes >= WX_BIG_ALLOC_MIN) {
        advise_huge(p, bytes);
    }
    return p;
}

void wx_release_freed_memory(void)
{
#ifdef __GLIBC__
    (void)malloc_trim(0);
#endif
}
