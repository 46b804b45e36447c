// usage.c: command-line helpers shared by the programs (usage.h).
#include "core/usage.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>

#include "core/error.h"

int wx_usage_error(const char *program, const char *fmt, const char *detail)
{
    fprintf(stderr, "%s: ", program);
    fprintf(stderr, fmt, detail);
    fprintf(stderr, "\nTry '%s --help'.\n", program);
    return WX_BAD_INPUT;
}

bool wx_parse_whole(const char *text, uint64_t lo, uint64_t hi, uint64_t *out)
{
    if (text == NULL || text[0] < '0' || text[0] > '9') {
        return false;
    }
    errno = 0;
    char *end = NULL;
    unsigned long long v = strtoull(text, &end, 10);
    if (errno != 0 || *end != '\0' || v < lo || v > hi) {
        return false;
    }
    *out = (uint64_t)v;
    return true;
}
