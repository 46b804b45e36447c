// bench_report.h: what the benchmarks share. Every figure a benchmark wants in
// the summary of `make bench` goes through bench_row(), which appends one line
// to the CSV file named by $WX_BENCH_CSV (when set):
//
//     bench,configuration,metric,value,unit,target,status
//
// `target` is empty for figures without one; `status` is "met", "MISSED" or
// empty. A missed target is a row, never an exit status: the benchmarks exit
// non-zero only when they cannot run. tests/bench/report.sh prints the table.
#ifndef WX_BENCH_REPORT_H
#define WX_BENCH_REPORT_H

#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <time.h>

static inline double bench_now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static inline double bench_cpu_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static inline int bench_compare_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/// Median of n values (sorts them in place).
static inline double bench_median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof(double), bench_compare_double);
    return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Peak resident memory of this process so far, in MB.
static inline double bench_peak_mb(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_maxrss / 1024.0; // kilobytes on Linux
}

static inline long bench_env_long(const char *name, long fallback)
{
    const char *v = getenv(name);
    return v != NULL && atol(v) > 0 ? atol(v) : fallback;
}

/// Appends one row to $WX_BENCH_CSV. `target` may be NULL (no target); then
/// `met` is ignored. The configuration is a printf format.
static inline void bench_row(const char *bench, const char *metric, double value,
                             const char *unit, const char *target, bool met,
                             const char *config_fmt, ...)
{
    const char *path = getenv("WX_BENCH_CSV");
    if (path == NULL || path[0] == '\0') {
        return;
    }
    FILE *f = fopen(path, "a");
    if (f == NULL) {
        return;
    }
    char config[256];
    va_list ap;
    va_start(ap, config_fmt);
    vsnprintf(config, sizeof config, config_fmt, ap);
    va_end(ap);
    for (char *c = config; *c != '\0'; ++c) {
        *c = *c == ',' ? ';' : *c; // a comma would shift the CSV's columns
    }
    fprintf(f, "%s,%s,%s,%.6g,%s,%s,%s\n", bench, config, metric, value, unit,
            target != NULL ? target : "", target == NULL ? "" : met ? "met" : "MISSED");
    fclose(f);
}

#endif
