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
    /// 1 per triangle, NULL when the mesh has none: bit k set when the edge
    /// from corner k to corner k + 1 (mod 3) is a crease, an edge whose other
    /// triangle has other normals at its ends (wx_mesh_find_creases). The
    /// smooth surface keeps it straight.
    uint8_t *creases;
    int material_count;    ///< distinct material names used by triangles, in file order
    char (*material_names)[WX_MATERIAL_NAME_MAX];
    bool *material_colored; ///< per material: all its vertices carry a colour
    double bounds_min[3];  ///< world-space bounds of the vertices
    double bounds_max[3];
    /// Closed parts whose normals pointed into them, turned outwards by the
    /// import (wx_mesh_orient_outwards).
    int64_t parts_turned;
    /// Parts with an edge two triangles run the same way (faces wound both
    /// ways, some inside out): left as they are, and warned about, since
    /// the layered maps then read a solid's side as a sheet and particles
    /// pass through (wx_mesh_orient_outwards).
    int64_t parts_wound_both_ways;
} wx_mesh_data;

/// Frees the vertex and triangle arrays only (once uploaded), keeping counts,
/// material names and bounds.
void wx_mesh_data_release_arrays(wx_mesh_data *mesh);

/// Frees everything; the struct is zeroed.
void wx_mesh_data_free(wx_mesh_data *mesh);

/// The depth complexity of the mesh seen along `axis` (a unit vector): the
/// most triangles any ray parallel to it crosses, over a grid x grid lattice
/// of rays spanning the mesh's outline (docs/cameras.md, "Layers"). 0 for no
/// triangles; -1 when out of memory. What `init` sizes its cameras' layers by.
int wx_mesh_depth_complexity(const wx_mesh_data *mesh, const double axis[3], int grid);

/// Phong tessellation's shape factor: 1/2 makes the curve along an edge leave
/// each end in the tangent plane its vertex normal gives (for a circle's chord
/// the exact quadratic; 3/4, the paper's choice for looks, leaves half the
/// kink of the flat triangles between neighbours, 1 the whole kink turned
/// over). docs/cameras.md.
#define WX_PHONG_SHAPE 0.5

/// The point of triangle `tri` at barycentric weights w (summing to 1) on the
/// smooth surface its vertex normals describe, relative to mesh->origin: the
/// flat point projected onto each corner's tangent plane, the projections
/// blended by w and mixed with the flat point by WX_PHONG_SHAPE (Phong
/// tessellation, Boubekeur and Alexa 2008). A corner without a normal keeps
/// the flat point; a triangle whose three normals are equal stays flat, and so
/// does an edge whose two normals are equal. A point of an edge is the same,
/// bit for bit, from both triangles that share it.
void wx_mesh_phong_point(const wx_mesh_data *mesh, int64_t tri, const double w[3],
                         double out[3]);

/// The unit normal of that smooth surface at weights w (the cross product of
/// its derivatives, turned to the side of the interpolated vertex normals):
/// what the normal maps and the TextureMaps read, so that the area a texel
/// covers is the area of the surface the depth maps hold. A triangle whose
/// normals are its plane's gets its plane's normal.
void wx_mesh_phong_normal(const wx_mesh_data *mesh, int64_t tri, const double w[3],
                          float out[3]);

/// The length of the edges whose two vertex normals differ at `quantile`
/// (0.9: nine in ten are shorter; 1: the longest); 0 for a flat-shaded mesh.
double wx_mesh_curved_edge_length(const wx_mesh_data *mesh, double quantile);

/// Finds the mesh's creases (mesh->creases; left NULL when it has none): the
/// edges, by their ends' positions, that two triangles share with other
/// normals at an end (a hard edge where the normals are split: a cylinder's
/// rim between its flat cap and its smooth side, or the pole of a sphere whose
/// fan exceeds the 60 degree smoothing). Each side would curve the edge its
/// own way and the smooth surface would open a crack along it, through which
/// the cameras would see the inside; straight on both sides, it stays closed.
/// WX_FAIL when out of memory.
wx_result wx_mesh_find_creases(wx_mesh_data *mesh, wx_error *err);

/// Whether triangle t has an edge, not a crease, whose vertex normals differ
/// (the bake draws it on its smooth surface, with wx_mesh_phong_normal's
/// normals).
bool wx_mesh_triangle_curves(const wx_mesh_data *mesh, int64_t t);

/// How many triangles have an edge, not a crease, whose vertex normals differ.
int64_t wx_mesh_curved_triangles(const wx_mesh_data *mesh);

/// The most triangles the bake cuts a mesh's smooth surface into
/// (raster/bake.c; pipeline/memory.c counts them).
#define WX_SMOOTH_MAX_TRIANGLES 1000000.0

/// Replaces every triangle that has an edge whose normals differ by level x
/// level triangles on its smooth surface (wx_mesh_phong_point), with its
/// normals there (wx_mesh_phong_normal) and colours interpolated, so that a renderer draws the surface the normals
/// describe; the other triangles stay. Shared edges are cut at the same points
/// on both sides (no cracks). UVs are not carried (the bake does not read
/// them). level <= 1 changes nothing.
wx_result wx_mesh_smooth_subdivide(wx_mesh_data *mesh, int level, wx_error *err);

/// Turns outwards every closed part of the mesh whose normals point into it,
/// as a mesh exported with its normals flipped has them: the bake, the
/// TextureMap's `seen` and the masks read the vertex normals as the outside,
/// so such a part would be seen only from behind (docs/cameras.md, "Meshes
/// wound inwards"). A part is a set of triangles joined through vertices at
/// the same position; it is closed when each of its edges is shared by exactly
/// two of its triangles, running opposite ways (a triangle with two corners at
/// one position bounds nothing and is left out). Its normals point in when the
/// flux of the position through the surface along the normals (area times
/// centroid . mean corner normal, summed) is negative: its vertices' normals
/// are negated. Its winding, where the signed volume of its triangles is
/// negative, is turned too (two corners swapped). Open parts, sheets, parts
/// whose volume is under a millionth of their bounding box's and cavities (a
/// closed part inside another closed part: a room seen from inside) stay as
/// they are.
/// *turned (may be NULL) receives how many parts had their normals turned.
/// WX_FAIL when out of memory (the mesh unchanged).
wx_result wx_mesh_orient_outwards(wx_mesh_data *mesh, int64_t *turned, wx_error *err);

#endif
