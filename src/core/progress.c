// progress.c: a one-line progress bar on stderr.
#include "core/progress.h"

#include <stdio.h>
#include <time.h>
#include <unistd.h>

double wx_now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void draw(const wx_progress *progress, int64_t done, double now)
{
    enum { BAR = 30 };
    double fraction = progress->total > 0 ? (double)done / (double)progress->total : 1.0;
    if (fraction > 1.0) {
        fraction = 1.0;
    }
    int filled = (int)(fraction * BAR);
    char bar[BAR + 1];
    for (int i = 0; i < BAR; ++i) {
        bar[i] = i < filled ? '#' : '.';
    }
    bar[BAR] = '\0';
    double elapsed = now - progress->start_s;
    double eta = fraction > 0.0 ? elapsed * (1.0 - fraction) / fraction : 0.0;
    fprintf(stderr, "\r%-10s [%s] %5.1f%%  %6.1fs  eta %6.1fs ", progress->label, bar,
            100.0 * fraction, elapsed, eta);
    fflush(stderr);
}

void wx_progress_begin(wx_progress *progress, const char *label, int64_t total, bool quiet)
{
    progress->label = label;
    progress->total = total;
    progress->enabled = !quiet && isatty(STDERR_FILENO);
    progress->start_s = wx_now_s();
    progress->last_draw_s = 0.0;
    if (progress->enabled) {
        draw(progress, 0, progress->start_s);
    }
}

void wx_progress_update(wx_progress *progress, int64_t done)
{
    if (!progress->enabled) {
        return;
    }
    double now = wx_now_s();
    if (now - progress->last_draw_s < 0.1) {
        return;
    }
    progress->last_draw_s = now;
    draw(progress, done, now);
}

void wx_progress_end(wx_progress *progress)
{
    if (!progress->enabled) {
        return;
    }
    draw(progress, progress->total, wx_now_s());
    fputc('\n', stderr);
    progress->enabled = false;
}
