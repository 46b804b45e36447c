// exr_channel.c: one channel of an EXR, as raw floats or as a PNG a person can
// look at, for analysing masks and maps outside the program.
//
//   make build/tools/exr_channel
//   build/tools/exr_channel FILE.exr CHANNEL OUT.f32     raw float32, rows top down;
//                                                       prints "WIDTH HEIGHT"
//   build/tools/exr_channel FILE.exr CHANNEL OUT.png [--max M]
//                                                       the preview's scaling
//                                                       (white at M, default the
//                                                       99th percentile)
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/exr.h"
#include "io/png_preview.h"
#include "model/image.h"

int main(int argc, char **argv)
{
    if (argc != 4 && !(argc == 6 && strcmp(argv[4], "--max") == 0)) {
        fprintf(stderr, "usage: exr_channel FILE.exr CHANNEL OUT.f32|OUT.png [--max M]\n");
        return 2;
    }
    const char *wanted[1] = { argv[2] };
    wx_image image;
    wx_error err;
    memset(&image, 0, sizeof image);
    if (wx_exr_read(argv[1], wanted, 1, &image, &err) != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
        return 2;
    }
    size_t n = (size_t)image.width * (size_t)image.height;
    const char *out = argv[3];
    size_t len = strlen(out);
    int status = 0;
    if (len > 4 && strcmp(out + len - 4, ".png") == 0) {
        float *scaled = malloc(n * sizeof *scaled);
        float max = argc == 6 ? (float)atof(argv[5]) : 0.0f;
        if (max <= 0.0f && wx_preview_scale(image.channels[0], n, &max, &err) != WX_OK) {
            max = 1.0f;
        }
        // wx_preview_write_png scales by the 99th percentile itself: hand it
        // values clamped to [0, max] with one texel at max, so that its
        // scale is max.
        for (size_t i = 0; i < n; ++i) {
            float v = image.channels[0][i];
            scaled[i] = isfinite(v) ? fminf(fmaxf(v, 0.0f), max) : 0.0f;
        }
        if (wx_preview_write_png(out, scaled, NULL, image.width, image.height, &err) != WX_OK) {
            fprintf(stderr, "%s\n", err.message);
            status = 1;
        }
        free(scaled);
    } else {
        FILE *f = fopen(out, "wb");
        if (f == NULL || fwrite(image.channels[0], sizeof(float), n, f) != n || fclose(f) != 0) {
            fprintf(stderr, "%s: cannot write\n", out);
            status = 1;
        }
    }
    printf("%d %d\n", image.width, image.height);
    wx_image_free(&image);
    return status;
}
