// mesh.h: a triangle mesh in world space as flat arrays: what
// io/mesh_import.c makes of a mesh file and raster/bake.c uploads. Positions
// are stored relative to `origin` (the centre of the bounds), so that float
// keeps its precision for models far from the world origin. Every vertex
// belongs to triangles of one material only, so a per-triangle material is also
// a per-vertex one.
#ifndef WX_MESH_H
#define WX_MESH_H

#include <stdbool.h>
#include <stdint.h>

#include "core/error.h"
#include "core/limits.h"


/// UV channels a mesh may carry (Assimp's AI_MAX_NUMBER_OF_TEXTURECOORDS).
#define WX_MESH_MAX_UV_CHANNELS 8

/// A triangle mesh in world space, as flat arrays.
typedef struct wx_mesh_data {
    int64_t vertex_count;
    int64_t triangle_count;
    double origin[3];      ///< world position of the local origin of `positions`
    float *positions;      ///< 3 per vertex: world position minus origin
    float *normals;        ///< 3 per vertex: world-space unit normal (0 when degenerate)
    float *colors;         ///< 4 per vertex (RGBA, first colour set), NULL when the file has none
    /// 2 per vertex (u, v) per UV channel asked of the import (mesh_import.h),
    /// NULL for the others.
    float *uvs[WX_MESH_MAX_UV_CHANNELS];
    uint32_t *indices;     ///< 3 per triangle
    uint16_t *materials;   ///< 1 per triangle: index into material_names
    int material_count;    ///< distinct material names used by triangles, in file order
    char (*material_names)[WX_MATERIAL_NAME_MAX];
    bool *material_colored; ///< per material: all its vertices carry a colour
    double bounds_min[3];  ///< world-space bounds of the vertices
    double bounds_max[3];
} wx_mesh_data;

/// Frees the vertex and triangle arrays only (once uploaded), keeping counts,
/// material names and bounds.
void wx_mesh_data_release_arrays(wx_mesh_data *mesh);

/// Frees everything; the struct is zeroed.
void wx_mesh_data_free(wx_mesh_data *mesh);

#endif
