// test_error.c: causes and their exit statuses, messages kept to one printable
// line and to WX_ERROR_MAX bytes with their reason (core/error.c).
#include <string.h>

#include "core/error.h"
#include "ensure.h"

TEST(every_cause_has_its_result_and_name)
{
    // The exit statuses of docs/design.md section 6: 1 for failures of the
    // machine, 2 for bad usage and bad input.
    ENSURE(wx_cause_result(WX_CAUSE_NONE) == WX_OK);
    ENSURE(wx_cause_result(WX_CAUSE_OUT_OF_MEMORY) == WX_FAIL);
    ENSURE(wx_cause_result(WX_CAUSE_IO) == WX_FAIL);
    ENSURE(wx_cause_result(WX_CAUSE_RENDERER) == WX_FAIL);
    ENSURE(wx_cause_result(WX_CAUSE_INTERNAL) == WX_FAIL);
    ENSURE(wx_cause_result(WX_CAUSE_USAGE) == WX_BAD_INPUT);
    ENSURE(wx_cause_result(WX_CAUSE_BAD_VALUE) == WX_BAD_INPUT);
    ENSURE(wx_cause_result(WX_CAUSE_MEMORY_LIMIT) == WX_BAD_INPUT);
    ENSURE(wx_cause_result(WX_CAUSE_COUNT) == WX_FAIL); // not a cause
    int bad_input = 0;
    for (int c = 0; c < WX_CAUSE_COUNT; ++c) {
        const char *name = wx_cause_name((wx_cause)c);
        ENSURE(name[0] >= 'A' && name[0] <= 'Z');
        for (int d = 0; d < c; ++d) {
            ENSURE(strcmp(name, wx_cause_name((wx_cause)d)) != 0);
        }
        bad_input += wx_cause_result((wx_cause)c) == WX_BAD_INPUT;
    }
    ENSURE(strcmp(wx_cause_name(WX_CAUSE_BAD_VALUE), "BAD_VALUE") == 0);
    ENSURE(bad_input == WX_CAUSE_COUNT - 6); // NONE and the five failures
}

TEST(fail_records_cause_and_escaped_message)
{
    wx_error err = { 0 };
    ENSURE(wx_fail(&err, WX_CAUSE_BAD_VALUE, "%s:%d: x=\"%s\"", "s.xml", 3, "1\nfake\033[31m") ==
           WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_VALUE);
    ENSURE(strcmp(err.message, "s.xml:3: x=\"1\\nfake\\x1b[31m\"") == 0);
    ENSURE(wx_fail(NULL, WX_CAUSE_IO, "ignored") == WX_FAIL); // no error to fill
    // UTF-8 passes as it is; a byte that is not UTF-8 is escaped.
    ENSURE(wx_fail(&err, WX_CAUSE_BAD_MESH, "caf\xc3\xa9 \xe9") == WX_BAD_INPUT);
    ENSURE(strcmp(err.message, "caf\xc3\xa9 \\xe9") == 0);
    wx_error_prefix(&err, "%s:%d", "scene.xml", 12);
    ENSURE(strcmp(err.message, "scene.xml:12: caf\xc3\xa9 \\xe9") == 0);
    ENSURE_CAUSE(err, BAD_MESH); // a prefix keeps the cause
}

TEST(long_messages_keep_their_reason)
{
    // A 3000-character path (a deep --out) and the reason after it.
    char path[3001];
    memset(path, 'p', 3000);
    path[0] = '/';
    memcpy(path + 2000, "\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9", 8); // UTF-8 where the cut may fall
    path[3000] = '\0';
    wx_error err = { 0 };
    wx_fail(&err, WX_CAUSE_IO, "%s: cannot create folder (%s)", path, "Not a directory");
    size_t len = strlen(err.message);
    ENSURE(len < WX_ERROR_MAX && len > WX_ERROR_MAX - 16);
    ENSURE(err.message[0] == '/');
    ENSURE(ensure_contains(err.message, "pppp ... pppp"));
    const char *end = ": cannot create folder (Not a directory)";
    ENSURE(strcmp(err.message + len - strlen(end), end) == 0);
    // Nowhere is a UTF-8 sequence cut: every lead byte has its continuation.
    for (size_t i = 0; i < len; ++i) {
        unsigned char c = (unsigned char)err.message[i];
        if (c == 0xc3) {
            ENSURE(i + 1 < len && (unsigned char)err.message[i + 1] == 0xa9);
        } else if (c == 0xa9) {
            ENSURE(i > 0 && (unsigned char)err.message[i - 1] == 0xc3);
        }
    }
    // Escapes count: 2000 control characters become 8000 bytes, still fitted.
    char controls[2001];
    memset(controls, '\001', 2000);
    controls[2000] = '\0';
    wx_fail(&err, WX_CAUSE_BAD_VALUE, "name=\"%s\" is not a plain name", controls);
    len = strlen(err.message);
    ENSURE(len < WX_ERROR_MAX);
    ENSURE(strncmp(err.message, "name=\"\\x01", 10) == 0);
    ENSURE(ensure_contains(err.message, "\" is not a plain name"));
    ENSURE(strchr(err.message, '\001') == NULL);
    // A prefix on a full message: the prefix and the reason both stay.
    wx_fail(&err, WX_CAUSE_BAD_MESH, "%s: refers to 'x', outside the mesh's folder", path);
    wx_error_prefix(&err, "%s:%d", "scene.xml", 7);
    ENSURE(strncmp(err.message, "scene.xml:7: /ppp", 17) == 0);
    ENSURE(ensure_contains(err.message, "refers to 'x', outside the mesh's folder"));
    ENSURE(strlen(err.message) < WX_ERROR_MAX);
}

int main(void)
{
    RUN(every_cause_has_its_result_and_name);
    RUN(fail_records_cause_and_escaped_message);
    RUN(long_messages_keep_their_reason);
    return ensure_summary();
}
