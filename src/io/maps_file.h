// maps_file.h: the maps of one camera read from their EXR files: depth (R or Z),
// normal (R G B), impact (R G), dirt (R G B, or the initialDirt channel a
// simulated dirt map keeps), checked for size agreement and finite values.
#ifndef WX_MAPS_FILE_H
#define WX_MAPS_FILE_H

#include "core/error.h"
#include "model/image.h"
#include "model/maps.h"
#include "model/scene.h"

/// Which maps to load.
enum {
    WX_MAPS_DEPTH = 1 << 0,
    WX_MAPS_NORMAL = 1 << 1,
    WX_MAPS_IMPACT = 1 << 2,
    WX_MAPS_DIRT = 1 << 3,
    WX_MAPS_ALL = 15,
    /// With WX_MAPS_DIRT: read the dirt plane from channel "initialDirt" when the
    /// file has it (a dirt map written by `simulate`), else from R.
    WX_MAPS_INITIAL_DIRT = 1 << 4,
    /// With WX_MAPS_DIRT: also read the channels a simulated dirt map adds,
    /// "initialDirt" and "hits", into initial_dirt and hits (for the gather).
    WX_MAPS_SIMULATED = 1 << 5,
};

/// wx_maps_load for the maps of `scene` (NULL: version 1's one substance): the
/// dirt map's substances as the scene declares them. A substance whose
/// NAME.amount the file lacks reads as zeros, but for substance "dirt" of a
/// file in version 1's layout (R G B, e.g. the thesis' maps). The surface and
/// area planes are read when the file has them.
wx_result wx_maps_load_scene(wx_maps *maps, unsigned which, int threads, const wx_scene *scene,
                             const char *depth_path, const char *normal_path,
                             const char *impact_path, const char *dirt_path, wx_error *err);

/// wx_maps_load_scene for a camera of `layers` layers (docs/design.md section
/// 14): layer 0 from the plain channels, layer k from "layerK." ones, into the
/// per-layer blocks of model/maps.h. A layer the files lack is an error
/// naming the file and channel.
wx_result wx_maps_load_layers(wx_maps *maps, unsigned which, int threads, const wx_scene *scene,
                              int layers, const char *depth_path, const char *normal_path,
                              const char *impact_path, const char *dirt_path, wx_error *err);

/// wx_maps_load_layers with some files already in memory: given[k] (NULL: read
/// the file) holds what the file at paths[k] holds (depth, normal, impact,
/// dirt; its planes, channel names and string and matrix attributes, as
/// `bake` hands them to the writer of that file), and is read in its place.
/// The maps are the same as from the files; `given` is only read.
wx_result wx_maps_load_given(wx_maps *maps, unsigned which, int threads, const wx_scene *scene,
                             int layers, const char *const paths[4], const wx_image *const given[4],
                             wx_error *err);

/// Loads the maps selected by `which` from the given paths (NULL or "" for a map
/// not wanted). Depth reads channel R or Z, normal R G B, impact R G, dirt R G B.
/// All loaded maps must have the same size; a mismatch names both files. Each
/// file's chunks are decoded on `threads` workers (the same maps for any count).
wx_result wx_maps_load(wx_maps *maps, unsigned which, int threads, const char *depth_path,
                       const char *normal_path, const char *impact_path,
                       const char *dirt_path, wx_error *err);

#endif
