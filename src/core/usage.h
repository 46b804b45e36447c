// usage.h: what the programs (weathering, weathering-viewer) share on their
// command lines: the one-line usage error and the parsing of whole numbers.
#ifndef WX_USAGE_H
#define WX_USAGE_H

#include <stdbool.h>
#include <stdint.h>

/// Prints "PROGRAM: <fmt with detail>" and "Try 'PROGRAM --help'." on stderr;
/// returns WX_BAD_INPUT (exit status 2).
int wx_usage_error(const char *program, const char *fmt, const char *detail);

/// A whole decimal number in [lo, hi] (digits only, no sign, no spaces).
bool wx_parse_whole(const char *text, uint64_t lo, uint64_t hi, uint64_t *out);

#endif
