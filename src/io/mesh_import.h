// mesh_import.h: triangle meshes imported with Assimp's C API (OBJ, PLY, glTF,
// FBX, STL, ...) into a wx_mesh_data (model/mesh.h).
//
// The import triangulates (Assimp, only for files with polygons, which must
// fit WX_MESH_POLYGON_WORK), generates smooth normals only where the file has
// none (smoothing across edges sharper than WX_MESH_SMOOTHING_ANGLE_DEG is not
// done, so a box keeps flat faces), joins identical vertices and applies the
// node transforms; the normals and the joining are ours, in time linear in the
// triangles (Assimp's compared every vertex with every other at its position).
// The aiScene is released as soon as the arrays are built.
// Assimp reads through our own file system: regular files only (a FIFO, a
// device or a folder is refused, never waited on), and besides the mesh file
// only files inside the mesh's folder (after realpath), so an OBJ's mtllib or a
// glTF buffer URI cannot reach elsewhere. A referenced file that is not there
// is no refusal: Assimp does without it, as before (an OBJ without its .mtl).
// Positions come out in metres where the file states a unit Assimp leaves to
// us: FBX's UnitScaleFactor (centimetres per file unit). Collada's <unit> and
// 3DS's master scale are applied by Assimp; glTF is metres; OBJ, PLY and STL
// have no unit and are taken as metres.
#ifndef WX_MESH_IMPORT_H
#define WX_MESH_IMPORT_H

#include "core/error.h"
#include "model/mesh.h"

/// Largest angle between face normals that generated normals smooth across.
#define WX_MESH_SMOOTHING_ANGLE_DEG 60.0f

/// How large a file's polygons may be: Assimp triangulates a face of n
/// vertices in time growing as n^2 (ear cutting), so the sum of n^2 over the
/// faces of more than three vertices may be at most WX_MESH_POLYGON_WORK per
/// vertex of a face (every face a 256-gon) plus WX_MESH_POLYGON_FREE (one
/// polygon of 4096 vertices, 0.1 s): the import's time stays linear in the
/// file's size. More is refused (WX_CAUSE_TOO_MANY).
#define WX_MESH_POLYGON_WORK 256.0
#define WX_MESH_POLYGON_FREE 16777216.0

/// Imports a mesh file. WX_BAD_INPUT, with a message naming the file, when it
/// is missing ("not found"), not a regular file, unreadable or unsupported
/// (Assimp's reason), when it refers to a file that is not a regular file or
/// lies outside its folder ("refers to 'x.mtl', which is not a regular file (a
/// FIFO)", "refers to '../a.bin', outside the mesh's folder"), when a vertex
/// position, a vertex colour or a normal given in the file is not a finite
/// number, or when an FBX unit is not positive; WX_CAUSE_TOO_MANY when its
/// polygons are too large to triangulate (WX_MESH_POLYGON_WORK). Normals
/// generated for triangles too large for float stay 0. WX_FAIL when out of memory, inside
/// Assimp (std::bad_alloc) too. A file without triangles imports with
/// triangle_count 0. On failure `out` is left empty (safe to free).
wx_result wx_mesh_import(const char *path, wx_mesh_data *out, wx_error *err);

/// wx_mesh_import, also keeping the texture coordinates of the UV channels
/// whose bit is set in `uv_channels` (bit c: channel c, below
/// WX_MESH_MAX_UV_CHANNELS) in out->uvs[c]. WX_BAD_INPUT naming the file when a
/// part of the mesh that has triangles lacks one of them (WX_CAUSE_NO_UVS:
/// "part 'Body' of the mesh has no texture coordinates in UV channel 0") or
/// when a texture coordinate is not a finite number (WX_CAUSE_BAD_MESH).
wx_result wx_mesh_import_uvs(const char *path, unsigned uv_channels, wx_mesh_data *out,
                             wx_error *err);

#endif
