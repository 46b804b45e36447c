// screenshot.c: framebuffer to PNG (screenshot.h), with libpng.
#include "screenshot.h"

#include <errno.h>
#include <png.h>
#include <setjmp.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/atomic_file.h"
#include "gl.h"
#include "core/limits.h"

typedef struct png_failure {
    jmp_buf jump;
    char message[256];
} png_failure;

static void on_png_error(png_structp png, png_const_charp message)
{
    png_failure *failure = png_get_error_ptr(png);
    snprintf(failure->message, sizeof failure->message, "%s", message);
    longjmp(failure->jump, 1);
}

static void on_png_warning(png_structp png, png_const_charp message)
{
    (void)png;
    (void)message;
}

// Everything libpng touches between setjmp and longjmp lives here, so that no
// local variable is modified after setjmp.
typedef struct png_writer {
    FILE *file;
    png_structp png;
    png_infop info;
    const uint8_t *pixels; // top-down RGB rows
    int width, height;
    png_failure failure;
} png_writer;

static bool write_rows(png_writer *w)
{
    if (setjmp(w->failure.jump)) {
        return false;
    }
    png_init_io(w->png, w->file);
    png_set_IHDR(w->png, w->info, (png_uint_32)w->width, (png_uint_32)w->height, 8,
                 PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_write_info(w->png, w->info);
    for (int j = 0; j < w->height; ++j) {
        png_write_row(w->png, (png_const_bytep)(w->pixels + (size_t)j * 3 * (size_t)w->width));
    }
    png_write_end(w->png, NULL);
    return true;
}

static wx_result write_png(const char *path, const uint8_t *pixels, int width, int height,
                           wx_error *err)
{
    char tmp[WX_PATH_MAX];
    wx_temp_path(path, tmp);
    png_writer w;
    memset(&w, 0, sizeof w);
    w.pixels = pixels;
    w.width = width;
    w.height = height;
    w.file = fopen(tmp, "wb");
    if (w.file == NULL) {
        return wx_fail(err, WX_CAUSE_IO, "%s: cannot write (%s)", path, strerror(errno));
    }
    w.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &w.failure, on_png_error,
                                    on_png_warning);
    w.info = w.png != NULL ? png_create_info_struct(w.png) : NULL;
    bool ok = w.info != NULL && write_rows(&w);
    if (!ok && w.failure.message[0] == '\0') {
        snprintf(w.failure.message, sizeof w.failure.message, "out of memory");
    }
    png_destroy_write_struct(&w.png, &w.info);
    int closed = fclose(w.file);
    if (!ok) {
        unlink(tmp);
        return wx_fail(err, WX_CAUSE_IO, "%s: cannot write PNG (%s)", path, w.failure.message);
    }
    if (closed != 0) {
        int saved = errno;
        unlink(tmp);
        return wx_fail(err, WX_CAUSE_IO, "%s: cannot write (%s)", path, strerror(saved));
    }
    return wx_atomic_commit(tmp, path, err);
}

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
    wx_result r = write_png(path, top_down, width, height, err);
    free(top_down);
    return r;
}
