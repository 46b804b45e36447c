// error.c: formatting of user-facing error messages.
#include "error.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

wx_result wx_error_set(wx_error *err, wx_result code, const char *fmt, ...)
{
    if (err != NULL) {
        va_list args;
        va_start(args, fmt);
        vsnprintf(err->message, sizeof err->message, fmt, args);
        va_end(args);
    }
    return code;
}

void wx_error_prefix(wx_error *err, const char *fmt, ...)
{
    if (err == NULL) {
        return;
    }
    char prefix[WX_ERROR_MAX];
    va_list args;
    va_start(args, fmt);
    vsnprintf(prefix, sizeof prefix, fmt, args);
    va_end(args);
    char joined[2 * WX_ERROR_MAX + 2];
    snprintf(joined, sizeof joined, "%s: %s", prefix, err->message);
    snprintf(err->message, sizeof err->message, "%.*s", WX_ERROR_MAX - 1, joined);
}
