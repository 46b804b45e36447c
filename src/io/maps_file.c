// maps_file.c: loads the four maps of one camera (depth, normal, impact, dirt)
// from their EXR files into the in-memory layout of model/maps.h
// (docs/design.md section 2).
#include "io/maps_file.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "io/exr.h"

// The first loaded map fixes the size; every other one must match it.
// What the maps of one camera share: the size of the first (all must have it)
// and the workers that decode each file's chunks.
typedef struct size_check {
    const char *first_path;
    int width;
    int height;
    int threads;
} size_check;

static wx_result check_size(size_check *check, const char *path, int width, int height,
                            wx_error *err)
{
    if (check->first_path == NULL) {
        check->first_path = path;
        check->width = width;
        check->height = height;
        return WX_OK;
    }
    if (width != check->width || height != check->height) {
        return wx_fail(
            err, WX_CAUSE_MAP_SIZE,
            "%s: %d x %d, but %s is %d x %d (maps of one camera must have the same size)", path,
            width, height, check->first_path, check->width, check->height);
    }
    return WX_OK;
}

static bool wanted(unsigned which, unsigned bit)
{
    return (which & bit) != 0;
}

static wx_result need_path(const char *path, const char *what, wx_error *err)
{
    if (path == NULL || path[0] == '\0') {
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "no file given for the %s map", what);
    }
    return WX_OK;
}

// Refuses NaN and infinities in a map whose values are all meant to be finite
// (normal, impact, dirt: only the depth map marks "no surface" with them).
static wx_result check_finite(const char *path, const char *what, const float *values,
                              size_t count, int width, int stride, const char *const *channels,
                              wx_error *err)
{
    for (size_t k = 0; k < count; k++) {
        if (!isfinite(values[k])) {
            size_t texel = k / (size_t)stride;
            return wx_fail(err, WX_CAUSE_MAP_VALUE,
                           "%s: %s map texel (%d, %d) channel %s is %s (must be finite)", path,
                           what, (int)(texel % (size_t)width), (int)(texel / (size_t)width),
                           channels[k % (size_t)stride], isnan(values[k]) ? "NaN" : "infinite");
        }
    }
    return WX_OK;
}

// Reads an interleaved map and checks its size.
static wx_result load_interleaved(const char *path, const char *const *channels, int count,
                                  float **out, size_check *check, wx_error *err)
{
    int width = 0;
    int height = 0;
    wx_result result = wx_exr_read_interleaved(path, channels, count, check->threads, out, &width,
                                               &height, err);
    if (result == WX_OK) {
        result = check_size(check, path, width, height, err);
    }
    return result;
}

// An interleaved map whose values must all be finite (normal, impact).
static wx_result load_finite(const char *path, const char *what, const char *const *channels,
                             int count, float **out, size_check *check, wx_error *err)
{
    wx_result result = need_path(path, what, err);
    if (result == WX_OK) {
        result = load_interleaved(path, channels, count, out, check, err);
    }
    if (result == WX_OK) {
        result = check_finite(path, what, *out,
                              (size_t)count * (size_t)check->width * (size_t)check->height,
                              check->width, count, channels, err);
    }
    return result;
}

wx_result wx_maps_load(wx_maps *maps, unsigned which, int threads, const char *depth_path,
                       const char *normal_path, const char *impact_path, const char *dirt_path,
                       wx_error *err)
{
    memset(maps, 0, sizeof *maps);
    size_check check = { NULL, 0, 0, threads };
    wx_result result = WX_OK;

    if (wanted(which, WX_MAPS_DEPTH)) {
        static const char *const channels[] = {"R|Z"};
        result = need_path(depth_path, "depth", err);
        if (result == WX_OK) {
            result = load_interleaved(depth_path, channels, 1, &maps->depth, &check, err);
        }
        if (result == WX_OK) {
            size_t texels = (size_t)check.width * (size_t)check.height;
            float *depth = maps->depth;
            for (size_t t = 0; t < texels; t++) {
                if (wx_depth_is_empty(depth[t])) {
                    depth[t] = INFINITY;
                }
            }
        }
    }
    if (result == WX_OK && wanted(which, WX_MAPS_NORMAL)) {
        static const char *const channels[] = {"R", "G", "B"};
        result = load_finite(normal_path, "normal", channels, 3, &maps->normal, &check, err);
    }
    if (result == WX_OK && wanted(which, WX_MAPS_IMPACT)) {
        static const char *const channels[] = {"R", "G"};
        result = load_finite(impact_path, "impact", channels, 2, &maps->impact, &check, err);
    }
    if (result == WX_OK && wanted(which, WX_MAPS_DIRT)) {
        // A dirt map that `simulate` wrote keeps the dirt it started from in
        // "initialDirt": a new simulation starts from that, not from its result.
        const char *const channels[] = {
            wanted(which, WX_MAPS_INITIAL_DIRT) ? "initialDirt|R" : "R", "G", "B",
            WX_INITIAL_DIRT_CHANNEL, WX_HITS_CHANNEL
        };
        const int channel_count = wanted(which, WX_MAPS_SIMULATED) ? 5 : 3;
        result = need_path(dirt_path, "dirt", err);
        wx_image *image = NULL;
        if (result == WX_OK) {
            image = malloc(sizeof *image); // large (attributes): keep it off the stack
            if (image == NULL) {
                result = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", dirt_path);
            }
        }
        if (result == WX_OK) {
            result = wx_exr_read_parallel(dirt_path, channels, channel_count, threads, image, err);
            if (result == WX_OK) {
                // Take the planes over from the image.
                float **planes[5] = { &maps->dirt, &maps->deposit, &maps->erosion,
                                      &maps->initial_dirt, &maps->hits };
                for (int c = 0; c < channel_count; ++c) {
                    *planes[c] = image->channels[c];
                    image->channels[c] = NULL;
                }
                result = check_size(&check, dirt_path, image->width, image->height, err);
            }
            if (result == WX_OK && image->attr_count > 0) {
                maps->dirt_attrs = malloc((size_t)image->attr_count * sizeof *maps->dirt_attrs);
                if (maps->dirt_attrs == NULL) {
                    result = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", dirt_path);
                } else {
                    memcpy(maps->dirt_attrs, image->attrs,
                           (size_t)image->attr_count * sizeof *maps->dirt_attrs);
                    maps->dirt_attr_count = image->attr_count;
                }
            }
            const float *checked[5] = { maps->dirt, maps->deposit, maps->erosion,
                                        maps->initial_dirt, maps->hits };
            for (int c = 0; c < channel_count && result == WX_OK; c++) {
                const char *name[1] = { image->channel_names[c] };
                result = check_finite(dirt_path, "dirt", checked[c],
                                      (size_t)check.width * (size_t)check.height, check.width, 1,
                                      name, err);
            }
            wx_image_free(image);
        }
        free(image);
    }

    if (result != WX_OK) {
        wx_maps_free(maps);
        return result;
    }
    maps->width = check.width;
    maps->height = check.height;
    return WX_OK;
}
