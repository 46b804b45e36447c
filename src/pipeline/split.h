// split.h: `weathering split FILE.exr` (docs/presets.md): every channel of an
// EXR as a one-channel file BASE_NAME.exr (channel Y inside), for programs
// that read one layer at a time (Blender 3.4's shader nodes).
//
// Channel names come from the file, so they are untrusted: they become file
// names only through the scene-name rule (wx_default_out_name: no '/', no
// leading '.', no control character), and every check is made before the
// first file is written: two channels that would share a file, a file that is
// the input, an existing folder, link or other non-regular file, a name too
// long for the file system.
#ifndef WX_SPLIT_H
#define WX_SPLIT_H

#include "core/error.h"
#include "core/limits.h"

/// What to split, and where.
typedef struct wx_split_def {
    const char *input;   ///< the EXR file
    const char *out_dir; ///< the folder of the files (made when missing); NULL: the input's
    /// Called with each file's path once it is written (may be NULL).
    void (*on_written)(const char *path, void *context);
    void *context;
} wx_split_def;

/// The file name BASE_NAME.exr of `channel` in an EXR whose own name (without
/// folder and extension) is `base`: a trailing ".Y" dropped ("rust.Y" gives
/// BASE_rust.exr, a plain "Y" gives BASE_Y.exr), then the scene-name rule.
void wx_split_file_name(const char *base, const char *channel, char out[WX_OUTPUT_NAME_MAX]);

/// Writes every channel of def->input as its own file. WX_BAD_INPUT (nothing
/// written, no folder made) for an unreadable input and for every conflict
/// above; WX_FAIL for a failure while writing.
wx_result wx_split_exr(const wx_split_def *def, wx_error *err);

#endif
