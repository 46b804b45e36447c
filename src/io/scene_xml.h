// scene_xml.h: the scene file (docs/design.md section 3) read with libxml2 into
// a wx_scene. Everything is checked on loading (numbers finite and in range,
// matrices of 16 numbers that invert one another, unique camera names, map
// files that exist and agree in size, no unknown elements or attributes), so
// later phases can trust a wx_scene. Every error reads "scene.xml:LINE: what is
// wrong". The only module that includes libxml2 (io/scene_xml*.c).
#ifndef WX_SCENE_XML_H
#define WX_SCENE_XML_H

#include "core/error.h"
#include "model/scene.h"

/// Parses and validates a scene file. On failure the scene is left empty (safe
/// to free) and err holds "path:LINE: message" (WX_BAD_INPUT) or an I/O error.
wx_result wx_scene_load(const char *path, wx_scene *out, wx_error *err);

/// wx_scene_load of a scene held in memory (`size` bytes of `text`), as if it
/// were the file `path`: relative paths inside it are relative to path's
/// folder, messages name path. The file itself is never opened.
wx_result wx_scene_load_text(const char *path, const char *text, size_t size, wx_scene *out,
                             wx_error *err);

/// One tile's changes to a scene file (docs/tiles.md): its name, its <Tile>,
/// the new <View> of each input camera (by name; a camera not listed is left
/// out of the tile), and the folder the tile scene is written to, so that
/// relative paths of meshes and maps are rewritten to stay valid from there.
typedef struct wx_tile_scene_edit {
    const char *name;       ///< the tile scene's `name`
    wx_tile_def tile;       ///< written as <Tile>
    const char *to_dir;     ///< absolute folder the tile scene goes to
    int view_count;
    const char *const *view_names;
    const wx_view *views;
    /// The output camera's new <View> and <OutputMap> size, or NULL to keep it.
    const wx_view *output_view;
} wx_tile_scene_edit;

/// The text of the tile scene that `edit` makes of the scene file `path`
/// (everything else as the file has it, comments included). *text is malloc'd.
wx_result wx_scene_tile_text(const char *path, const wx_tile_scene_edit *edit, char **text,
                             size_t *size, wx_error *err);

#endif
