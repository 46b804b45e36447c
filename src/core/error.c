// error.c: formatting of user-facing error messages, warnings and notes.
#include "core/error.h"

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

// Length of the UTF-8 sequence at s that encodes a printable character (no C1
// control U+0080..U+009F, no overlong form, no surrogate), or 0.
static int utf8_printable_length(const unsigned char *s)
{
    unsigned c = s[0];
    int n;
    if (c >= 0xc2 && c <= 0xdf) {
        n = 2;
    } else if (c >= 0xe0 && c <= 0xef) {
        n = 3;
    } else if (c >= 0xf0 && c <= 0xf4) {
        n = 4;
    } else {
        return 0;
    }
    uint32_t cp = c & (0x7fu >> n);
    for (int k = 1; k < n; ++k) {
        if ((s[k] & 0xc0) != 0x80) {
            return 0;
        }
        cp = (cp << 6) | (s[k] & 0x3fu);
    }
    bool overlong = (n == 3 && cp < 0x800) || (n == 4 && cp < 0x10000);
    if (overlong || cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff) ||
        (cp >= 0x80 && cp <= 0x9f)) {
        return 0;
    }
    return n;
}

void wx_printable(const char *text, char *out, size_t cap)
{
    if (cap == 0) {
        return;
    }
    size_t used = 0;
    const unsigned char *s = (const unsigned char *)text;
    while (*s != '\0') {
        char piece[8];
        size_t len;
        int n = *s >= 0x80 ? utf8_printable_length(s) : 1;
        if (*s >= 0x20 && *s != 0x7f && n > 0) {
            len = (size_t)n;
            memcpy(piece, s, len);
        } else {
            n = 1;
            const char *name = *s == '\n' ? "\\n" : *s == '\r' ? "\\r" : *s == '\t' ? "\\t" : NULL;
            len = name != NULL ? (size_t)snprintf(piece, sizeof piece, "%s", name)
                               : (size_t)snprintf(piece, sizeof piece, "\\x%02x", *s);
        }
        if (used + len + 1 > cap) {
            break;
        }
        memcpy(out + used, piece, len);
        used += len;
        s += n;
    }
    out[used] = '\0';
}

// Copies `text` into out[cap]; a text too long keeps its beginning and its end
// (where a message says what happened) around " ... ", cut between characters.
static void fit(const char *text, char *out, size_t cap)
{
    size_t len = strlen(text);
    if (len < cap) {
        memcpy(out, text, len + 1);
        return;
    }
    static const char gap[] = " ... ";
    size_t keep = (cap - sizeof gap) / 2;
    size_t head = keep, tail = len - keep;
    while (head > 0 && ((unsigned char)text[head] & 0xc0) == 0x80) {
        head--; // not inside a UTF-8 sequence
    }
    while (tail < len && ((unsigned char)text[tail] & 0xc0) == 0x80) {
        tail++;
    }
    snprintf(out, cap, "%.*s%s%s", (int)head, text, gap, text + tail);
}

// Formats, escapes and fits into out[cap]: a message longer than cap (a path of
// 4000 characters) keeps the reason at its end.
static void vformat_printable(char *out, size_t cap, const char *fmt, va_list args)
{
    char small[WX_ERROR_MAX];
    char *raw = small;
    va_list again;
    va_copy(again, args);
    int n = vsnprintf(small, sizeof small, fmt, args);
    if (n >= (int)sizeof small && (raw = malloc((size_t)n + 1)) != NULL) {
        vsnprintf(raw, (size_t)n + 1, fmt, again);
    } else if (raw == NULL) {
        raw = small; // out of memory: the first WX_ERROR_MAX - 1 bytes
    }
    va_end(again);
    size_t len = strlen(raw);
    char *escaped = len >= sizeof small / 4 ? malloc(4 * len + 1) : NULL;
    if (escaped != NULL) {
        wx_printable(raw, escaped, 4 * len + 1);
        fit(escaped, out, cap);
        free(escaped);
    } else {
        wx_printable(raw, out, cap);
    }
    if (raw != small) {
        free(raw);
    }
}

static const wx_result cause_results[WX_CAUSE_COUNT] = {
#define WX_CAUSE_RESULT(name, result, text) result,
    WX_CAUSES(WX_CAUSE_RESULT)
#undef WX_CAUSE_RESULT
};

static const char *const cause_names[WX_CAUSE_COUNT] = {
#define WX_CAUSE_NAME(name, result, text) #name,
    WX_CAUSES(WX_CAUSE_NAME)
#undef WX_CAUSE_NAME
};

wx_result wx_cause_result(wx_cause cause)
{
    return cause >= 0 && cause < WX_CAUSE_COUNT ? cause_results[cause] : WX_FAIL;
}

const char *wx_cause_name(wx_cause cause)
{
    return cause >= 0 && cause < WX_CAUSE_COUNT ? cause_names[cause] : "?";
}

wx_result wx_fail(wx_error *err, wx_cause cause, const char *fmt, ...)
{
    if (err != NULL) {
        err->cause = cause;
        va_list args;
        va_start(args, fmt);
        vformat_printable(err->message, sizeof err->message, fmt, args);
        va_end(args);
    }
    return wx_cause_result(cause);
}

void wx_error_prefix(wx_error *err, const char *fmt, ...)
{
    if (err == NULL) {
        return;
    }
    char prefix[WX_ERROR_MAX];
    va_list args;
    va_start(args, fmt);
    vformat_printable(prefix, sizeof prefix, fmt, args);
    va_end(args);
    char joined[2 * WX_ERROR_MAX + 2];
    snprintf(joined, sizeof joined, "%s: %s", prefix, err->message);
    fit(joined, err->message, sizeof err->message);
}

void wx_list_append(char *list, size_t cap, const char *item)
{
    size_t used = strlen(list);
    if (used + 1 < cap) {
        snprintf(list + used, cap - used, "%s%s", used > 0 ? ", " : "", item);
    }
}

static void vprint_labelled(bool quiet, const char *label, const char *fmt, va_list args)
{
    if (quiet) {
        return;
    }
    char message[WX_ERROR_MAX];
    vformat_printable(message, sizeof message, fmt, args);
    fprintf(stderr, "weathering: %s: %s\n", label, message);
}

void wx_warn(bool quiet, const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    vprint_labelled(quiet, "warning", fmt, args);
    va_end(args);
}

void wx_note(bool quiet, const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    vprint_labelled(quiet, "note", fmt, args);
    va_end(args);
}
