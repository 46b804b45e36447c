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
    /// Where the scene will be written (NULL: scene.xml in the current folder):
    /// it is checked as that file before it is handed back.
    const char *scene_path;
    bool quiet;             ///< no warning (a mesh the cameras see edge-on)
} wx_init_def;

/// The smallest and the largest mesh (largest extent, in its units) a scene is
/// generated for: the cameras' matrices of a smaller or a larger one mix
/// numbers too different for single precision (the scene check refuses them
/// as singular or not orthographic; the limit is about 5e5 for the largest).
#define WX_INIT_MIN_SIZE 1e-6
#define WX_INIT_MAX_SIZE 1e5

/// Index of a preset by name, or -1.
int wx_preset_find(const char *name);

/// Metres per unit of a --units name (m, cm, mm, in, ft), or 0 when unknown.
double wx_unit_metres(const char *name);

/// Imports the mesh and writes the scene's XML into *text (malloc'd,
/// commented), checked as the scene file def->scene_path before it is handed
/// back. WX_BAD_INPUT naming the mesh (WX_CAUSE_BAD_MESH, nothing in *text)
/// when it cannot be read or has no triangles, when its path cannot be
/// written in XML (not UTF-8, a control character), when it is too small or
/// too large (WX_INIT_MIN_SIZE, WX_INIT_MAX_SIZE) or lies too far from the
/// origin for its size (floats there more than a quarter of a camera
/// texel apart), or when the scene check refuses the scene for any other
/// reason. Warns (unless def->quiet) when the generated cameras would see the
/// mesh edge-on (wx_geometry_warn_blind).
wx_result wx_scene_generate(const wx_init_def *def, char **text, wx_error *err);

#endif
