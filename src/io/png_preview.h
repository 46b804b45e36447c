// png_preview.h: an 8-bit PNG preview of a mask (libpng), scaled to be readable:
// grey = min(1, value / white)^(1/2.2), where white is the larger of 1 and the
// 99th percentile of the mask's positive values (p99): a mask within [0, 1] is
// shown as it is (a constant 0.144 is grey 106, not white), a larger one
// stretched so that its top 1% is white; alpha 0 where the camera sees no
// surface (docs/mask.md, "The PNG preview").
#ifndef WX_PNG_PREVIEW_H
#define WX_PNG_PREVIEW_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"

/// The 99th percentile of the positive finite values (sorted ascending, element
/// floor(0.99 * (n - 1))), or 0 when there are none: the preview's white point
/// when it is above 1. Returns WX_FAIL when out of memory.
wx_result wx_preview_scale(const float *mask, size_t count, float *scale, wx_error *err);

/// Writes `path` atomically as an 8-bit PNG of `height` top-down rows of
/// width * channels bytes: 2 channels (grey, alpha) or 3 (RGB). The preview and
/// the viewer's screenshots are written this way.
wx_result wx_png_write(const char *path, const uint8_t *pixels, int width, int height,
                       int channels, wx_error *err);

/// The preview's white point for a mask whose wx_preview_scale is `p99`: the
/// larger of 1 and p99.
float wx_preview_white(float p99);

/// Writes `path` atomically as 8-bit grey + alpha, white at wx_preview_white.
/// `surface` (may be NULL: all opaque) holds width*height depths; texels
/// without a surface (maps.h) get alpha 0.
wx_result wx_preview_write_png(const char *path, const float *mask, const float *surface,
                               int width, int height, wx_error *err);

#endif
