// ensure.h: the test harness. Each tests/test_<module>.c is its own program:
//
//   TEST(exr_round_trip) { ... ENSURE(x == 1); ENSURE_NEAR(d, 2.0, 1e-6); }
//   int main(void) { RUN(exr_round_trip); return ensure_summary(); }
//
// A failed ENSURE prints file:line and the condition and ends that test;
// SKIP("reason") ends it as skipped, for a test that cannot run here (under a
// sanitizer, say), never for one whose subject is missing (that is a
// failure). The summary prints "N passed, M failed, K skipped" and returns the
// exit status (skips do not fail it). tests/run.sh runs every test program and
// adds up their counts.
#ifndef WX_ENSURE_H
#define WX_ENSURE_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "core/error.h"

extern int ensure_failed_checks; // failed checks in the running test

void ensure_report(const char *file, int line, const char *what);
void ensure_report_near(const char *file, int line, const char *what, double a, double b,
                        double tol);
void ensure_run(const char *name, void (*fn)(void));
int ensure_summary(void);
void ensure_skip(const char *reason);
bool ensure_fast(void);

#define TEST(name) static void name(void)
#define RUN(name) ensure_run(#name, name)

#define ENSURE(cond)                                                                         \
    do {                                                                                     \
        if (!(cond)) {                                                                       \
            ensure_report(__FILE__, __LINE__, #cond);                                        \
            return;                                                                          \
        }                                                                                    \
    } while (0)

/// Ends the running test as skipped, saying why.
#define SKIP(reason)                                                                         \
    do {                                                                                     \
        ensure_skip(reason);                                                                 \
        return;                                                                              \
    } while (0)

/// Marks a test that takes seconds (a whole scene run): `make test-fast`
/// (WX_FAST=1) skips it; `make test` runs it.
#define SLOW()                                                                               \
    do {                                                                                     \
        if (ensure_fast()) {                                                                 \
            SKIP("make test-fast leaves out the tests that take seconds");                   \
        }                                                                                    \
    } while (0)

#define ENSURE_NEAR(a, b, tol)                                                               \
    do {                                                                                     \
        double ensure_a_ = (double)(a), ensure_b_ = (double)(b);                             \
        if (!(fabs(ensure_a_ - ensure_b_) <= (double)(tol))) {                               \
            ensure_report_near(__FILE__, __LINE__, #a " ~ " #b, ensure_a_, ensure_b_,       \
                               (double)(tol));                                               \
            return;                                                                          \
        }                                                                                    \
    } while (0)

/// Ends the test unless the error's cause is WX_CAUSE_<want>: tests branch on the
/// cause, and check in the message only what a person reads there (the file, the
/// line, the numbers). ENSURE_CAUSE(err, BAD_VALUE).
#define ENSURE_CAUSE(err, want)                                                              \
    do {                                                                                     \
        if ((err).cause != WX_CAUSE_##want) {                                                \
            ensure_report_cause(__FILE__, __LINE__, &(err), WX_CAUSE_##want);                \
            return;                                                                          \
        }                                                                                    \
    } while (0)

void ensure_report_cause(const char *file, int line, const wx_error *err, wx_cause want);

/// Folder of the built programs ($WX_BUILD, default "build").
const char *ensure_build_dir(void);

/// Folder of the repository's tests/ (source data such as tests/bad/).
const char *ensure_tests_dir(void);

/// A new empty folder for this test program under $WX_BUILD/tmp; removed at exit.
const char *ensure_tmpdir(void);

/// Runs a shell command with stdout and stderr captured into `out` (truncated to
/// cap-1 characters). Returns the exit status, or -1 when it did not exit.
int ensure_shell(char *out, size_t cap, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/// Writes `text` to `dir/name` and returns the full path (static buffer ring of 8).
const char *ensure_write_file(const char *dir, const char *name, const char *text);

/// Reads a whole file into a malloc'd NUL-terminated string (NULL on failure).
char *ensure_read_file(const char *path);

/// One channel of an EXR (malloc'd), or NULL with the error on stderr.
float *ensure_read_channel(const char *path, const char *name, int *width, int *height);

/// A number of a --stats JSON text: the first `"key": value` after the first
/// occurrence of `after` (NULL: from the start); NaN when json is NULL or
/// either is absent.
double ensure_json_number(const char *json, const char *after, const char *key);

/// The two sides of a substance's ledger (docs/design.md section 9) in a
/// --stats JSON, from its object's text at `at`: what came in (initial
/// surface, emitted, grown, transferred in) and where it went (final surface,
/// in flight, escaped, decayed, transferred out).
void ensure_ledger_sides(const char *at, double *in, double *out);

/// What a bad input of tests/bad/ must do, from its first line
/// "<!-- expect: LINE: CAUSE: substring -->": fail for WX_CAUSE_<CAUSE> with a
/// message that starts "path:LINE: " (LINE 0: names no XML line) and contains
/// the substring. False (with a note on stderr) when the line is not there.
typedef struct ensure_expectation {
    int line;
    wx_cause cause;
    char substring[512];
} ensure_expectation;

bool ensure_read_expectation(const char *path, ensure_expectation *out);

/// True when `haystack` contains `needle`.
bool ensure_contains(const char *haystack, const char *needle);

#endif
