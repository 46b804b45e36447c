// preset.h: a scene generated for a mesh from a preset (docs/design.md section
// 13, docs/presets.md): `weathering init MESH --preset P` and `weathering run
// MESH --preset P`. Everything is sized from the mesh's bounding box, so that
// a model in centimetres weathers as one in metres; only gravity is physical,
// in the mesh's unit (`--units`).
#ifndef WX_PRESET_H
#define WX_PRESET_H

#include <stdbool.h>

#include "core/error.h"

/// The presets, in the order `--help` lists them.
extern const char *const wx_preset_names[];
extern const int wx_preset_count;

/// What a scene is generated from.
typedef struct wx_init_def {
    const char *mesh_path;  ///< the mesh file (any format the import reads)
    const char *mesh_ref;   ///< the path the scene writes for it (relative to the scene's folder)
    const char *preset;     ///< one of wx_preset_names (NULL: "rain")
    int resolution;         ///< texels across the largest camera frame (default 1024)
    double unit_m;          ///< metres per mesh unit (default 1)
} wx_init_def;

/// Index of a preset by name, or -1.
int wx_preset_find(const char *name);

/// Metres per unit of a --units name (m, cm, mm, in, ft), or 0 when unknown.
double wx_unit_metres(const char *name);

/// Imports the mesh (WX_BAD_INPUT naming it when it cannot be read or has no
/// triangles) and writes the scene's XML into *text (malloc'd, commented).
wx_result wx_scene_generate(const wx_init_def *def, char **text, wx_error *err);

#endif
