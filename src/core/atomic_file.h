// atomic_file.h: outputs are written to a temporary name beginning with '.' in
// the same folder and renamed over the final name only when complete (docs/design.md
// section 7), so an interrupted run never leaves a torn file under a final name.
//
// Every temporary name handed out is remembered until it is committed, so that
// an interrupt (SIGINT, SIGTERM, SIGHUP) can remove the temporaries still being
// written before the program exits (wx_temp_remove_all, async-signal-safe). A
// run killed outright (SIGKILL) leaves its temporaries behind; the next run in
// the same folder removes them (wx_temp_remove_stale).
#ifndef WX_ATOMIC_FILE_H
#define WX_ATOMIC_FILE_H

#include <stdbool.h>
#include <stddef.h>

#include "core/error.h"
#include "core/limits.h"

/// The temporary name for `path`: "<folder>/.<basename>.tmp<pid>". The name is
/// remembered until wx_atomic_commit (or wx_temp_forget) for wx_temp_remove_all.
void wx_temp_path(const char *path, char tmp[WX_PATH_MAX]);

/// Forgets a temporary name that was removed or never created.
void wx_temp_forget(const char *tmp);

/// Removes every remembered temporary file. Async-signal-safe: meant for a
/// signal handler that exits right after.
void wx_temp_remove_all(void);

/// An interrupt's handler: from now on a temporary created by another thread
/// is removed at once (wx_temp_created), then removes every remembered one.
/// Async-signal-safe; the handler exits right after.
void wx_temp_interrupt(void);

/// Called by a writer right after it created `tmp`: when an interrupt came
/// first, removes it and waits for the handler to end the process. Without
/// this a thread that created its temporary after the handler's sweep (a
/// loaded machine can pause the handler between its sweep and its exit) left
/// it behind.
void wx_temp_created(const char *tmp);

/// Removes the temporary files ".<name>.tmp<pid>" in `folder` whose process no
/// longer runs (left by a run that was killed) and whose <name> `is_ours` accepts
/// (only the program's own output names: a user's ".draft.txt.tmp42" stays).
/// Returns how many were removed.
int wx_temp_remove_stale(const char *folder, bool (*is_ours)(const char *name, void *context),
                         void *context);

/// Flushes `tmp` to disk and renames it to `path`; removes `tmp` on failure.
wx_result wx_atomic_commit(const char *tmp, const char *path, wx_error *err);

/// Writes `size` bytes to `path` atomically.
wx_result wx_write_file_atomic(const char *path, const void *data, size_t size, wx_error *err);

#endif
