// points.c: the nearest point per pixel, in tile order (points.h).
#include "points.h"

#include <stdlib.h>
#include <string.h>

bool vw_points_begin(vw_point_filter *f, const float mvp[16], int width, int height,
                     size_t max_points)
{
    width = width > 1 ? width : 1;
    height = height > 1 ? height : 1;
    if (max_points > f->capacity) {
        vw_point_record *records = realloc(f->records, max_points * sizeof *records);
        if (records == NULL) {
            return false;
        }
        f->records = records;
        vw_point_record *sorted = realloc(f->sorted, max_points * sizeof *sorted);
        if (sorted == NULL) {
            return false;
        }
        f->sorted = sorted;
        f->capacity = max_points;
    }
    int tiles_x = (width + VW_TILE - 1) / VW_TILE, tiles_y = (height + VW_TILE - 1) / VW_TILE;
    size_t tiles = (size_t)tiles_x * (size_t)tiles_y;
    if (tiles > f->tile_capacity) {
        uint32_t *starts = realloc(f->tile_start, tiles * sizeof *starts);
        if (starts == NULL) {
            return false;
        }
        f->tile_start = starts;
        f->tile_capacity = tiles;
    }
    f->width = width;
    f->height = height;
    f->tiles_x = tiles_x;
    f->tiles_y = tiles_y;
    memcpy(f->mvp, mvp, sizeof f->mvp);
    memset(f->tile_start, 0, tiles * sizeof *f->tile_start);
    f->count = 0;
    return true;
}

static size_t tile_of(const vw_point_filter *f, uint32_t pixel)
{
    return (size_t)(pixel >> (16 + VW_TILE_SHIFT)) * (size_t)f->tiles_x +
           ((pixel & 0xFFFF) >> VW_TILE_SHIFT);
}

size_t vw_points_winners(vw_point_filter *f, float *out)
{
    size_t tiles = (size_t)f->tiles_x * (size_t)f->tiles_y;
    // Counts to starts, then a stable move of the records into their tiles.
    uint32_t at = 0;
    for (size_t t = 0; t < tiles; ++t) {
        uint32_t n = f->tile_start[t];
        f->tile_start[t] = at;
        at += n;
    }
    for (size_t k = 0; k < f->count; ++k) {
        const vw_point_record *r = &f->records[k];
        f->sorted[f->tile_start[tile_of(f, r->pixel)]++] = *r;
    }
    // The move left each start at the next tile's: tile t begins where t-1 ends.
    size_t n_out = 0;
    uint32_t begin = 0;
    for (size_t t = 0; t < tiles; ++t) {
        uint32_t end = f->tile_start[t];
        if (end == begin) {
            continue;
        }
        if (++f->stamp == 0) { // wrapped: forget every old stamp
            memset(f->tile_stamp, 0, sizeof f->tile_stamp);
            f->stamp = 1;
        }
        const uint32_t stamp = f->stamp;
        uint32_t lo = VW_TILE * VW_TILE, hi = 0; // the pixels used in this tile
        for (uint32_t k = begin; k < end; ++k) {
            const vw_point_record *r = &f->sorted[k];
            uint32_t local = (r->pixel & (VW_TILE - 1)) |
                             ((r->pixel >> 16) & (VW_TILE - 1)) << VW_TILE_SHIFT;
            if (f->tile_stamp[local] != stamp) {
                f->tile_stamp[local] = stamp;
                lo = local < lo ? local : lo;
                hi = local > hi ? local : hi;
            } else if (!(r->depth < f->tile_depth[local])) {
                continue;
            }
            f->tile_depth[local] = r->depth;
            f->tile_winner[local] = k;
        }
        for (uint32_t local = lo; local <= hi; ++local) {
            if (f->tile_stamp[local] == stamp) {
                memcpy(out + 4 * n_out++, f->sorted[f->tile_winner[local]].data, 4 * sizeof(float));
            }
        }
        begin = end;
    }
    return n_out;
}

void vw_points_free(vw_point_filter *f)
{
    free(f->records);
    free(f->sorted);
    free(f->tile_start);
    memset(f, 0, sizeof *f);
}
