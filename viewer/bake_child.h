// bake_child.h: `weathering bake` in a child process.
//
// The viewer draws with the system's libGL and the bake renders with OSMesa;
// the two must never share a process, so maps are baked by the command-line
// program that sits beside the viewer. Its stderr is passed through to ours and
// its last line kept for the overlay.
#ifndef VW_BAKE_CHILD_H
#define VW_BAKE_CHILD_H

#include <stdbool.h>
#include <stddef.h>
#include <sys/types.h>

#include "core/error.h"
#include "model/scene.h"
#include "core/limits.h"

typedef struct vw_bake_child {
    pid_t pid;           ///< 0 when no child runs
    int stderr_fd;       ///< read end of the child's stderr, -1 when closed
    char last_line[512]; ///< last complete line the child wrote on stderr
    char partial[512];   ///< the line being written
    size_t partial_len;
} vw_bake_child;

/// Folder of the running executable (/proc/self/exe, else argv[0]'s folder).
bool vw_executable_dir(const char *argv0, char dir[WX_PATH_MAX]);

/// Starts `<exe_dir>/weathering bake SCENE --out DIR -q`, without a shell.
wx_result vw_bake_start(vw_bake_child *child, const char *exe_dir, const char *scene_path,
                        const char *out_dir, wx_error *err);

/// Reads what the child wrote. Returns true once it has ended (then *status is
/// its exit status, 1 when it died of a signal); with `wait`, blocks until then.
bool vw_bake_poll(vw_bake_child *child, bool wait, int *status);

/// Stops a running child (the viewer quits during a bake) and reaps it.
void vw_bake_cancel(vw_bake_child *child);

#endif
