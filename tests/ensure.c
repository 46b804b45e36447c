// ensure.c: counters, reports and small helpers for the test programs.
#include "ensure.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "io/exr.h"
#include "model/image.h"

int ensure_failed_checks;
static int passed;
static int failed;
static int skipped;
static bool skipping; // the running test called SKIP
static char tmpdir[4096];

void ensure_report(const char *file, int line, const char *what)
{
    fprintf(stderr, "%s:%d: ENSURE failed: %s\n", file, line, what);
    ensure_failed_checks++;
}

void ensure_report_near(const char *file, int line, const char *what, double a, double b,
                        double tol)
{
    fprintf(stderr, "%s:%d: ENSURE_NEAR failed: %s (%.9g vs %.9g, tolerance %.3g)\n", file,
            line, what, a, b, tol);
    ensure_failed_checks++;
}

void ensure_report_cause(const char *file, int line, const wx_error *err, wx_cause want)
{
    fprintf(stderr, "%s:%d: ENSURE_CAUSE failed: %s, expected %s (\"%s\")\n", file, line,
            wx_cause_name(err->cause), wx_cause_name(want), err->message);
    ensure_failed_checks++;
}

bool ensure_read_expectation(const char *path, ensure_expectation *out)
{
    char *text = ensure_read_file(path);
    const char *prefix = "<!-- expect: ";
    bool ok = false;
    if (text != NULL && strncmp(text, prefix, strlen(prefix)) == 0) {
        char *rest = text + strlen(prefix);
        char *after_line;
        long line = strtol(rest, &after_line, 10);
        char *cause = after_line + 2;
        size_t cause_len = strspn(cause, "ABCDEFGHIJKLMNOPQRSTUVWXYZ_");
        char *substring = cause + cause_len + 2;
        char *end = strstr(rest, " -->");
        char *newline = strchr(rest, '\n');
        if (after_line != rest && strncmp(after_line, ": ", 2) == 0 && cause_len > 0 &&
            strncmp(cause + cause_len, ": ", 2) == 0 && end != NULL && end > substring &&
            (newline == NULL || end < newline)) {
            for (int c = 0; c < WX_CAUSE_COUNT && !ok; ++c) {
                const char *name = wx_cause_name((wx_cause)c);
                if (strlen(name) == cause_len && strncmp(name, cause, cause_len) == 0) {
                    out->line = (int)line;
                    out->cause = (wx_cause)c;
                    snprintf(out->substring, sizeof out->substring, "%.*s",
                             (int)(end - substring), substring);
                    ok = true;
                }
            }
        }
    }
    free(text);
    if (!ok) {
        fprintf(stderr, "%s: no '<!-- expect: LINE: CAUSE: substring -->' first line\n", path);
    }
    return ok;
}

void ensure_run(const char *name, void (*fn)(void))
{
    // WX_ONLY=NAME runs that test alone (a developer's shortcut; unset in CI).
    const char *only = getenv("WX_ONLY");
    if (only != NULL && only[0] != '\0' && strcmp(only, name) != 0) {
        return;
    }
    ensure_failed_checks = 0;
    skipping = false;
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    fn();
    clock_gettime(CLOCK_MONOTONIC, &t1);
    double seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    // Tests of a second or more say how long they took (what `make test-fast`
    // leaves out is chosen by these).
    char took[32] = "";
    if (seconds >= 1.0) {
        snprintf(took, sizeof took, " (%.1f s)", seconds);
    }
    if (ensure_failed_checks == 0 && skipping) {
        skipped++;
        printf("  skip  %s\n", name);
    } else if (ensure_failed_checks == 0) {
        passed++;
        printf("  ok    %s%s\n", name, took);
    } else {
        failed++;
        printf("  FAIL  %s%s\n", name, took);
    }
    fflush(stdout);
}

static void remove_tmpdir(void)
{
    if (tmpdir[0] != '\0' && getenv("WX_KEEP_TMP") == NULL) {
        char cmd[4200];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
        if (system(cmd) != 0) {
            fprintf(stderr, "could not remove %s\n", tmpdir);
        }
    }
}

int ensure_summary(void)
{
    printf("%d passed, %d failed, %d skipped\n", passed, failed, skipped);
    return failed == 0 ? 0 : 1;
}

bool ensure_fast(void)
{
    const char *fast = getenv("WX_FAST");
    return fast != NULL && fast[0] != '\0' && strcmp(fast, "0") != 0;
}

void ensure_skip(const char *reason)
{
    skipping = true;
    printf("        skipped: %s\n", reason);
}

const char *ensure_build_dir(void)
{
    const char *b = getenv("WX_BUILD");
    return b != NULL && b[0] != '\0' ? b : "build";
}

const char *ensure_tests_dir(void)
{
    const char *t = getenv("WX_TESTS");
    return t != NULL && t[0] != '\0' ? t : "tests";
}

const char *ensure_tmpdir(void)
{
    if (tmpdir[0] == '\0') {
        char parent[3800];
        snprintf(parent, sizeof parent, "%s/tmp", ensure_build_dir());
        mkdir(parent, 0777);
        snprintf(tmpdir, sizeof tmpdir, "%s/testXXXXXX", parent);
        if (mkdtemp(tmpdir) == NULL) {
            perror("mkdtemp");
            exit(1);
        }
        atexit(remove_tmpdir);
    }
    return tmpdir;
}

int ensure_shell(char *out, size_t cap, const char *fmt, ...)
{
    char cmd[16384];
    va_list args;
    va_start(args, fmt);
    vsnprintf(cmd, sizeof cmd, fmt, args);
    va_end(args);
    char full[16500];
    snprintf(full, sizeof full, "( %s ) 2>&1", cmd);
    FILE *pipe = popen(full, "r");
    if (pipe == NULL) {
        return -1;
    }
    size_t used = 0;
    char buf[4096];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, pipe)) > 0) {
        if (out != NULL && used + 1 < cap) {
            size_t take = n < cap - 1 - used ? n : cap - 1 - used;
            memcpy(out + used, buf, take);
            used += take;
        }
    }
    if (out != NULL && cap > 0) {
        out[used] = '\0';
    }
    int status = pclose(pipe);
    if (status == -1 || !WIFEXITED(status)) {
        return -1;
    }
    return WEXITSTATUS(status);
}

const char *ensure_write_file(const char *dir, const char *name, const char *text)
{
    static char paths[8][4096];
    static int next;
    char *path = paths[next];
    next = (next + 1) % 8;
    snprintf(path, 4096, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (f == NULL) {
        perror(path);
        exit(1);
    }
    fputs(text, f);
    fclose(f);
    return path;
}

char *ensure_read_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        return NULL;
    }
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *text = malloc((size_t)size + 1);
    if (text != NULL) {
        size_t got = fread(text, 1, (size_t)size, f);
        text[got] = '\0';
    }
    fclose(f);
    return text;
}

float *ensure_read_channel(const char *path, const char *name, int *width, int *height)
{
    const char *const names[1] = { name };
    wx_image image;
    wx_error err;
    if (wx_exr_read(path, names, 1, &image, &err) != WX_OK) {
        fprintf(stderr, "        %s\n", err.message);
        return NULL;
    }
    *width = image.width;
    *height = image.height;
    float *plane = image.channels[0];
    image.channels[0] = NULL;
    wx_image_free(&image);
    return plane;
}

double ensure_json_number(const char *json, const char *after, const char *key)
{
    const char *p = json != NULL && after != NULL ? strstr(json, after) : json;
    char pattern[128];
    snprintf(pattern, sizeof pattern, "\"%s\": ", key);
    p = p != NULL ? strstr(p, pattern) : NULL;
    return p != NULL ? strtod(p + strlen(pattern), NULL) : NAN;
}

bool ensure_contains(const char *haystack, const char *needle)
{
    return haystack != NULL && strstr(haystack, needle) != NULL;
}

void ensure_ledger_sides(const char *at, double *in, double *out)
{
    static const char *const ins[4] = { "initial_surface", "emitted", "grown", "transferred_in" };
    static const char *const outs[5] = { "final_surface", "in_flight", "escaped", "decayed",
                                         "transferred_out" };
    *in = *out = 0.0;
    for (int k = 0; k < 4; ++k) {
        *in += ensure_json_number(at, NULL, ins[k]);
    }
    for (int k = 0; k < 5; ++k) {
        *out += ensure_json_number(at, NULL, outs[k]);
    }
}
