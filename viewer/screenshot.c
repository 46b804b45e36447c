// screenshot.c: framebuffer to PNG (screenshot.h), written by io/png_preview.c.
#include "screenshot.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gl.h"
#include "io/png_preview.h"

wx_result vw_screenshot_write(const char *path, int width, int height, wx_error *err)
{
    if (width < 1 || height < 1) {
        return wx_fail(err, WX_CAUSE_RENDERER, "%s: the window is empty", path);
    }
    size_t row = 3 * (size_t)width;
    uint8_t *bottom_up = malloc(row * (size_t)height);
    uint8_t *top_down = malloc(row * (size_t)height);
    if (bottom_up == NULL || top_down == NULL) {
        free(bottom_up);
        free(top_down);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_BACK);
    glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, bottom_up);
    // glReadPixels returns rows bottom-up: the one flip (docs/design.md section 2).
    for (int j = 0; j < height; ++j) {
        memcpy(top_down + (size_t)j * row, bottom_up + (size_t)(height - 1 - j) * row, row);
    }
    free(bottom_up);
    wx_result r = wx_png_write(path, top_down, width, height, 3, err);
    free(top_down);
    return r;
}
