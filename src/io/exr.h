// exr.h: float maps in and out of OpenEXR files (OpenEXR Core C API).
//
// Reading: named channels (float or half, any compression) into float planes,
// row 0 = the top scanline, as the file stores it. Writing: float32 scanline
// files, ZIP compression unless the image asks for another, any channel names,
// m44f and string header attributes, written to a temporary ".name" in the same
// folder and renamed when complete.
#ifndef WX_EXR_H
#define WX_EXR_H

#include <stdbool.h>

#include "core/error.h"
#include "model/image.h"

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

/// Reads every channel of `path`, in the file's order (names taken as they
/// are: no '|' alternatives), as wx_exr_read does.
wx_result wx_exr_read_all(const char *path, wx_image *out, wx_error *err);

/// wx_exr_read with the chunks decoded on `threads` workers (<= 1: the calling
/// thread): the same planes and the same messages for any count.
wx_result wx_exr_read_parallel(const char *path, const char *const *wanted, int wanted_count,
                               int threads, wx_image *out, wx_error *err);

/// Like wx_exr_read, but into one malloc'd buffer of wanted_count floats per texel,
/// interleaved in `wanted` order: channel c of texel (i, j) is at
/// (j*width + i)*wanted_count + c, its chunks decoded on `threads` workers. The
/// caller frees *out_texels with free().
wx_result wx_exr_read_interleaved(const char *path, const char *const *wanted, int wanted_count,
                                  int threads, float **out_texels, int *out_width,
                                  int *out_height, wx_error *err);

/// Writes every channel of `image` as float32 with image->compression (ZIP
/// unless set), plus its attributes, atomically (temporary ".<name>.tmp<pid>"
/// beside it, then rename).
wx_result wx_exr_write(const char *path, const wx_image *image, wx_error *err);

#endif
