// image.c: float images in memory: planes, names and header attributes (image.h).
#include "model/image.h"
#include "core/big_alloc.h"

#include <assert.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

wx_result wx_image_alloc(wx_image *image, int width, int height, int channel_count,
                         const char *const *names, wx_error *err)
{
    memset(image, 0, sizeof *image);
    if (width <= 0 || height <= 0 || width > WX_MAP_MAX_SIDE || height > WX_MAP_MAX_SIDE ||
        (long long)width * height > WX_MAP_MAX_TEXELS) {
        return wx_fail(err, WX_CAUSE_MAP_SIZE, "%d x %d exceeds the largest map size %d x %d",
                            width, height, WX_MAP_MAX_SIDE, WX_MAP_MAX_SIDE);
    }
    if (channel_count < 1 || channel_count > WX_IMAGE_MAX_CHANNELS) {
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "%d channels (1 to %d supported)", channel_count,
                            WX_IMAGE_MAX_CHANNELS);
    }
    for (int c = 0; c < channel_count; c++) {
        if (names == NULL || names[c] == NULL || names[c][0] == '\0' ||
            strlen(names[c]) >= WX_NAME_MAX) {
            return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "channel %d: missing or too long name", c);
        }
    }
    size_t texels = (size_t)width * (size_t)height;
    for (int c = 0; c < channel_count; c++) {
        image->channels[c] = wx_big_calloc(texels, sizeof(float));
        if (image->channels[c] == NULL) {
            wx_image_free(image);
            return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory for %d x %d x %d floats",
                           width, height, channel_count);
        }
        snprintf(image->channel_names[c], sizeof image->channel_names[c], "%s", names[c]);
    }
    image->width = width;
    image->height = height;
    image->channel_count = channel_count;
    return WX_OK;
}

// The attribute named `name`, added if new. Too many attributes is a programmer error.
static wx_attr *attr_slot(wx_image *image, const char *name)
{
    assert(strlen(name) < WX_NAME_MAX);
    for (int a = 0; a < image->attr_count; a++) {
        if (strcmp(image->attrs[a].name, name) == 0) {
            return &image->attrs[a];
        }
    }
    assert(image->attr_count < WX_IMAGE_MAX_ATTRS);
    if (image->attr_count >= WX_IMAGE_MAX_ATTRS) {
        return NULL;
    }
    wx_attr *attr = &image->attrs[image->attr_count++];
    memset(attr, 0, sizeof *attr);
    snprintf(attr->name, sizeof attr->name, "%s", name);
    return attr;
}

void wx_image_set_m44f(wx_image *image, const char *name, const float m[16])
{
    wx_attr *attr = attr_slot(image, name);
    if (attr != NULL) {
        attr->type = WX_ATTR_M44F;
        memcpy(attr->m44f, m, sizeof attr->m44f);
    }
}

void wx_image_set_string(wx_image *image, const char *name, const char *value)
{
    wx_attr *attr = attr_slot(image, name);
    if (attr != NULL) {
        attr->type = WX_ATTR_STRING;
        snprintf(attr->string, sizeof attr->string, "%s", value);
    }
}

const wx_attr *wx_image_find_attr(const wx_image *image, const char *name)
{
    for (int a = 0; a < image->attr_count; a++) {
        if (strcmp(image->attrs[a].name, name) == 0) {
            return &image->attrs[a];
        }
    }
    return NULL;
}

void wx_image_free(wx_image *image)
{
    for (int c = 0; c < WX_IMAGE_MAX_CHANNELS; c++) {
        free(image->channels[c]);
    }
    memset(image, 0, sizeof *image);
}

wx_result wx_image_check_finite(const wx_image *image, const char *path, wx_error *err)
{
    size_t texels = (size_t)image->width * (size_t)image->height;
    int64_t bad = 0;
    int first_channel = -1;
    size_t first_texel = 0;
    for (int c = 0; c < image->channel_count; ++c) {
        const float *plane = image->channels[c];
        for (size_t t = 0; plane != NULL && t < texels; ++t) {
            if (!isfinite(plane[t])) {
                if (bad++ == 0) {
                    first_channel = c;
                    first_texel = t;
                }
            }
        }
    }
    if (bad == 0) {
        return WX_OK;
    }
    float v = image->channels[first_channel][first_texel];
    return wx_fail(err, WX_CAUSE_INTERNAL,
                   "%s: not written: channel %s holds %s at texel (%zu, %zu), and %lld values "
                   "in all are not finite numbers (an amount overflowed single precision; "
                   "lower the scene's amounts, see docs/reliability.md)",
                   path, image->channel_names[first_channel],
                   isnan(v) ? "NaN" : (v > 0.0f ? "+inf" : "-inf"),
                   first_texel % (size_t)image->width, first_texel / (size_t)image->width,
                   (long long)bad);
}
