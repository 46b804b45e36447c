// error.h: result codes and messages for everything that touches files, XML or GL.
// A function that can fail on input returns a wx_result and fills a wx_error whose
// message names the file (and the XML line), ready to print as it is: one
// printable line, whatever bytes the files it quotes hold.
#ifndef WX_ERROR_H
#define WX_ERROR_H

#include <stdbool.h>
#include <stddef.h>

/// Exit-status-compatible result codes (docs/design.md section 6).
typedef enum wx_result {
    WX_OK = 0,
    WX_FAIL = 1,      ///< other failure: out of memory, I/O error, GL failure
    WX_BAD_INPUT = 2, ///< bad usage or bad input: the message names the file
} wx_result;

/// Every cause of failure with the result (exit status) it gives and a short
/// description: one list makes the enum and the tables (sokol's X-macro list;
/// cgltf's cgltf_result names each cause the same way). The message says what
/// happened to whom; the cause is what code and tests branch on.
#define WX_CAUSES(X)                                                                          \
    X(NONE, WX_OK, "no error")                                                                \
    X(OUT_OF_MEMORY, WX_FAIL, "out of memory")                                                \
    X(IO, WX_FAIL, "a file could not be read or written")                                     \
    X(RENDERER, WX_FAIL, "the OpenGL renderer failed")                                        \
    X(THREAD, WX_FAIL, "a thread could not be started")                                       \
    X(INTERNAL, WX_FAIL, "a programming error")                                               \
    X(BAD_ARGUMENT, WX_BAD_INPUT, "a function called with arguments it does not take")       \
    X(USAGE, WX_BAD_INPUT, "bad command line")                                                \
    X(UNREADABLE, WX_BAD_INPUT, "an input file that cannot be opened or read")               \
    X(FILE_MISSING, WX_BAD_INPUT, "a file that is not there")                                 \
    X(NOT_REGULAR_FILE, WX_BAD_INPUT, "a folder, a FIFO, a device or a link loop")            \
    X(PATH_TOO_LONG, WX_BAD_INPUT, "a path or name too long")                                 \
    X(XML_SYNTAX, WX_BAD_INPUT, "a file that is not well-formed XML")                         \
    X(XML_CONTENT, WX_BAD_INPUT, "text, an entity or a processing instruction in a scene")    \
    X(UNKNOWN_NAME, WX_BAD_INPUT, "an element or attribute the format does not have")         \
    X(MISSING, WX_BAD_INPUT, "a required element or attribute is absent")                    \
    X(DUPLICATE, WX_BAD_INPUT, "a name or an element given twice")                            \
    X(BAD_VALUE, WX_BAD_INPUT, "a value that is not of its type or out of its range")        \
    X(TOO_MANY, WX_BAD_INPUT, "more of something than the program takes")                    \
    X(BAD_CAMERA, WX_BAD_INPUT, "a camera whose matrices cannot be used")                     \
    X(BAD_MAP, WX_BAD_INPUT, "a map file that is not a usable EXR")                           \
    X(MAP_SIZE, WX_BAD_INPUT, "maps whose sizes disagree or exceed the limits")              \
    X(MAP_VALUE, WX_BAD_INPUT, "a map holding NaN or infinities where it must not")          \
    X(BAD_MESH, WX_BAD_INPUT, "a mesh file that cannot be imported or is refused")           \
    X(UNMATCHED_MATERIAL, WX_BAD_INPUT, "a material that no <Surface> matches or lacks colours") \
    X(MEMORY_LIMIT, WX_BAD_INPUT, "a run that needs more memory than is available")          \
    X(OUTPUT_CONFLICT, WX_BAD_INPUT, "an output that would replace an input or a non-file")  \
    X(MISSING_PHASE, WX_BAD_INPUT, "a phase run before the one whose files it reads")        \
    X(BAD_SCENE, WX_BAD_INPUT, "a scene that is inconsistent as a whole")                   \
    X(NO_UVS, WX_BAD_INPUT, "a mesh without the texture coordinates a <TextureMap> reads")

/// The causes: WX_CAUSE_NONE, WX_CAUSE_OUT_OF_MEMORY, ...
typedef enum wx_cause {
#define WX_CAUSE_ENUM(name, result, text) WX_CAUSE_##name,
    WX_CAUSES(WX_CAUSE_ENUM)
#undef WX_CAUSE_ENUM
    WX_CAUSE_COUNT
} wx_cause;

#define WX_ERROR_MAX 1024

/// What went wrong: the cause for code, the message for people, e.g.
/// "scene.xml:12: <Gravity> acceleration is not a number" (WX_CAUSE_BAD_VALUE).
typedef struct wx_error {
    wx_cause cause;
    char message[WX_ERROR_MAX];
} wx_error;

/// The result (exit status) a cause gives.
wx_result wx_cause_result(wx_cause cause);

/// The cause's name as in the enum without its prefix ("BAD_VALUE").
const char *wx_cause_name(wx_cause cause);

/// Records `cause` and the formatted message in err (when err is not NULL) and
/// returns the cause's result. Control characters (a newline from `&#10;` in an
/// attribute, an ESC in a mesh's material name) are written as escapes (\n,
/// \x1b), so the message stays one printable line.
wx_result wx_fail(wx_error *err, wx_cause cause, const char *fmt, ...)
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
