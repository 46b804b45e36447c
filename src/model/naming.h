// naming.h: the names of what a run reads and writes, in one place
// (docs/design.md sections 6, 10 and 11): the phases as bits, a camera's map
// kinds and their files <camera>_<kind>.exr, an output's frames BASE.NNNN.exr,
// UDIM tiles BASE.TTTT.exr and previews, and the channels of the mask and of a
// texture (NAME.Y, seen). Every layer above names its files through these.
#ifndef WX_NAMING_H
#define WX_NAMING_H

#include <stdbool.h>
#include <stddef.h>

#include "core/limits.h"
#include "model/scene.h"

/// The phases of a run, as bits.
enum {
    WX_PHASE_BAKE = 1 << 0,
    WX_PHASE_SIMULATE = 1 << 1,
    WX_PHASE_GATHER = 1 << 2,
    WX_PHASE_ALL = 7,
};

/// The maps of a camera, in the order bake renders them and a scene lists them.
typedef enum wx_map_kind {
    WX_MAP_DEPTH,
    WX_MAP_NORMAL,
    WX_MAP_IMPACT,
    WX_MAP_DIRT,
    WX_MAP_KINDS,
} wx_map_kind;

/// "depth", "normal", "impact", "dirt": the kind in file names and messages.
const char *wx_map_kind_name(int kind);

/// <camera>_<kind>.exr: the file bake (or simulate, for the dirt) writes for a
/// camera's map in the output folder.
void wx_map_file_name(const char *camera, int kind, char *out, size_t cap);

/// The length of `file` without a final ".exr" (in any case: ".EXR" too): the
/// BASE of BASE.NNNN.exr, BASE.TTTT.exr and BASE_NAME.png.
size_t wx_output_base_length(const char *file);

/// The preview's name for a mask's: its extension replaced by .png ("mask.exr"
/// -> "mask.png"; "mask" -> "mask.png"; "mask.png" -> "mask.preview.png").
void wx_preview_name(const char *mask_name, char *out, size_t cap);

/// BASE.NNNN.exr of mask file BASE.exr, and BASE_NAME.png, the preview of
/// channel NAME.Y.
void wx_frame_name(const char *mask_name, int frame, char *out, size_t cap);
void wx_channel_preview_name(const char *mask_name, const char *channel, char *out, size_t cap);

/// The name of tile `udim` of texture file `file`: BASE.(1001 + udim).exr,
/// BASE the file without its ".exr" (as the frames' BASE.NNNN.exr).
void wx_tile_name(const char *file, int udim, char *out, size_t cap);

/// The length of a channel's name without its final ".Y" (rust.Y -> rust;
/// ".Y" -> ""); the whole length when it has none.
size_t wx_channel_stem_length(const char *channel);

/// The mask's channels (docs/design.md sections 10 and 12): "Y" for a scene
/// with neither <Substances> nor <Masks>, else NAME.Y per substance ("dirt"
/// without <Substances>), then NAME.Y per derived mask. Returns the count.
int wx_mask_channels(const wx_scene *scene, char names[][WX_NAME_MAX]);

/// The texture's channels: the mask's (section 10) and `seen`. Returns the count.
int wx_texture_channels(const wx_scene *scene, char names[][WX_NAME_MAX]);

/// The most previews one mask or texture file writes: one per channel.
#define WX_MAX_PREVIEWS (WX_MAX_SUBSTANCES + WX_MAX_MASKS)

/// The previews the final mask or TextureMap file `file` (BASE.exr) writes
/// (docs/design.md section 10): BASE.png when the mask has one channel
/// (wx_mask_channels), else BASE_NAME.png per channel NAME.Y. The one rule the
/// writers, the scene's name checks and the run's list of outputs follow.
/// Returns the count (at most WX_MAX_PREVIEWS).
int wx_preview_names(const wx_scene *scene, const char *file, char names[][WX_OUTPUT_NAME_MAX]);

/// Whether frame `frame` (0: the final files) writes texture `t`.
bool wx_texture_writes_frame(const wx_texture_map *t, int frame);

/// Whether frame `frame` writes anything: the mask's or some TextureMap's
/// `every` divides it (frame 0: always).
bool wx_frame_wanted(const wx_scene *scene, int frame);

#endif
