// preview_noise.c: how speckled a mask preview is, as one number a person can
// compare between two versions of the same picture.
//
// For every pixel whose alpha and whose eight neighbours' alpha are all 255
// (inside the mask's coverage, away from its silhouette) and whose neighbours'
// mean grey g is at least --floor (default 8 of 255: a clean region has no
// relative noise to speak of), the pixel's deviation is |v - g| / g, with v its
// own grey. The tool prints the median and the 90th percentile of those
// deviations, and how many pixels they cover. Monte Carlo speckle makes every
// pixel differ from its neighbours; a smooth mask with sharp edges keeps the
// median near zero (an edge is a thin line of pixels, far from the median).
//
//   make build/tools/preview_noise
//   build/tools/preview_noise PREVIEW.png [--floor G]
//
// The PNG must be 8-bit grey + alpha, as `gather` writes its previews.
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int compare_floats(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    if (argc != 2 && !(argc == 4 && strcmp(argv[2], "--floor") == 0)) {
        fprintf(stderr, "usage: preview_noise PREVIEW.png [--floor G]\n");
        return 2;
    }
    double floor_grey = argc == 4 ? atof(argv[3]) : 8.0;

    png_image image;
    memset(&image, 0, sizeof image);
    image.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&image, argv[1])) {
        fprintf(stderr, "%s: %s\n", argv[1], image.message);
        return 2;
    }
    image.format = PNG_FORMAT_GA;
    size_t w = image.width, h = image.height;
    unsigned char *px = malloc(w * h * 2);
    float *dev = malloc(w * h * sizeof *dev);
    if (!px || !dev || !png_image_finish_read(&image, NULL, px, 0, NULL)) {
        fprintf(stderr, "%s: %s\n", argv[1], px && dev ? image.message : "out of memory");
        free(px);
        free(dev);
        return 2;
    }

    size_t n = 0;
    for (size_t y = 1; y + 1 < h; ++y) {
        for (size_t x = 1; x + 1 < w; ++x) {
            int inside = 1;
            double sum = 0.0;
            for (int dy = -1; dy <= 1 && inside; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const unsigned char *q = px + 2 * ((y + dy) * w + (x + dx));
                    if (q[1] != 255) {
                        inside = 0;
                        break;
                    }
                    if (dx != 0 || dy != 0)
                        sum += q[0];
                }
            }
            double g = sum / 8.0;
            if (!inside || g < floor_grey)
                continue;
            double v = px[2 * (y * w + x)];
            dev[n++] = (float)(v > g ? v - g : g - v) / (float)g;
        }
    }
    if (n == 0) {
        printf("%s: no pixel inside the coverage above grey %g\n", argv[1], floor_grey);
    } else {
        qsort(dev, n, sizeof *dev, compare_floats);
        printf("%s: median deviation %.1f%%, 90th percentile %.1f%%, over %zu pixels\n", argv[1],
               100.0 * dev[n / 2], 100.0 * dev[n * 9 / 10], n);
    }
    free(px);
    free(dev);
    return 0;
}
