// progress.h: a progress bar on stderr for long phases, shown only when stderr
// is a terminal and the user did not ask for quiet (-q).
#ifndef WX_PROGRESS_H
#define WX_PROGRESS_H

#include <stdbool.h>
#include <stdint.h>

typedef struct wx_progress {
    const char *label;
    int64_t total;
    bool enabled;
    double start_s;
    double last_draw_s;
} wx_progress;

/// Starts a bar of `total` units (nothing is drawn when quiet or not a terminal).
void wx_progress_begin(wx_progress *progress, const char *label, int64_t total, bool quiet);

/// Reports `done` of `total` units; redraws at most ten times a second.
void wx_progress_update(wx_progress *progress, int64_t done);

/// Draws the finished bar with the elapsed time and ends the line.
void wx_progress_end(wx_progress *progress);

/// Monotonic time in seconds.
double wx_now_s(void);

#endif
