// array.h: arrays that grow by doubling, the one growth loop of the program.
#ifndef WX_ARRAY_H
#define WX_ARRAY_H

#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>

/// Makes room for at least `needed` items of `item_size` bytes in *items, whose
/// allocation holds *capacity items: doubles the capacity (starting from
/// `first`) until it suffices. Returns false when out of memory; the array and
/// its capacity are then unchanged.
static inline bool wx_array_reserve(void **items, int64_t *capacity, int64_t needed,
                                    size_t item_size, int64_t first)
{
    if (needed <= *capacity) {
        return true;
    }
    int64_t grown_capacity = *capacity > 0 ? *capacity : first;
    while (grown_capacity < needed) {
        grown_capacity *= 2;
    }
    void *grown = realloc(*items, (size_t)grown_capacity * item_size);
    if (grown == NULL) {
        return false;
    }
    *items = grown;
    *capacity = grown_capacity;
    return true;
}

#endif
