// stats.c: the run's noise figures (stats.h).
#include "model/stats.h"

#include <stdlib.h>

wx_result wx_noise_report_add(wx_noise_report *report, const wx_noise_figures *figures,
                              wx_error *err)
{
    if (report == NULL) {
        return WX_OK;
    }
    wx_noise_figures *grown = realloc(report->items, (size_t)(report->count + 1) * sizeof *grown);
    if (grown == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "gather: out of memory (statistics)");
    }
    report->items = grown;
    report->items[report->count++] = *figures;
    return WX_OK;
}

void wx_noise_report_free(wx_noise_report *report)
{
    free(report->items);
    report->items = NULL;
    report->count = 0;
}
