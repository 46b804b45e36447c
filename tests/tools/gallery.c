// gallery.c: one contact sheet of weathering results for people to look at
// (`make gallery`, docs/images/gallery.png): a grid of cells, each a square
// picture of one model under one preset.
//
// A cell is either a PNG that another tool drew (render_texture: a TextureMap
// on its mesh) or a mask seen from its output camera, shaded here the way
// render_texture shades a texture, so that the two kinds look alike (values
// written as they are, as render_texture does): clay
// (0.80 0.78 0.72) blending to dirt (0.25 0.20 0.15) by t = min(1, value /
// white), lit by a headlight (0.25 + 0.75 |N.view|, N from the output
// camera's normal map), on a dark grey background; white is the larger of 1
// and the 99th percentile of the mask's positive values (wx_preview_white).
// Cells are scaled to CELL x CELL pixels (box filter, aspect kept), laid out
// in rows of `--columns`, with a 4-pixel gutter.
//
//   make build/tools/gallery
//   build/tools/gallery OUT.png --columns N [--cell CELL]
//       png:PICTURE.png | mask:MASK.exr:CHANNEL:NORMAL.exr | empty ...
//
// Exit status 2 on bad arguments or unreadable files, 1 on other failures.
#include <math.h>
#include <png.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/exr.h"
#include "io/png_preview.h"
#include "model/image.h"

static const float CLAY[3] = { 0.80f, 0.78f, 0.72f };
static const float DIRT[3] = { 0.25f, 0.20f, 0.15f };
static const float BACKGROUND[3] = { 0.15f, 0.15f, 0.15f };
static const float AMBIENT = 0.25f;
enum { GUTTER = 4 };

// An RGB picture, floats in [0, 1].
typedef struct picture {
    int width, height;
    float *rgb;
} picture;

static bool read_png(const char *path, picture *out)
{
    png_image image;
    memset(&image, 0, sizeof image);
    image.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&image, path)) {
        fprintf(stderr, "gallery: %s: %s\n", path, image.message);
        return false;
    }
    image.format = PNG_FORMAT_RGB;
    size_t n = (size_t)image.width * image.height;
    uint8_t *bytes = malloc(3 * n);
    out->rgb = malloc(3 * n * sizeof *out->rgb);
    if (bytes != NULL) {
        // libpng composites a picture with alpha over what the buffer holds:
        // the background, not whatever malloc left there.
        for (size_t i = 0; i < 3 * n; ++i) {
            bytes[i] = (uint8_t)(BACKGROUND[i % 3] * 255.0f + 0.5f);
        }
    }
    if (bytes == NULL || out->rgb == NULL ||
        !png_image_finish_read(&image, NULL, bytes, 0, NULL)) {
        fprintf(stderr, "gallery: %s: cannot read\n", path);
        free(bytes);
        free(out->rgb);
        return false;
    }
    for (size_t k = 0; k < 3 * n; ++k) {
        out->rgb[k] = bytes[k] / 255.0f;
    }
    free(bytes);
    out->width = (int)image.width;
    out->height = (int)image.height;
    return true;
}

static float *read_channel(const char *path, const char *name, int *w, int *h)
{
    const char *wanted[1] = { name };
    wx_image image;
    wx_error err;
    memset(&image, 0, sizeof image);
    if (wx_exr_read(path, wanted, 1, &image, &err) != WX_OK) {
        fprintf(stderr, "gallery: %s\n", err.message);
        return NULL;
    }
    float *plane = image.channels[0];
    image.channels[0] = NULL;
    *w = image.width;
    *h = image.height;
    wx_image_free(&image);
    return plane;
}

// "MASK.exr:CHANNEL:NORMAL.exr" shaded as render_texture shades a texture.
static bool shade_mask(char *spec, picture *out)
{
    char *channel = strchr(spec, ':');
    char *normal_path = channel != NULL ? strchr(channel + 1, ':') : NULL;
    if (normal_path == NULL) {
        fprintf(stderr, "gallery: mask:%s: expected MASK.exr:CHANNEL:NORMAL.exr\n", spec);
        return false;
    }
    *channel++ = '\0';
    *normal_path++ = '\0';
    int w = 0, h = 0, nw = 0, nh = 0, k1, k2;
    float *mask = read_channel(spec, channel, &w, &h);
    float *nx = read_channel(normal_path, "R", &nw, &nh);
    float *ny = read_channel(normal_path, "G", &k1, &k2);
    float *nz = read_channel(normal_path, "B", &k1, &k2);
    // The view direction: worldToCamera's z column (row vectors, z = depth).
    wx_image *header = calloc(1, sizeof *header);
    const wx_attr *to_camera = NULL;
    if (header != NULL && wx_exr_read_header(spec, header, NULL) == WX_OK) {
        to_camera = wx_image_find_attr(header, "worldToCamera");
    }
    float view[3] = { 0, 0, 0 };
    if (to_camera != NULL && to_camera->type == WX_ATTR_M44F) {
        float len = 0.0f;
        for (int k = 0; k < 3; ++k) {
            view[k] = to_camera->m44f[4 * k + 2];
            len += view[k] * view[k];
        }
        for (int k = 0; k < 3 && len > 0.0f; ++k) {
            view[k] /= sqrtf(len);
        }
    }
    free(header);
    bool ok = mask != NULL && nx != NULL && ny != NULL && nz != NULL && nw == w && nh == h &&
              to_camera != NULL;
    float p99 = 0.0f;
    wx_error err;
    if (ok && wx_preview_scale(mask, (size_t)w * h, &p99, &err) != WX_OK) {
        ok = false;
    }
    float white = wx_preview_white(p99);
    out->rgb = ok ? malloc((size_t)w * h * 3 * sizeof *out->rgb) : NULL;
    if (out->rgb != NULL) {
        out->width = w;
        out->height = h;
        for (size_t t = 0; t < (size_t)w * h; ++t) {
            float *px = &out->rgb[3 * t];
            // No surface: the normal map holds 0 there.
            float n = fabsf(nx[t] * view[0] + ny[t] * view[1] + nz[t] * view[2]);
            bool surface = isfinite(mask[t]) && (mask[t] != 0.0f || n > 0.0f);
            if (!surface) {
                memcpy(px, BACKGROUND, sizeof BACKGROUND);
                continue;
            }
            float v = fmaxf(mask[t], 0.0f) / white;
            float tt = v < 1.0f ? v : 1.0f;
            float light = AMBIENT + (1.0f - AMBIENT) * fminf(1.0f, n);
            for (int k = 0; k < 3; ++k) {
                px[k] = light * (CLAY[k] + tt * (DIRT[k] - CLAY[k]));
            }
        }
    }
    free(mask);
    free(nx);
    free(ny);
    free(nz);
    if (!ok || out->rgb == NULL) {
        fprintf(stderr, "gallery: %s: cannot shade with %s\n", spec, normal_path);
        return false;
    }
    return true;
}

// Box-filters `in` into a cell x cell square at (x0, y0) of `sheet` (aspect
// kept, centred, background around it).
static void place(const picture *in, int cell, float *sheet, int sheet_width, int x0, int y0)
{
    double scale = fmax((double)in->width, (double)in->height) / cell;
    int w = (int)(in->width / scale), h = (int)(in->height / scale);
    int ox = x0 + (cell - w) / 2, oy = y0 + (cell - h) / 2;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            int sx0 = (int)(x * scale), sx1 = (int)fmax(sx0 + 1, (x + 1) * scale);
            int sy0 = (int)(y * scale), sy1 = (int)fmax(sy0 + 1, (y + 1) * scale);
            double sum[3] = { 0, 0, 0 };
            int n = 0;
            for (int sy = sy0; sy < sy1 && sy < in->height; ++sy) {
                for (int sx = sx0; sx < sx1 && sx < in->width; ++sx) {
                    for (int k = 0; k < 3; ++k) {
                        sum[k] += in->rgb[3 * ((size_t)sy * in->width + sx) + k];
                    }
                    n++;
                }
            }
            float *px = &sheet[3 * ((size_t)(oy + y) * sheet_width + (ox + x))];
            for (int k = 0; k < 3 && n > 0; ++k) {
                px[k] = (float)(sum[k] / n);
            }
        }
    }
}

int main(int argc, char **argv)
{
    if (argc < 4 || strcmp(argv[2], "--columns") != 0) {
        fprintf(stderr, "usage: gallery OUT.png --columns N [--cell PIXELS] "
                        "png:FILE | mask:MASK.exr:CHANNEL:NORMAL.exr | empty ...\n");
        return 2;
    }
    int columns = atoi(argv[3]), cell = 256, first = 4;
    if (argc > 5 && strcmp(argv[4], "--cell") == 0) {
        cell = atoi(argv[5]);
        first = 6;
    }
    int count = argc - first;
    if (columns < 1 || cell < 16 || cell > 4096 || count < 1) {
        fprintf(stderr, "gallery: bad --columns, --cell or no cell\n");
        return 2;
    }
    int rows = (count + columns - 1) / columns;
    int width = columns * cell + (columns + 1) * GUTTER;
    int height = rows * cell + (rows + 1) * GUTTER;
    float *sheet = malloc((size_t)width * height * 3 * sizeof *sheet);
    uint8_t *bytes = malloc((size_t)width * height * 3);
    if (sheet == NULL || bytes == NULL) {
        fprintf(stderr, "gallery: out of memory\n");
        return 1;
    }
    for (size_t t = 0; t < (size_t)width * height; ++t) {
        sheet[3 * t] = sheet[3 * t + 1] = sheet[3 * t + 2] = 0.08f; // gutters
    }
    int status = 0;
    for (int c = 0; c < count; ++c) {
        int x0 = GUTTER + (c % columns) * (cell + GUTTER);
        int y0 = GUTTER + (c / columns) * (cell + GUTTER);
        for (int y = 0; y < cell; ++y) {
            for (int x = 0; x < cell; ++x) {
                memcpy(&sheet[3 * ((size_t)(y0 + y) * width + (x0 + x))], BACKGROUND,
                       sizeof BACKGROUND);
            }
        }
        char *spec = argv[first + c];
        picture pic = { 0, 0, NULL };
        bool ok = true;
        if (strncmp(spec, "png:", 4) == 0) {
            ok = read_png(spec + 4, &pic);
        } else if (strncmp(spec, "mask:", 5) == 0) {
            ok = shade_mask(spec + 5, &pic);
        } else if (strcmp(spec, "empty") != 0) {
            fprintf(stderr, "gallery: unknown cell '%s'\n", spec);
            ok = false;
        }
        if (!ok) {
            status = 2;
        } else if (pic.rgb != NULL) {
            place(&pic, cell, sheet, width, x0, y0);
        }
        free(pic.rgb);
    }
    for (size_t k = 0; k < (size_t)width * height * 3; ++k) {
        float v = sheet[k] < 0.0f ? 0.0f : sheet[k] > 1.0f ? 1.0f : sheet[k];
        bytes[k] = (uint8_t)lroundf(255.0f * v); // as render_texture writes its pictures
    }
    wx_error err;
    if (status == 0 && wx_png_write(argv[1], bytes, width, height, 3, &err) != WX_OK) {
        fprintf(stderr, "gallery: %s\n", err.message);
        status = 1;
    }
    free(sheet);
    free(bytes);
    return status;
}
