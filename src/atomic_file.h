// atomic_file.h: outputs are written to a temporary name beginning with '.' in
// the same folder and renamed over the final name only when complete (DESIGN
// section 7), so an interrupted run never leaves a torn file under a final name.
#ifndef WX_ATOMIC_FILE_H
#define WX_ATOMIC_FILE_H

#include <stddef.h>

#include "error.h"
#include "scene.h"

/// The temporary name for `path`: "<folder>/.<basename>.tmp<pid>".
void wx_temp_path(const char *path, char tmp[WX_PATH_MAX]);

/// Flushes `tmp` to disk and renames it to `path`; removes `tmp` on failure.
wx_result wx_atomic_commit(const char *tmp, const char *path, wx_error *err);

/// Writes `size` bytes to `path` atomically.
wx_result wx_write_file_atomic(const char *path, const void *data, size_t size, wx_error *err);

#endif
