// points.h: picks, for each pixel, the nearest of many one-pixel points, and
// lists the winners in screen-tile order.
//
// With a depth test, a pixel shows only the nearest of the one-pixel points
// that fall in it; the others cost llvmpipe (a software rasteriser) as much as
// a visible one: vertex shading, setup and binning per point. 196k depth samples
// of the thesis scene cover some 11k pixels, and particles pile up too. So the
// viewer projects the points on the CPU, keeps the nearest per pixel and uploads
// only those. Listed tile by tile (llvmpipe rasterises 64x64-pixel tiles), the
// points' setup data is read back in the order it was written; in the
// simulation's order it missed the cache at every point.
//
// Every pass touches memory in order: points are projected and appended with
// their vertex data (four floats), moved into their tiles, and each tile is
// resolved in a small depth buffer of its own.
#ifndef VW_POINTS_H
#define VW_POINTS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

enum { VW_TILE_SHIFT = 6, VW_TILE = 1 << VW_TILE_SHIFT };

/// An offered point: where it falls and the four floats to draw it with.
typedef struct vw_point_record {
    uint32_t pixel; ///< x | y << 16, pixels from the bottom-left corner
    float depth;    ///< NDC z
    float data[4];
} vw_point_record;

typedef struct vw_point_filter {
    int width, height;          ///< pixels
    int tiles_x, tiles_y;
    float mvp[16];
    size_t count, capacity;
    vw_point_record *records;   ///< offered points on the screen, in offer order
    vw_point_record *sorted;    ///< the same, tile by tile
    uint32_t *tile_start;       ///< per tile: points, then where the tile starts
    size_t tile_capacity;
    // One tile's depth buffer, with a stamp per pixel instead of clearing.
    float tile_depth[VW_TILE * VW_TILE];
    uint32_t tile_winner[VW_TILE * VW_TILE];
    uint32_t tile_stamp[VW_TILE * VW_TILE];
    uint32_t stamp;
} vw_point_filter;

/// Starts a pass over a screen of width x height pixels seen through `mvp`
/// (column-major, as for GL), for at most `max_points` offers. False when out
/// of memory.
bool vw_points_begin(vw_point_filter *f, const float mvp[16], int width, int height,
                     size_t max_points);

/// Offers a point at world position (x, y, z) with four floats of vertex data;
/// points outside the view volume are dropped.
static inline void vw_points_offer(vw_point_filter *f, float x, float y, float z, float d0,
                                   float d1, float d2, float d3)
{
    const float *m = f->mvp;
    float cw = m[3] * x + m[7] * y + m[11] * z + m[15];
    if (!(cw > 0.0f) || f->count == f->capacity) {
        return;
    }
    float inv = 1.0f / cw;
    float nx = (m[0] * x + m[4] * y + m[8] * z + m[12]) * inv;
    float ny = (m[1] * x + m[5] * y + m[9] * z + m[13]) * inv;
    float nz = (m[2] * x + m[6] * y + m[10] * z + m[14]) * inv;
    if (!(nx >= -1.0f && nx < 1.0f && ny >= -1.0f && ny < 1.0f && nz >= -1.0f && nz <= 1.0f)) {
        return;
    }
    int px = (int)((nx + 1.0f) * 0.5f * (float)f->width);
    int py = (int)((ny + 1.0f) * 0.5f * (float)f->height);
    px = px < f->width ? px : f->width - 1;
    py = py < f->height ? py : f->height - 1;
    vw_point_record *r = &f->records[f->count++];
    r->pixel = (uint32_t)px | (uint32_t)py << 16;
    r->depth = nz;
    r->data[0] = d0;
    r->data[1] = d1;
    r->data[2] = d2;
    r->data[3] = d3;
    f->tile_start[(py >> VW_TILE_SHIFT) * f->tiles_x + (px >> VW_TILE_SHIFT)]++;
}

/// Writes the four floats of every pixel's nearest point into `out` (room for
/// one point per pixel), tile by tile, rows within a tile, and returns how
/// many. On equal depths the point offered first wins, as with GL_LESS.
size_t vw_points_winners(vw_point_filter *f, float *out);

void vw_points_free(vw_point_filter *f);

#endif
