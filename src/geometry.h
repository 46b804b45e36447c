// geometry.h: the scene's <Geometry> imported and matched to its <Surface>s:
// what `bake` draws, what `info` reports, and what both refuse before any work
// (a material that no <Surface> matches, vertex colours a <Surface> asks for
// and the mesh lacks).
#ifndef WX_GEOMETRY_H
#define WX_GEOMETRY_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "mesh.h"
#include "scene.h"

/// One <Mesh> of the scene, imported.
typedef struct wx_geometry_mesh {
    wx_mesh_data data;  ///< the arrays may be released once drawn (wx_mesh_data_release_arrays)
    int *surface;       ///< per material of `data`: index into the <Mesh>'s surfaces
} wx_geometry_mesh;

/// Every <Mesh> of a scene, in scene order.
typedef struct wx_geometry {
    int count;
    wx_geometry_mesh *meshes;
    int64_t triangles;  ///< all meshes
    int64_t vertices;
    int64_t file_bytes; ///< sizes of the mesh files
    bool has_dirt;      ///< some matched surface starts with dirt (a density or vertex colours)
    double import_s;    ///< wall-clock seconds of the imports
} wx_geometry;

/// Imports every mesh of `scene` and matches each of its materials to a
/// <Surface> (the one naming it, else "*"). WX_BAD_INPUT "scene:LINE: ..." for
/// a mesh that cannot be imported, a material no <Surface> matches, or a
/// <Surface vertexColors> on a material without colours; a mesh without
/// triangles is a warning (unless quiet). On failure `out` is left empty.
wx_result wx_geometry_load(const wx_scene *scene, bool quiet, wx_geometry *out, wx_error *err);

/// Frees everything; the struct is zeroed.
void wx_geometry_free(wx_geometry *geometry);

/// The mesh path as the scene file wrote it (relative to the scene's folder).
const char *wx_mesh_display_name(const wx_scene *scene, const wx_mesh *mesh);

#endif
