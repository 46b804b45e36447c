// geometry.h: the scene's <Geometry> as imported meshes matched to their
// <Surface>s: what `bake` draws and `info` reports (pipeline/load.c imports it).
#ifndef WX_GEOMETRY_H
#define WX_GEOMETRY_H

#include <stdbool.h>
#include <stdint.h>

#include "core/error.h"
#include "model/camera.h"
#include "model/mesh.h"
#include "model/scene.h"

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
    bool has_dirt;      ///< some matched surface starts with a substance (a density or vertex colours), or a rule grows one
    double import_s;    ///< wall-clock seconds of the imports
} wx_geometry;

/// Matches each material of imported mesh `mesh_index` to a <Surface> (the one
/// naming it, else "*") into g->surface (allocated by the caller, one per
/// material); sets *has_dirt when a matched surface starts with dirt.
/// WX_CAUSE_UNMATCHED_MATERIAL "scene:LINE: ..." for a material no <Surface>
/// matches, or a <Surface vertexColors> on a material without colours.
wx_result wx_geometry_match(const wx_scene *scene, int mesh_index, wx_geometry_mesh *g,
                            bool *has_dirt, wx_error *err);

/// Frees everything; the struct is zeroed.
void wx_geometry_free(wx_geometry *geometry);

/// The texels of `camera`'s map that the mesh's triangles cover, as the sum of
/// their projected areas in texels (overlaps counted twice) over the triangles
/// that reach into its frame: about 0 when the camera sees the mesh edge-on
/// (a mesh without thickness along its view), so that its bake records no
/// surface. 0 when the mesh's arrays are released or the camera is not
/// orthographic.
double wx_geometry_texels_seen(const wx_mesh_data *mesh, const wx_camera *camera);

#endif
