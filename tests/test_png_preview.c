// test_png_preview.c: the mask's PNG preview (io/png_preview.h): its white
// point (the 99th percentile of the positive values, at least 1), its grey
// levels, and a preview of no surface.
#include <math.h>
#include <png.h>
#include <string.h>

#include "core/limits.h"
#include "ensure.h"
#include "io/png_preview.h"

TEST(preview_scale_is_the_99th_percentile)
{
    // 200 positive values 1..200 and zeros: element floor(0.99 * 199) = 197 of
    // the sorted values, i.e. 198.
    float values[300];
    for (int k = 0; k < 300; ++k) {
        values[k] = k < 100 ? 0.0f : (float)((k * 37) % 200 + 1);
    }
    float scale;
    ENSURE(wx_preview_scale(values, 300, &scale, NULL) == WX_OK);
    ENSURE(scale == 198.0f);
    ENSURE(wx_preview_scale(values, 100, &scale, NULL) == WX_OK);
    ENSURE(scale == 0.0f);
    // Preview of no surface anywhere: written, fully transparent.
    char path[WX_PATH_MAX];
    snprintf(path, sizeof path, "%s/empty.png", ensure_tmpdir());
    float depth[4] = { INFINITY, INFINITY, INFINITY, INFINITY };
    ENSURE(wx_preview_write_png(path, values, depth, 2, 2, NULL) == WX_OK);
    png_image image;
    memset(&image, 0, sizeof image);
    image.version = PNG_IMAGE_VERSION;
    ENSURE(png_image_begin_read_from_file(&image, path) != 0);
    image.format = PNG_FORMAT_GA;
    unsigned char pixels[8];
    ENSURE(png_image_finish_read(&image, NULL, pixels, 0, NULL) != 0);
    ENSURE(pixels[1] == 0 && pixels[3] == 0 && pixels[5] == 0 && pixels[7] == 0);
}

// Issue 24: a constant mask (0.144 everywhere) had a pure white preview, as if
// it were at its most. The white point is the larger of 1 and the 99th
// percentile: a mask within [0, 1] shows its values, grey =
// round(255 * v^(1/2.2)); a larger one is stretched to its 99th percentile.
static bool preview_grey(const char *name, const float *values, int count, unsigned char *grey)
{
    char path[WX_PATH_MAX];
    snprintf(path, sizeof path, "%s/%s", ensure_tmpdir(), name);
    if (wx_preview_write_png(path, values, NULL, count, 1, NULL) != WX_OK) {
        return false;
    }
    png_image image;
    memset(&image, 0, sizeof image);
    image.version = PNG_IMAGE_VERSION;
    if (png_image_begin_read_from_file(&image, path) == 0) {
        return false;
    }
    image.format = PNG_FORMAT_GRAY;
    return png_image_finish_read(&image, NULL, grey, 0, NULL) != 0;
}

TEST(constant_mask_preview_shows_its_value)
{
    float constant[16], ramp[16], large[16];
    for (int k = 0; k < 16; ++k) {
        constant[k] = 0.144f;
        ramp[k] = (float)k / 30.0f; // 0 to 0.5
        large[k] = 5.0f * (float)(k + 1);
    }
    unsigned char grey[16];
    ENSURE(preview_grey("constant.png", constant, 16, grey));
    // 255 * 0.144^(1/2.2) = 105.7
    printf("        constant 0.144: grey %d (was 255)\n", grey[0]);
    for (int k = 0; k < 16; ++k) {
        ENSURE(grey[k] == 106);
    }
    ENSURE(preview_grey("ramp.png", ramp, 16, grey));
    ENSURE(grey[0] == 0);
    ENSURE(grey[15] == 186); // 255 * 0.5^(1/2.2) = 186.1
    ENSURE(grey[3] == 90);   // 255 * 0.1^(1/2.2) = 89.5
    // Above 1: stretched as before, the 99th percentile (element 14 of 16: 75) white.
    ENSURE(preview_grey("large.png", large, 16, grey));
    ENSURE(grey[14] == 255 && grey[15] == 255);
    ENSURE(grey[0] == 74); // 255 * (5/75)^(1/2.2) = 74.5
    ENSURE(wx_preview_white(0.144f) == 1.0f && wx_preview_white(75.0f) == 75.0f);
}

int main(void)
{
    RUN(preview_scale_is_the_99th_percentile);
    RUN(constant_mask_preview_shows_its_value);
    return ensure_summary();
}
