// input_file.h: opening the files a scene names (scene, maps, meshes and the
// files a mesh refers to) for reading. Only regular files are opened, and the
// open never blocks: a FIFO, a device, a folder or a loop of symbolic links is
// refused with a reason instead of hanging the program or reading a stream.
#ifndef WX_INPUT_FILE_H
#define WX_INPUT_FILE_H

#include <stdbool.h>
#include <stddef.h>

#include "core/error.h"

/// Room for the reason of a refusal ("is not a regular file (a FIFO)").
#define WX_INPUT_WHY_MAX 96

/// Opens `path` read-only when it is a regular file. Returns the descriptor
/// (close-on-exec, blocking reads), or -1 with `why` set to a short phrase for
/// a message ("is not a regular file (a FIFO)", "cannot open (No such file or
/// directory)") and `cause` (may be NULL) to WX_CAUSE_FILE_MISSING,
/// WX_CAUSE_NOT_REGULAR_FILE or WX_CAUSE_UNREADABLE.
int wx_open_regular(const char *path, char why[WX_INPUT_WHY_MAX], wx_cause *cause);

/// The same test without opening the file (stat): true when `path` names a
/// regular file, else false with `why` and `cause` as above.
bool wx_is_regular_file(const char *path, char why[WX_INPUT_WHY_MAX], wx_cause *cause);

#endif
