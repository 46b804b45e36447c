// maps_file.c: loads the four maps of one camera (depth, normal, impact, dirt)
// from their EXR files into the in-memory layout of model/maps.h
// (docs/design.md section 2).
#include "io/maps_file.h"
#include "core/big_alloc.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>

#include "io/exr.h"

// The files of a layered camera, each decoded once with every channel it
// holds: a layer's channels are a few of a file's, and a chunk is decompressed
// whole whichever of its channels are read, so reading each layer from the
// file decompressed the file once per layer (the house's five four-layer
// cameras: 1.9 s of a run's reading). Kept until every layer is loaded.
enum { DECODED_FILES = 4 };
typedef struct decoded_files {
    const char *path[DECODED_FILES];
    wx_image *image[DECODED_FILES]; ///< NULL: not read, or unreadable (read directly)
    bool borrowed[DECODED_FILES];   ///< the caller's (wx_maps_load_given): not freed here
    int count;
} decoded_files;

// The first loaded map fixes the size; every other one must match it.
// What the maps of one camera share: the size of the first (all must have it),
// the workers that decode each file's chunks, and the decoded files of a
// layered camera (NULL for one layer).
typedef struct size_check {
    const char *first_path;
    int width;
    int height;
    int threads;
    decoded_files *files;
} size_check;

static void decoded_free(decoded_files *files)
{
    for (int k = 0; k < files->count; ++k) {
        if (files->image[k] != NULL && !files->borrowed[k]) {
            wx_image_free(files->image[k]);
            free(files->image[k]);
        }
    }
    files->count = 0;
}

// The decoded file at `path`, read with every channel on first use; NULL when
// it cannot be (then the caller reads the file itself and reports what is wrong).
static const wx_image *decoded(size_check *check, const char *path)
{
    decoded_files *files = check->files;
    if (files == NULL || path == NULL) {
        return NULL;
    }
    for (int k = 0; k < files->count; ++k) {
        if (strcmp(files->path[k], path) == 0) {
            return files->image[k];
        }
    }
    if (files->count == DECODED_FILES) {
        return NULL;
    }
    wx_image *image = malloc(sizeof *image);
    wx_error ignored;
    if (image != NULL &&
        wx_exr_read_parallel(path, NULL, 0, check->threads, image, &ignored) != WX_OK) {
        free(image);
        image = NULL;
    }
    files->path[files->count] = path;
    files->borrowed[files->count] = false;
    files->image[files->count++] = image;
    return image;
}

// The index in `image` of the first of the alternatives "A|B" it has, or -1.
static int decoded_channel(const wx_image *image, const char *alternatives)
{
    for (const char *a = alternatives; *a != '\0';) {
        const char *bar = strchr(a, '|');
        size_t len = bar != NULL ? (size_t)(bar - a) : strlen(a);
        for (int c = 0; c < image->channel_count; ++c) {
            if (strlen(image->channel_names[c]) == len &&
                strncmp(image->channel_names[c], a, len) == 0) {
                return c;
            }
        }
        a += len + (bar != NULL ? 1 : 0);
    }
    return -1;
}

// The decoded file at `path` when it has every wanted channel, each once
// (their indices in index[]), else NULL: the file reader then says what is
// missing or asked for twice.
static const wx_image *decoded_channels(size_check *check, const char *path,
                                        const char *const *wanted, int count,
                                        int index[WX_IMAGE_MAX_CHANNELS])
{
    const wx_image *image = decoded(check, path);
    if (image == NULL || count > WX_IMAGE_MAX_CHANNELS) {
        return NULL;
    }
    for (int c = 0; c < count; ++c) {
        index[c] = decoded_channel(image, wanted[c]);
        for (int k = 0; k < c && index[c] >= 0; ++k) {
            index[c] = index[k] == index[c] ? -1 : index[c];
        }
        if (index[c] < 0) {
            return NULL;
        }
    }
    return image;
}

// The size and attributes of a decoded file, as a read of it gives them.
static void copy_frame(wx_image *out, const wx_image *image)
{
    out->width = image->width;
    out->height = image->height;
    out->attr_count = image->attr_count;
    memcpy(out->attrs, image->attrs, (size_t)image->attr_count * sizeof *out->attrs);
}

// wx_exr_read_parallel from the decoded file when it has every wanted channel
// (the same planes, names and attributes), else from the file.
static wx_result read_planar(size_check *check, const char *path, const char *const *wanted,
                             int count, wx_image *out, wx_error *err)
{
    int index[WX_IMAGE_MAX_CHANNELS];
    const wx_image *image = decoded_channels(check, path, wanted, count, index);
    if (image == NULL) {
        return wx_exr_read_parallel(path, wanted, count, check->threads, out, err);
    }
    memset(out, 0, sizeof *out);
    size_t texels = (size_t)image->width * (size_t)image->height;
    for (int c = 0; c < count; ++c) {
        out->channels[c] = wx_big_malloc(texels * sizeof(float));
        if (out->channels[c] == NULL) {
            wx_image_free(out);
            return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory for %d x %d texels",
                           path, image->width, image->height);
        }
        memcpy(out->channels[c], image->channels[index[c]], texels * sizeof(float));
        memcpy(out->channel_names[c], image->channel_names[index[c]], sizeof out->channel_names[c]);
    }
    out->channel_count = count;
    copy_frame(out, image);
    return WX_OK;
}

// wx_exr_read_header from the decoded file when there is one.
static wx_result read_header(size_check *check, const char *path, wx_image *out, wx_error *err)
{
    const wx_image *image = decoded(check, path);
    if (image == NULL) {
        return wx_exr_read_header(path, out, err);
    }
    memset(out, 0, sizeof *out);
    out->channel_count = image->channel_count;
    memcpy(out->channel_names, image->channel_names, sizeof out->channel_names);
    copy_frame(out, image);
    return WX_OK;
}

// wx_exr_read_interleaved from the decoded file when it has every wanted
// channel, else from the file.
static wx_result read_interleaved(size_check *check, const char *path, const char *const *wanted,
                                  int count, float **out, int *width, int *height, wx_error *err)
{
    int index[WX_IMAGE_MAX_CHANNELS];
    const wx_image *image = decoded_channels(check, path, wanted, count, index);
    if (image == NULL) {
        return wx_exr_read_interleaved(path, wanted, count, check->threads, out, width, height,
                                       err);
    }
    size_t texels = (size_t)image->width * (size_t)image->height;
    *out = wx_big_malloc(texels * (size_t)count * sizeof(float));
    if (*out == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory for %d x %d texels", path,
                       image->width, image->height);
    }
    for (int c = 0; c < count; ++c) {
        const float *from = image->channels[index[c]];
        for (size_t t = 0; t < texels; ++t) {
            (*out)[t * (size_t)count + (size_t)c] = from[t];
        }
    }
    *width = image->width;
    *height = image->height;
    return WX_OK;
}

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
    wx_result result = read_interleaved(check, path, channels, count, out, &width, &height, err);
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

static bool header_has(const wx_image *header, const char *name)
{
    for (int c = 0; c < header->channel_count; ++c) {
        if (strcmp(header->channel_names[c], name) == 0) {
            return true;
        }
    }
    return false;
}

// The channel names of layer `layer` (docs/design.md section 14): each
// alternative of "A|B" prefixed "layerK." for K >= 1, unchanged in layer 0.
static void layer_names(char *out, size_t size, int layer, const char *alternatives)
{
    if (layer == 0) {
        snprintf(out, size, "%s", alternatives);
        return;
    }
    size_t used = 0;
    out[0] = '\0';
    for (const char *a = alternatives; *a != '\0' && used < size;) {
        const char *bar = strchr(a, '|');
        size_t len = bar != NULL ? (size_t)(bar - a) : strlen(a);
        int n = snprintf(out + used, size - used, "%slayer%d.%.*s", used > 0 ? "|" : "", layer,
                         (int)len, a);
        used += n > 0 ? (size_t)n : 0;
        a += len + (bar != NULL ? 1 : 0);
    }
}

// One plane of wx_maps the dirt map fills: a channel (or alternatives) of the
// file, or zeros.
typedef struct dirt_plane {
    char channel[2 * (WX_NAME_MAX + 16) + 2]; ///< "" = zeros
    float **dest;                      ///< the wx_maps plane block
    size_t offset;                     ///< plane index within it
} dirt_plane;

// The dirt map of a scene with substances, or with the bake's surface and area
// records: the planes model/maps.h lays out, from the channels the file has.
static wx_result load_scene_dirt(wx_maps *maps, unsigned which, const wx_scene *scene, int layer,
                                 const char *dirt_path, size_check *check, wx_error *err)
{
    wx_image *image = calloc(2, sizeof *image); // header and planes: off the stack
    dirt_plane *planes = calloc(WX_IMAGE_MAX_CHANNELS, sizeof *planes);
    if (image == NULL || planes == NULL) {
        free(image);
        free(planes);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", dirt_path);
    }
    wx_image *header = &image[1];
    wx_result result = read_header(check, dirt_path, header, err);
    int S = scene->substances_declared ? scene->substance_count : 1;
    bool simulated = wanted(which, WX_MAPS_SIMULATED);
    bool restart = wanted(which, WX_MAPS_INITIAL_DIRT);
    int count = 0;
    for (int s = 0; s < S && result == WX_OK; ++s) {
        char amount[WX_NAME_MAX + 8], deposit[WX_NAME_MAX + 8], erosion[WX_NAME_MAX + 8],
            initial[WX_NAME_MAX + 8];
        if (scene->substances_declared) {
            snprintf(amount, sizeof amount, "%s.amount", scene->substances[s]);
            snprintf(deposit, sizeof deposit, "%s.deposit", scene->substances[s]);
            snprintf(erosion, sizeof erosion, "%s.erosion", scene->substances[s]);
            snprintf(initial, sizeof initial, "%s.initial", scene->substances[s]);
        }
        if (!scene->substances_declared ||
            (!header_has(header, amount) && s == scene->dirt_substance)) {
            snprintf(amount, sizeof amount, "R");
            snprintf(deposit, sizeof deposit, "G");
            snprintf(erosion, sizeof erosion, "B");
            snprintf(initial, sizeof initial, "%s", WX_INITIAL_DIRT_CHANNEL);
        }
        bool present = header_has(header, amount);
        bool has_initial = present && header_has(header, initial);
        dirt_plane *p = &planes[count];
        if (present) {
            snprintf(p[0].channel, sizeof p[0].channel, "%s%s%s", restart && has_initial ? initial : "",
                     restart && has_initial ? "|" : "", amount);
            snprintf(p[1].channel, sizeof p[1].channel, "%s", deposit);
            snprintf(p[2].channel, sizeof p[2].channel, "%s", erosion);
        }
        p[0].dest = &maps->dirt;
        p[1].dest = &maps->deposit;
        p[2].dest = &maps->erosion;
        for (int k = 0; k < 3; ++k) {
            p[k].offset = (size_t)s;
        }
        count += 3;
        if (simulated) {
            p = &planes[count++];
            if (has_initial) {
                snprintf(p->channel, sizeof p->channel, "%s", initial);
            }
            p->dest = &maps->initial_dirt;
            p->offset = (size_t)s;
        }
    }
    if (simulated) {
        dirt_plane *p = &planes[count++];
        snprintf(p->channel, sizeof p->channel, "%s", WX_HITS_CHANNEL);
        p->dest = &maps->hits;
    }
    if (result == WX_OK && header_has(header, WX_SURFACE_CHANNEL)) {
        dirt_plane *p = &planes[count++];
        snprintf(p->channel, sizeof p->channel, "%s", WX_SURFACE_CHANNEL);
        p->dest = &maps->surface;
    }
    if (result == WX_OK && header_has(header, WX_AREA_CHANNEL)) {
        dirt_plane *p = &planes[count++];
        snprintf(p->channel, sizeof p->channel, "%s", WX_AREA_CHANNEL);
        p->dest = &maps->area;
    }
    const char *channels[WX_IMAGE_MAX_CHANNELS];
    int read = 0;
    for (int k = 0; k < count; ++k) {
        if (planes[k].channel[0] != '\0') {
            char plain[sizeof planes[k].channel];
            memcpy(plain, planes[k].channel, sizeof plain);
            layer_names(planes[k].channel, sizeof planes[k].channel, layer, plain);
            channels[read++] = planes[k].channel;
        }
    }
    if (result == WX_OK) {
        result = read_planar(check, dirt_path, channels, read, image, err);
    }
    if (result == WX_OK) {
        result = check_size(check, dirt_path, image->width, image->height, err);
    }
    size_t n = (size_t)check->width * (size_t)check->height;
    for (int k = 0, c = 0; k < count && result == WX_OK; ++k) {
        dirt_plane *p = &planes[k];
        size_t block = p->dest == &maps->dirt || p->dest == &maps->deposit ||
                               p->dest == &maps->erosion || p->dest == &maps->initial_dirt
                           ? (size_t)S
                           : 1;
        if (*p->dest == NULL) {
            *p->dest = wx_big_calloc(n * block + 1, sizeof(float));
            if (*p->dest == NULL) {
                result = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", dirt_path);
                break;
            }
        }
        if (p->channel[0] == '\0') {
            continue; // zeros
        }
        const char *name[1] = { image->channel_names[c] };
        result = check_finite(dirt_path, "dirt", image->channels[c], n, check->width, 1, name, err);
        if (result == WX_OK) {
            memcpy(*p->dest + p->offset * n, image->channels[c], n * sizeof(float));
        }
        c++;
    }
    if (result == WX_OK && image->attr_count > 0) {
        maps->dirt_attrs = malloc((size_t)image->attr_count * sizeof *maps->dirt_attrs);
        if (maps->dirt_attrs == NULL) {
            result = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", dirt_path);
        } else {
            memcpy(maps->dirt_attrs, image->attrs, (size_t)image->attr_count * sizeof *maps->dirt_attrs);
            maps->dirt_attr_count = image->attr_count;
        }
    }
    maps->substances = S;
    wx_image_free(image);
    free(image);
    free(planes);
    return result;
}

wx_result wx_maps_load(wx_maps *maps, unsigned which, int threads, const char *depth_path,
                       const char *normal_path, const char *impact_path, const char *dirt_path,
                       wx_error *err)
{
    return wx_maps_load_scene(maps, which, threads, NULL, depth_path, normal_path, impact_path,
                              dirt_path, err);
}

// The planes of one layer of the maps (layer 0: the plain channels).
static wx_result load_layer(wx_maps *maps, unsigned which, int threads, const wx_scene *scene,
                            int layer, const char *depth_path, const char *normal_path,
                            const char *impact_path, const char *dirt_path, decoded_files *files,
                            wx_error *err)
{
    memset(maps, 0, sizeof *maps);
    char names[5][2 * (WX_NAME_MAX + 16) + 2];
    size_check check = { NULL, 0, 0, threads, files };
    wx_result result = WX_OK;

    if (wanted(which, WX_MAPS_DEPTH)) {
        layer_names(names[0], sizeof names[0], layer, "R|Z");
        const char *const channels[] = { names[0] };
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
        layer_names(names[0], sizeof names[0], layer, "R");
        layer_names(names[1], sizeof names[1], layer, "G");
        layer_names(names[2], sizeof names[2], layer, "B");
        const char *const channels[] = { names[0], names[1], names[2] };
        result = load_finite(normal_path, "normal", channels, 3, &maps->normal, &check, err);
    }
    if (result == WX_OK && wanted(which, WX_MAPS_IMPACT)) {
        layer_names(names[0], sizeof names[0], layer, "R");
        layer_names(names[1], sizeof names[1], layer, "G");
        const char *const channels[] = { names[0], names[1] };
        result = load_finite(impact_path, "impact", channels, 2, &maps->impact, &check, err);
    }
    bool scene_layout = scene != NULL && (scene->substances_declared ||
                                          wx_scene_has_surface_rules(scene) ||
                                          wx_scene_has_grow(scene));
    if (result == WX_OK && wanted(which, WX_MAPS_DIRT) && scene_layout) {
        result = need_path(dirt_path, "dirt", err);
        if (result == WX_OK) {
            result = load_scene_dirt(maps, which, scene, layer, dirt_path, &check, err);
        }
    } else if (result == WX_OK && wanted(which, WX_MAPS_DIRT)) {
        // A dirt map that `simulate` wrote keeps the dirt it started from in
        // "initialDirt": a new simulation starts from that, not from its result.
        static const char *const plain[] = { "initialDirt|R", "G", "B", WX_INITIAL_DIRT_CHANNEL,
                                             WX_HITS_CHANNEL };
        for (int c = 0; c < 5; ++c) {
            bool restart = c == 0 && wanted(which, WX_MAPS_INITIAL_DIRT);
            layer_names(names[c], sizeof names[c], layer, c == 0 && !restart ? "R" : plain[c]);
        }
        const char *const channels[] = { names[0], names[1], names[2], names[3], names[4] };
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
            result = read_planar(&check, dirt_path, channels, channel_count, image, err);
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

// Appends the block of one layer to a plane of the layered maps.
static bool append_block(float **plane, int layers, float *block, size_t block_floats, int layer)
{
    if (block == NULL) {
        return *plane == NULL;
    }
    if (layer == 0) {
        // A new block (not realloc's: its growth would be mapped in small pages).
        float *all = wx_big_malloc((size_t)layers * block_floats * sizeof(float) + sizeof(float));
        if (all == NULL) {
            return false;
        }
        memcpy(all, block, block_floats * sizeof(float));
        free(block);
        *plane = all;
        return true;
    }
    if (*plane == NULL) {
        return false;
    }
    memcpy(*plane + (size_t)layer * block_floats, block, block_floats * sizeof(float));
    return true;
}

wx_result wx_maps_load_scene(wx_maps *maps, unsigned which, int threads, const wx_scene *scene,
                             const char *depth_path, const char *normal_path,
                             const char *impact_path, const char *dirt_path, wx_error *err)
{
    return wx_maps_load_layers(maps, which, threads, scene, 1, depth_path, normal_path,
                               impact_path, dirt_path, err);
}

wx_result wx_maps_load_layers(wx_maps *maps, unsigned which, int threads, const wx_scene *scene,
                              int layers, const char *depth_path, const char *normal_path,
                              const char *impact_path, const char *dirt_path, wx_error *err)
{
    const char *const paths[4] = { depth_path, normal_path, impact_path, dirt_path };
    return wx_maps_load_given(maps, which, threads, scene, layers, paths, NULL, err);
}

wx_result wx_maps_load_given(wx_maps *maps, unsigned which, int threads, const wx_scene *scene,
                             int layers, const char *const paths[4], const wx_image *const given[4],
                             wx_error *err)
{
    const char *depth_path = paths[0], *normal_path = paths[1], *impact_path = paths[2],
               *dirt_path = paths[3];
    // The files in memory stand for the files: every read goes through the
    // decoded images, whose planes, names and attributes are the files'.
    decoded_files files = { .count = 0 };
    for (int k = 0; k < 4 && given != NULL; ++k) {
        if (given[k] != NULL && paths[k] != NULL) {
            files.path[files.count] = paths[k];
            files.image[files.count] = (wx_image *)given[k]; // read only: borrowed
            files.borrowed[files.count++] = true;
        }
    }
    if (layers <= 1) {
        wx_result r = load_layer(maps, which, threads, scene, 0, depth_path, normal_path,
                                 impact_path, dirt_path, files.count > 0 ? &files : NULL, err);
        decoded_free(&files);
        return r;
    }
    wx_maps one;
    wx_result r = load_layer(maps, which, threads, scene, 0, depth_path, normal_path, impact_path,
                             dirt_path, &files, err);
    if (r != WX_OK) {
        decoded_free(&files);
        return r;
    }
    size_t n = (size_t)maps->width * (size_t)maps->height;
    size_t S = (size_t)wx_maps_substances(maps);
    // Each plane with its floats per layer; layer 0 is grown to hold them all.
    for (int layer = 0; layer < layers && r == WX_OK; ++layer) {
        wx_maps *from = maps;
        if (layer > 0) {
            r = load_layer(&one, which, threads, scene, layer, depth_path, normal_path, impact_path,
                           dirt_path, &files, err);
            if (r != WX_OK) {
                break;
            }
            from = &one;
            if (one.width != maps->width || one.height != maps->height) {
                wx_maps_free(&one);
                r = wx_fail(err, WX_CAUSE_MAP_SIZE, "layer %d of the maps of %s differs in size",
                            layer, depth_path != NULL ? depth_path : dirt_path);
                break;
            }
        }
        float **to[] = { &maps->depth, &maps->normal, &maps->impact, &maps->dirt, &maps->deposit,
                         &maps->erosion, &maps->initial_dirt, &maps->hits, &maps->surface,
                         &maps->area };
        float *block[] = { from->depth, from->normal, from->impact, from->dirt, from->deposit,
                           from->erosion, from->initial_dirt, from->hits, from->surface,
                           from->area };
        size_t floats[] = { n, 3 * n, 2 * n, S * n, S * n, S * n, S * n, n, n, n };
        for (size_t k = 0; k < sizeof floats / sizeof floats[0] && r == WX_OK; ++k) {
            if (!append_block(to[k], layers, block[k], floats[k], layer)) {
                r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory for the layers of %s",
                            depth_path != NULL ? depth_path : dirt_path);
            }
        }
        if (layer > 0) {
            wx_maps_free(&one);
        }
    }
    decoded_free(&files);
    if (r != WX_OK) {
        wx_maps_free(maps);
        return r;
    }
    maps->layers = layers;
    maps->outward = true;
    return WX_OK;
}
