// mesh_postprocess.h: what the mesh import does to each aiMesh after Assimp
// has read it: normals and shared vertices, in time linear in the triangles
// (mesh_postprocess.c says how). Used by io/mesh_import.c only; it names
// Assimp's structures without including Assimp.
#ifndef WX_MESH_POSTPROCESS_H
#define WX_MESH_POSTPROCESS_H

#include <stdbool.h>
#include <stdint.h>

struct aiFace;
struct aiMesh;

/// What one aiMesh becomes: its triangles' corners numbered by joined vertex.
typedef struct wx_mesh_prep {
    bool done;
    uint32_t triangles;
    uint32_t vertices; ///< joined vertices
    uint32_t *corner;  ///< 3 per triangle: the joined vertex of each corner
    uint32_t *source;  ///< per joined vertex: the aiMesh vertex it takes its attributes from
    float *normal;     ///< 3 per joined vertex, in the mesh's own space (0 when degenerate)
} wx_mesh_prep;

/// True when face f is a triangle whose corners index the mesh's vertices.
bool wx_mesh_is_triangle(const struct aiFace *f, unsigned vertex_count);

/// Numbers the corners of `mesh`'s triangles by joined vertex: their normals
/// (the file's, or smoothed within WX_MESH_SMOOTHING_ANGLE_DEG where it has
/// none) and the corners that share every attribute (the UV channels of
/// `uv_channels`) joined. False when out of memory; a mesh of more corners than
/// 32 bits hold is reported through *too_many.
bool wx_mesh_prepare(const struct aiMesh *mesh, unsigned uv_channels, wx_mesh_prep *out,
                     bool *too_many);

/// Frees what wx_mesh_prepare made and empties *p.
void wx_mesh_prep_free(wx_mesh_prep *p);

#endif
