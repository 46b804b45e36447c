// png_preview.c: the mask's PNG preview (libpng, written to a temporary name and
// renamed).
#include "io/png_preview.h"

#include <errno.h>
#include <math.h>
#include <png.h>
#include <setjmp.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/atomic_file.h"
#include "model/maps.h"

// The k-th smallest of v[0..n-1] (Wirth's selection; v is reordered).
static float select_kth(float *v, ptrdiff_t n, ptrdiff_t k)
{
    ptrdiff_t lo = 0, hi = n - 1;
    while (lo < hi) {
        float pivot = v[k];
        ptrdiff_t i = lo, j = hi;
        do {
            while (v[i] < pivot) {
                i++;
            }
            while (pivot < v[j]) {
                j--;
            }
            if (i <= j) {
                float t = v[i];
                v[i] = v[j];
                v[j] = t;
                i++;
                j--;
            }
        } while (i <= j);
        if (j < k) {
            lo = i;
        }
        if (k < i) {
            hi = j;
        }
    }
    return v[k];
}

wx_result wx_preview_scale(const float *mask, size_t count, float *scale, wx_error *err)
{
    *scale = 0.0f;
    size_t n = 0;
    for (size_t t = 0; t < count; ++t) {
        n += mask[t] > 0.0f && mask[t] < INFINITY;
    }
    if (n == 0) {
        return WX_OK;
    }
    float *values = malloc(n * sizeof *values);
    if (values == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "preview: out of memory");
    }
    size_t k = 0;
    for (size_t t = 0; t < count; ++t) {
        if (mask[t] > 0.0f && mask[t] < INFINITY) {
            values[k++] = mask[t];
        }
    }
    *scale = select_kth(values, (ptrdiff_t)n, (ptrdiff_t)(0.99 * (double)(n - 1)));
    free(values);
    return WX_OK;
}

// A mask within [0, 1] (a derived mask, a normalised one, little dirt per
// square metre) shows its values as they are; only a larger one is stretched
// to its 99th percentile. Stretching every mask made a constant one (0.144
// everywhere) pure white, as if it were at its most (issue 24).
float wx_preview_white(float p99)
{
    return p99 > 1.0f ? p99 : 1.0f;
}

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
    (void)message; // the preview prints nothing but errors
}

// Everything libpng touches between setjmp and longjmp lives here, so that no
// local variable is modified after setjmp.
typedef struct png_writer {
    FILE *file;
    png_structp png;
    png_infop info;
    const uint8_t *pixels; // top-down rows of width * channels bytes
    int width, height, channels;
    png_failure failure;
} png_writer;

static bool write_rows(png_writer *w)
{
    if (setjmp(w->failure.jump)) {
        return false;
    }
    png_init_io(w->png, w->file);
    png_set_IHDR(w->png, w->info, (png_uint_32)w->width, (png_uint_32)w->height, 8,
                 w->channels == 2 ? PNG_COLOR_TYPE_GRAY_ALPHA : PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    // The preview is for looking: the fastest zlib level (docs/performance.md).
    png_set_compression_level(w->png, 1);
    png_set_filter(w->png, 0, PNG_FILTER_UP); // as small as the adaptive filters, twice as fast
    png_write_info(w->png, w->info);
    size_t row = (size_t)w->channels * (size_t)w->width;
    for (int j = 0; j < w->height; ++j) {
        png_write_row(w->png, (png_const_bytep)(w->pixels + (size_t)j * row));
    }
    png_write_end(w->png, NULL);
    return true;
}

wx_result wx_png_write(const char *path, const uint8_t *pixels, int width, int height,
                       int channels, wx_error *err)
{
    if (width < 1 || height < 1 || (channels != 2 && channels != 3)) {
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "%s: a PNG of %d x %d x %d", path, width,
                       height, channels);
    }
    char tmp[WX_PATH_MAX];
    wx_temp_path(path, tmp);
    png_writer w;
    memset(&w, 0, sizeof w);
    w.pixels = pixels;
    w.width = width;
    w.height = height;
    w.channels = channels;
    w.file = fopen(tmp, "wb");
    if (w.file == NULL) {
        return wx_fail(err, WX_CAUSE_IO, "%s: cannot write (%s)", path, strerror(errno));
    }
    wx_temp_created(tmp);
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

wx_result wx_preview_write_png(const char *path, const float *mask, const float *surface,
                               int width, int height, wx_error *err)
{
    if (width < 1 || height < 1) {
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "%s: empty preview", path);
    }
    size_t texels = (size_t)width * (size_t)height;
    float scale = 0.0f;
    wx_result result = wx_preview_scale(mask, texels, &scale, err);
    if (result != WX_OK) {
        return result;
    }
    uint8_t *pixels = malloc(2 * texels);
    if (pixels == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    const float inv_scale = 1.0f / wx_preview_white(scale);
    for (size_t t = 0; t < texels; ++t) {
        float value = mask[t] * inv_scale;
        value = value > 0.0f ? (value < 1.0f ? powf(value, 1.0f / 2.2f) : 1.0f) : 0.0f;
        bool has_surface = surface == NULL || !wx_depth_is_empty(surface[t]);
        pixels[2 * t] = (uint8_t)lrintf(255.0f * value);
        pixels[2 * t + 1] = has_surface ? 255 : 0;
    }
    result = wx_png_write(path, pixels, width, height, 2, err);
    free(pixels);
    return result;
}
