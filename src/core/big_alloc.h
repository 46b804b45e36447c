// big_alloc.h: the large arrays a run fills whole (maps' planes, dirt maps,
// the gather's and the bake's scratch), asked of the kernel in huge pages.
#ifndef WX_BIG_ALLOC_H
#define WX_BIG_ALLOC_H

#include <stddef.h>

/// malloc(bytes) for a block its user fills whole: aligned on 2 MiB and marked
/// for the kernel's transparent huge pages (madvise MADV_HUGEPAGE; Debian's
/// default THP mode is "madvise"), so that the first touch of each 2 MiB maps
/// it at once instead of in 512 faults of 4 KiB, each of which costs a
/// virtual machine's exit here. Blocks under WX_BIG_ALLOC_MIN are plain
/// malloc. Freed with free(); NULL when out of memory. The hint changes no
/// value, only how the memory is mapped (docs/performance.md, "Page faults").
void *wx_big_malloc(size_t bytes);

/// calloc(count, size) with the hint over the whole huge pages inside the
/// block (not aligned, nor written: calloc's fresh mapping holds memory only
/// where it is touched, so a block used sparsely stays small). NULL when out
/// of memory or when count * size overflows.
void *wx_big_calloc(size_t count, size_t size);

/// Gives the pages of freed heap memory back to the kernel (glibc's
/// malloc_trim; nothing elsewhere). glibc keeps what a phase freed in its
/// heap, resident, below what is still allocated: after the bake that is the
/// renderer's scene and the smooth surfaces, 110 to 130 MiB on the teapot,
/// Spot and the bunny, which the simulation and the gather would otherwise
/// sit on (docs/reliability.md, "What the renderer keeps").
void wx_release_freed_memory(void);

/// Below this many bytes (one huge page) a block is plain malloc.
#define WX_BIG_ALLOC_MIN ((size_t)2 << 20)

#endif
