// exr_io.h: float maps in and out of OpenEXR files (OpenEXR Core C API).
//
// Reading: named channels (float or half, any compression) into float planes,
// row 0 = the top scanline, as the file stores it. Writing: float32 scanline
// files, ZIP compression unless the image asks for another, any channel names,
// m44f and string header attributes, written to a temporary ".name" in the same
// folder and renamed when complete.
#ifndef WX_EXR_IO_H
#define WX_EXR_IO_H

#include <stdbool.h>

#include "error.h"

/// Largest map side accepted on reading and writing.
#define WX_MAP_MAX_SIDE 16384
/// Largest number of texels in one map: 16384 x 16384 (1 GiB per float channel).
#define WX_MAP_MAX_TEXELS (16384LL * 16384LL)

#define WX_IMAGE_MAX_CHANNELS 8
#define WX_IMAGE_MAX_ATTRS 16
#define WX_NAME_MAX 64
#define WX_ATTR_STRING_MAX 1024

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
    int channel_count;
    char channel_names[WX_IMAGE_MAX_CHANNELS][WX_NAME_MAX];
    float *channels[WX_IMAGE_MAX_CHANNELS];
    int attr_count;
    wx_attr attrs[WX_IMAGE_MAX_ATTRS];
} wx_image;

/// Reads the header only: size, every channel name (up to WX_IMAGE_MAX_CHANNELS;
/// more is an error), and the m44f/string attributes. No pixels are allocated.
wx_result wx_exr_read_header(const char *path, wx_image *out, wx_error *err);

/// Reads the channels named in `wanted`, in that order, into out->channels.
/// Each entry may list alternatives separated by '|' ("R|Z"): the first one the
/// file has is read and its name stored in out->channel_names[i]. A missing
/// channel, a size over the limits, a truncated or corrupt file, or a file that
/// is not an EXR give WX_BAD_INPUT with a message naming the file. Only the first
/// part of a file is read, scanline only (tiled and deep files are refused). The
/// image is the data window: its origin, when not (0, 0), is dropped.
wx_result wx_exr_read(const char *path, const char *const *wanted, int wanted_count,
                      wx_image *out, wx_error *err);

/// Like wx_exr_read, but into one malloc'd buffer of wanted_count floats per texel,
/// interleaved in `wanted` order: channel c of texel (i, j) is at
/// (j*width + i)*wanted_count + c. The caller frees *out_texels with free().
wx_result wx_exr_read_interleaved(const char *path, const char *const *wanted, int wanted_count,
                                  float **out_texels, int *out_width, int *out_height,
                                  wx_error *err);

/// Writes every channel of `image` as float32 with image->compression (ZIP
/// unless set), plus its attributes, atomically (temporary ".<name>.tmp<pid>"
/// beside it, then rename).
wx_result wx_exr_write(const char *path, const wx_image *image, wx_error *err);

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

/// Frees the planes; the struct is zeroed and may be reused.
void wx_image_free(wx_image *image);

#endif
