// mesh.h: triangle meshes imported with Assimp's C API (OBJ, PLY, glTF, FBX,
// STL, ...) and flattened into the arrays the bake uploads to the GPU.
//
// The import triangulates, generates smooth normals only where the file has
// none (smoothing across edges sharper than WX_MESH_SMOOTHING_ANGLE_DEG is not
// done, so a box keeps flat faces), joins identical vertices and applies the
// node transforms. The aiScene is released as soon as the arrays are built.
// Assimp reads through our own file system: regular files only (a FIFO, a
// device or a folder is refused, never waited on), and besides the mesh file
// only files inside the mesh's folder (after realpath), so an OBJ's mtllib or a
// glTF buffer URI cannot reach elsewhere. A referenced file that is not there
// is no refusal: Assimp does without it, as before (an OBJ without its .mtl).
// Positions come out in metres where the file states a unit Assimp leaves to
// us: FBX's UnitScaleFactor (centimetres per file unit). Collada's <unit> and
// 3DS's master scale are applied by Assimp; glTF is metres; OBJ, PLY and STL
// have no unit and are taken as metres.
// Positions are stored relative to `origin` (the centre of the bounds), so that
// float keeps its precision for models far from the world origin. Every vertex
// belongs to triangles of one material only (each Assimp mesh has one material
// and its vertices are copied per instance), so a per-triangle material is also
// a per-vertex one.
#ifndef WX_MESH_H
#define WX_MESH_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"

#define WX_MATERIAL_NAME_MAX 128
/// Largest angle between face normals that generated normals smooth across.
#define WX_MESH_SMOOTHING_ANGLE_DEG 60.0f
/// Most distinct material names one mesh file may use (per-triangle index is 16 bits).
#define WX_MESH_MAX_MATERIALS 65535

/// A triangle mesh in world space, as flat arrays.
typedef struct wx_mesh_data {
    int64_t vertex_count;
    int64_t triangle_count;
    double origin[3];      ///< world position of the local origin of `positions`
    float *positions;      ///< 3 per vertex: world position minus origin
    float *normals;        ///< 3 per vertex: world-space unit normal (0 when degenerate)
    float *colors;         ///< 4 per vertex (RGBA, first colour set), NULL when the file has none
    uint32_t *indices;     ///< 3 per triangle
    uint16_t *materials;   ///< 1 per triangle: index into material_names
    int material_count;    ///< distinct material names used by triangles, in file order
    char (*material_names)[WX_MATERIAL_NAME_MAX];
    bool *material_colored; ///< per material: all its vertices carry a colour
    double bounds_min[3];  ///< world-space bounds of the vertices
    double bounds_max[3];
} wx_mesh_data;

/// Imports a mesh file. WX_BAD_INPUT, with a message naming the file, when it
/// is missing ("not found"), not a regular file, unreadable or unsupported
/// (Assimp's reason), when it refers to a file that is not a regular file or
/// lies outside its folder ("refers to 'x.mtl', which is not a regular file (a
/// FIFO)", "refers to '../a.bin', outside the mesh's folder"), when a vertex
/// position, a vertex colour or a normal given in the file is not a finite
/// number, or when an FBX unit is not positive. Normals Assimp generates for
/// triangles too large for float stay 0. WX_FAIL when out of memory, inside
/// Assimp (std::bad_alloc) too. A file without triangles imports with
/// triangle_count 0. On failure `out` is left empty (safe to free).
wx_result wx_mesh_import(const char *path, wx_mesh_data *out, wx_error *err);

/// Frees the vertex and triangle arrays only (once uploaded), keeping counts,
/// material names and bounds.
void wx_mesh_data_release_arrays(wx_mesh_data *mesh);

/// Frees everything; the struct is zeroed.
void wx_mesh_data_free(wx_mesh_data *mesh);

#endif
