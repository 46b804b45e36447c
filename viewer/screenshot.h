// screenshot.h: the framebuffer as a PNG (--screenshot), written to a temporary
// name beginning with '.' and renamed (docs/design.md section 7).
#ifndef VW_SCREENSHOT_H
#define VW_SCREENSHOT_H

#include "core/error.h"

/// Reads the back buffer of the current context (width x height pixels, RGB),
/// turns glReadPixels' bottom-up rows into top-down ones, and writes `path`.
wx_result vw_screenshot_write(const char *path, int width, int height, wx_error *err);

#endif
