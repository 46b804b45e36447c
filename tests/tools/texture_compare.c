// texture_compare.c: how much two TextureMaps (or masks) of the same layout
// differ, relative to their mean, at several block sizes: the number issue 25
// asks for when it compares two seeds (the noise) with two orientations of the
// same model (what should be nothing but noise).
//
// Over the texels both files mark `seen` (every texel when a file has no `seen`
// channel), the channel's values are averaged in blocks of k x k texels (a
// block counts when at least half of it is seen in both); the tool prints, for
// k = 1, 2, 4, 8, 16, 32, the RMS of the blocks' differences divided by the mean
// of both files over the common texels, and the number of blocks.
//
//   make build/tools/texture_compare
//   build/tools/texture_compare A.exr B.exr [CHANNEL]      (default channel Y)
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../block_rms.h"
#include "io/exr.h"
#include "model/image.h"

static float *read_channel(const char *path, const char *name, int *w, int *h, bool optional)
{
    const char *wanted[1] = { name };
    wx_image image;
    wx_error err;
    memset(&image, 0, sizeof image);
    if (wx_exr_read(path, wanted, 1, &image, &err) != WX_OK) {
        if (!optional) {
            fprintf(stderr, "%s\n", err.message);
        }
        return NULL;
    }
    *w = image.width;
    *h = image.height;
    float *plane = image.channels[0];
    image.channels[0] = NULL;
    wx_image_free(&image);
    return plane;
}

int main(int argc, char **argv)
{
    if (argc != 3 && argc != 4) {
        fprintf(stderr, "usage: texture_compare A.exr B.exr [CHANNEL]\n");
        return 2;
    }
    const char *channel = argc == 4 ? argv[3] : "Y";
    int wa = 0, ha = 0, wb = 0, hb = 0, w2, h2;
    float *a = read_channel(argv[1], channel, &wa, &ha, false);
    float *b = read_channel(argv[2], channel, &wb, &hb, false);
    if (a == NULL || b == NULL || wa != wb || ha != hb) {
        fprintf(stderr, "texture_compare: two files of the same size with channel %s needed\n",
                channel);
        return 2;
    }
    float *sa = read_channel(argv[1], "seen", &w2, &h2, true);
    float *sb = read_channel(argv[2], "seen", &w2, &h2, true);
    int w = wa, h = ha;
    long count = 0;
    double mean = wx_block_mean(a, b, sa, sb, w, h, &count);
    printf("texels %ld, mean %.6g\n", count, mean);
    for (int k = 1; k <= 32; k *= 2) {
        long blocks = 0;
        double rms = wx_block_rms(a, b, sa, sb, w, h, k, &blocks);
        printf("block %2d: rms/mean %.4f over %ld blocks\n", k, mean > 0.0 ? rms / mean : 0.0,
               blocks);
    }
    free(a);
    free(b);
    free(sa);
    free(sb);
    return 0;
}
