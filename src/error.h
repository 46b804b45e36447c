// error.h: result codes and messages for everything that touches files, XML or GL.
// A function that can fail on input returns a wx_result and fills a wx_error whose
// message names the file (and the XML line), ready to print as it is: one
// printable line, whatever bytes the files it quotes hold.
#ifndef WX_ERROR_H
#define WX_ERROR_H

#include <stdbool.h>
#include <stddef.h>

/// Exit-status-compatible result codes (DESIGN section 6).
typedef enum wx_result {
    WX_OK = 0,
    WX_FAIL = 1,      ///< other failure: out of memory, I/O error, GL failure
    WX_BAD_INPUT = 2, ///< bad usage or bad input: the message names the file
} wx_result;

#define WX_ERROR_MAX 1024

/// A message for the user, e.g. "scene.xml:12: <Gravity> acceleration is not a number".
typedef struct wx_error {
    char message[WX_ERROR_MAX];
} wx_error;

/// Formats the message into err (when err is not NULL) and returns code. Control
/// characters (a newline from `&#10;` in an attribute, an ESC in a mesh's
/// material name) are written as escapes (\n, \x1b), so the message stays one
/// printable line.
wx_result wx_error_set(wx_error *err, wx_result code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/// Prepends "prefix: " to an existing message (for context such as a camera name).
void wx_error_prefix(wx_error *err, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/// Copies `text` into `out` (cap bytes with the NUL) with control characters,
/// DEL, C1 controls and bytes that are not UTF-8 written as escapes (\n, \t,
/// \xNN); truncated to fit.
void wx_printable(const char *text, char *out, size_t cap);

/// Appends ", item" (or "item" to an empty list) to the list in `list` (cap
/// bytes with the NUL), for messages such as "(allowed: a, b, c)"; truncated
/// to fit.
void wx_list_append(char *list, size_t cap, const char *item);

/// Prints "weathering: warning: MESSAGE" on stderr (unless quiet), the message
/// made printable as wx_error_set's.
void wx_warn(bool quiet, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/// Prints "weathering: note: MESSAGE" on stderr (unless quiet), likewise.
void wx_note(bool quiet, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#endif
