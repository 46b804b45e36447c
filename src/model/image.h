// image.h: a float image in memory as the EXR files hold it: named planes of
// width x height floats (row 0 at the top) and header attributes (m44f
// matrices, strings). io/exr.c reads and writes it; nothing here touches files.
#ifndef WX_IMAGE_H
#define WX_IMAGE_H

#include <stdbool.h>

#include "core/error.h"
#include "core/limits.h"

typedef enum wx_attr_type {
    WX_ATTR_M44F,
    WX_ATTR_STRING,
} wx_attr_type;

/// A header attribute: a 4x4 float matrix (row-major, as Imath stores M44f) or a string.
typedef struct wx_attr {
    char name[WX_NAME_MAX];
    wx_attr_type type;
    float m44f[16];
    char string[WX_ATTR_STRING_MAX];
} wx_attr;

/// How wx_exr_write compresses the pixels (all lossless). Zero is ZIP, so a
/// zero-initialised image is written as before; docs/performance.md compares
/// their speed and size on baked maps.
typedef enum wx_exr_compression {
    WX_EXR_ZIP = 0, ///< zlib, 16 scanlines per chunk (the default)
    WX_EXR_NONE,    ///< raw: the fastest, the largest
    WX_EXR_RLE,     ///< run lengths: fast; small where values repeat (background, flat maps)
    WX_EXR_ZIPS,    ///< zlib, one scanline per chunk
    WX_EXR_PIZ,     ///< wavelet + Huffman
} wx_exr_compression;

/// A float image: planes of width*height floats, row 0 = top.
typedef struct wx_image {
    int width;
    int height;
    wx_exr_compression compression; ///< used by wx_exr_write only (reading accepts any)
    /// Threads that compress the chunks in wx_exr_write (<= 1: the calling
    /// thread only); the file's bytes are the same for every count.
    int threads;
    /// zlib level of ZIP and ZIPS, 1 (fastest) to 9 (smallest); 0: OpenEXR's
    /// default (4). The maps the pipeline writes for itself use 1.
    int zip_level;
    int channel_count;
    char channel_names[WX_IMAGE_MAX_CHANNELS][WX_NAME_MAX];
    float *channels[WX_IMAGE_MAX_CHANNELS];
    int attr_count;
    wx_attr attrs[WX_IMAGE_MAX_ATTRS];
} wx_image;

/// Allocates `channel_count` zeroed planes of width*height floats and names them.
/// Returns WX_FAIL when out of memory, WX_BAD_INPUT when a size is over the limits.
wx_result wx_image_alloc(wx_image *image, int width, int height, int channel_count,
                         const char *const *names, wx_error *err);

/// Adds an m44f attribute (row-major) to the image.
void wx_image_set_m44f(wx_image *image, const char *name, const float m[16]);

/// Adds a string attribute to the image.
void wx_image_set_string(wx_image *image, const char *name, const char *value);

/// Finds an attribute by name, or NULL.
const wx_attr *wx_image_find_attr(const wx_image *image, const char *name);

/// The last guard before an output is written (issue 24): WX_OK when every
/// texel of every channel is a finite number; else WX_FAIL (WX_CAUSE_INTERNAL:
/// the scene's checks should have refused what overflowed) with a message
/// naming `path`, the first channel and texel and how many are not finite.
/// Depth maps, whose +inf means "no surface", are not checked with it.
wx_result wx_image_check_finite(const wx_image *image, const char *path, wx_error *err);

/// Frees the planes; the struct is zeroed and may be reused.
void wx_image_free(wx_image *image);

#endif
