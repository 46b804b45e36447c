// exr_write.c: float maps into OpenEXR files (OpenEXR Core C API): the image
// checked, its chunks compressed on the pool's threads and written in order
// through the stream of exr.c into a temporary file, fsync'ed and renamed over
// the destination (core/atomic_file.h).
#include "io/exr.h"

#include "core/atomic_file.h"
#include "core/parallel.h"

#include <errno.h>
#include <fcntl.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <openexr.h>

#include "io/exr_internal.h"

// ---------------------------------------------------------------------------
// Writing.

static wx_result check_image(const char *path, const wx_image *image, wx_error *err)
{
    if (image->width <= 0 || image->height <= 0 || image->width > WX_MAP_MAX_SIDE ||
        image->height > WX_MAP_MAX_SIDE ||
        (long long)image->width * image->height > WX_MAP_MAX_TEXELS) {
        return wx_fail(err, WX_CAUSE_MAP_SIZE, "%s: cannot write a %d x %d image (largest %d x %d)",
                       path, image->width, image->height, WX_MAP_MAX_SIDE, WX_MAP_MAX_SIDE);
    }
    if (image->channel_count < 1 || image->channel_count > WX_IMAGE_MAX_CHANNELS) {
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "%s: cannot write %d channels (1 to %d)", path,
                       image->channel_count, WX_IMAGE_MAX_CHANNELS);
    }
    for (int c = 0; c < image->channel_count; c++) {
        if (image->channels[c] == NULL || image->channel_names[c][0] == '\0') {
            return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "%s: channel %d has no %s", path, c,
                           image->channels[c] == NULL ? "pixels" : "name");
        }
        for (int d = 0; d < c; d++) {
            if (strcmp(image->channel_names[c], image->channel_names[d]) == 0) {
                return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "%s: channel %s appears twice", path,
                               image->channel_names[c]);
            }
        }
    }
    return WX_OK;
}

// The encoding state of one worker thread: its pipeline (OpenEXR Core's
// pipelines are meant to run one per thread on the same context), the
// library's compressor it wraps, and where the chunk it encodes is kept.
typedef struct chunk_encoder {
    exr_encode_pipeline_t enc;
    bool initialized;
    exr_result_t (*compress)(exr_encode_pipeline_t *enc);
    struct chunk_slot *slot; ///< the chunk being encoded
} chunk_encoder;

// One encoded chunk, kept until it is written in file order.
typedef struct chunk_slot {
    int y;      ///< first scanline
    void *data; ///< malloc'd copy of the compressed (or raw) chunk
    uint64_t bytes;
    exr_result_t rv;
} chunk_slot;

// OpenEXR Core (3.1 to 3.4 at least) keeps a zlib stream that is exactly as long as
// the raw data, and readers then take it for raw data (openexr issue #2306). Such a
// chunk is stored raw instead, as the file format says.
static exr_result_t compress_unambiguously(exr_encode_pipeline_t *enc)
{
    const chunk_encoder *hook = enc->encoding_user_data;
    exr_result_t rv = hook->compress(enc);
    if (rv == EXR_ERR_SUCCESS && enc->compressed_bytes == enc->packed_bytes &&
        enc->compressed_buffer != NULL && enc->packed_buffer != NULL &&
        enc->compressed_buffer != enc->packed_buffer) {
        memcpy(enc->compressed_buffer, enc->packed_buffer, enc->packed_bytes);
    }
    return rv;
}

// The pipeline's last stage: keep the chunk instead of writing it, so that the
// chunks compressed on several threads are written in order by one.
static exr_result_t keep_chunk(exr_encode_pipeline_t *enc)
{
    chunk_encoder *worker = enc->encoding_user_data;
    chunk_slot *slot = worker->slot;
    const void *bytes =
        enc->compressed_buffer != NULL ? enc->compressed_buffer : enc->packed_buffer;
    uint64_t size = enc->compressed_buffer != NULL ? enc->compressed_bytes : enc->packed_bytes;
    slot->data = malloc(size > 0 ? (size_t)size : 1);
    if (slot->data == NULL) {
        return EXR_ERR_OUT_OF_MEMORY;
    }
    memcpy(slot->data, bytes, (size_t)size);
    slot->bytes = size;
    return EXR_ERR_SUCCESS;
}

static wx_result write_failed(const char *path, const exr_stream *s, exr_result_t rv,
                              const char *what, wx_error *err)
{
    return wx_fail(err, WX_CAUSE_IO, "%s: cannot write%s%s (%s)", path, what[0] ? " " : "", what,
                   wx_exr_stream_detail(s, rv));
}

static exr_compression_t exr_compression(wx_exr_compression c)
{
    switch (c) {
    case WX_EXR_NONE:
        return EXR_COMPRESSION_NONE;
    case WX_EXR_RLE:
        return EXR_COMPRESSION_RLE;
    case WX_EXR_ZIPS:
        return EXR_COMPRESSION_ZIPS;
    case WX_EXR_PIZ:
        return EXR_COMPRESSION_PIZ;
    case WX_EXR_ZIP:
        break;
    }
    return EXR_COMPRESSION_ZIP;
}

// The chunks of one batch, encoded by the workers of wx_parallel_for.
typedef struct chunk_batch {
    exr_context_t ctx;
    int part;
    const wx_image *image;
    chunk_encoder *workers; ///< one per thread
    chunk_slot *slots;
} chunk_batch;

// Packs and compresses chunks [begin, end) of the batch on worker `worker`.
static void encode_chunks(int64_t begin, int64_t end, int worker, void *context)
{
    chunk_batch *batch = context;
    chunk_encoder *w = &batch->workers[worker];
    const wx_image *image = batch->image;
    const size_t width = (size_t)image->width;
    for (int64_t k = begin; k < end; ++k) {
        chunk_slot *slot = &batch->slots[k];
        exr_chunk_info_t ci;
        exr_result_t rv = exr_write_scanline_chunk_info(batch->ctx, batch->part, slot->y, &ci);
        if (rv == EXR_ERR_SUCCESS) {
            rv = w->initialized ? exr_encoding_update(batch->ctx, batch->part, &ci, &w->enc)
                                : exr_encoding_initialize(batch->ctx, batch->part, &ci, &w->enc);
            w->initialized = w->initialized || rv == EXR_ERR_SUCCESS;
        }
        for (int c = 0; rv == EXR_ERR_SUCCESS && c < w->enc.channel_count; c++) {
            exr_coding_channel_info_t *ch = &w->enc.channels[c];
            const float *plane = NULL;
            for (int i = 0; i < image->channel_count; i++) {
                if (ch->channel_name != NULL &&
                    strcmp(ch->channel_name, image->channel_names[i]) == 0) {
                    plane = image->channels[i];
                }
            }
            if (plane == NULL) {
                rv = EXR_ERR_INVALID_ARGUMENT;
                break;
            }
            ch->encode_from_ptr = (const uint8_t *)(plane + (size_t)slot->y * width);
            ch->user_pixel_stride = (int32_t)sizeof(float);
            ch->user_line_stride = (int32_t)(width * sizeof(float));
            ch->user_data_type = EXR_PIXEL_FLOAT;
            ch->user_bytes_per_element = (int16_t)sizeof(float);
        }
        if (rv == EXR_ERR_SUCCESS) {
            rv = exr_encoding_choose_default_routines(batch->ctx, batch->part, &w->enc);
        }
        if (rv == EXR_ERR_SUCCESS) {
            w->enc.encoding_user_data = w;
            w->slot = slot;
            if (w->enc.compress_fn != NULL) {
                w->compress = w->enc.compress_fn;
                w->enc.compress_fn = compress_unambiguously;
            }
            // Not written here: no waiting for the previous chunk (the library's
            // yield fails a chunk that is not the next), kept for write_chunks.
            w->enc.yield_until_ready_fn = NULL;
            w->enc.write_fn = keep_chunk;
            rv = exr_encoding_run(batch->ctx, batch->part, &w->enc);
        }
        slot->rv = rv;
    }
}

// Chunks encoded per batch: enough to keep every thread busy, few enough that
// the compressed chunks waiting to be written stay small.
enum { CHUNKS_PER_BATCH = 64 };

// Encodes every chunk (in parallel when `threads` > 1) and writes them in
// scanline order. The bytes do not depend on the thread count: each chunk is
// compressed on its own.
static exr_result_t write_chunks(exr_context_t ctx, int part, int lines, const wx_image *image,
                                 int threads)
{
    int chunk_count = (image->height + lines - 1) / lines;
    int batch_size = CHUNKS_PER_BATCH * threads;
    batch_size = batch_size < chunk_count ? batch_size : chunk_count;
    chunk_batch batch = { .ctx = ctx, .part = part, .image = image };
    batch.workers = calloc((size_t)threads, sizeof *batch.workers);
    batch.slots = calloc((size_t)batch_size, sizeof *batch.slots);
    exr_result_t rv =
        batch.workers != NULL && batch.slots != NULL ? EXR_ERR_SUCCESS : EXR_ERR_OUT_OF_MEMORY;
    for (int first = 0; rv == EXR_ERR_SUCCESS && first < chunk_count; first += batch_size) {
        int n = chunk_count - first < batch_size ? chunk_count - first : batch_size;
        for (int k = 0; k < n; ++k) {
            batch.slots[k] = (chunk_slot){ .y = (first + k) * lines };
        }
        wx_parallel_for(threads, n, 1, encode_chunks, &batch);
        for (int k = 0; k < n; ++k) {
            chunk_slot *slot = &batch.slots[k];
            if (rv == EXR_ERR_SUCCESS) {
                rv = slot->rv != EXR_ERR_SUCCESS
                         ? slot->rv
                         : exr_write_scanline_chunk(ctx, part, slot->y, slot->data, slot->bytes);
            }
            free(slot->data);
            slot->data = NULL;
        }
    }
    for (int t = 0; batch.workers != NULL && t < threads; ++t) {
        if (batch.workers[t].initialized) {
            exr_encoding_destroy(ctx, &batch.workers[t].enc);
        }
    }
    free(batch.workers);
    free(batch.slots);
    return rv;
}

// Longest name a file without the "long names" flag may hold (OpenEXR before
// 1.7 reads only those; the library refuses longer ones unless told).
enum { EXR_SHORT_NAME_MAX = 31 };

// True when a channel or attribute name of `image` is longer than 31 characters:
// a substance channel such as layer7.NAME.deposit of a 32-character substance
// (47 characters). Only such files carry the flag, so every other file keeps
// its bytes and stays readable by the oldest readers.
static bool needs_long_names(const wx_image *image)
{
    for (int c = 0; c < image->channel_count; c++) {
        if (strlen(image->channel_names[c]) > EXR_SHORT_NAME_MAX) {
            return true;
        }
    }
    for (int a = 0; a < image->attr_count; a++) {
        if (strlen(image->attrs[a].name) > EXR_SHORT_NAME_MAX) {
            return true;
        }
    }
    return false;
}

// Writes the whole file through the stream (the temporary file).
static wx_result write_body(exr_stream *s, const char *path, const char *tmp_path,
                            const wx_image *image, wx_error *err)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = wx_exr_stream_on_error;
    init.user_data = s;
    init.write_fn = wx_exr_stream_write;
    exr_context_t ctx = NULL;
    wx_exr_stream_reset(s);
    exr_result_t rv = exr_start_write(&ctx, tmp_path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv == EXR_ERR_SUCCESS && needs_long_names(image)) {
        rv = exr_set_longname_support(ctx, 1);
    }
    int part = 0;
    if (rv == EXR_ERR_SUCCESS) {
        rv = exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, &part);
    }
    if (rv == EXR_ERR_SUCCESS) {
        rv = exr_initialize_required_attr_simple(ctx, part, image->width, image->height,
                                                 exr_compression(image->compression));
    }
    if (rv == EXR_ERR_SUCCESS && image->zip_level >= 1 && image->zip_level <= 9) {
        rv = exr_set_zip_compression_level(ctx, part, image->zip_level);
    }
    for (int c = 0; rv == EXR_ERR_SUCCESS && c < image->channel_count; c++) {
        rv = (exr_result_t)exr_add_channel(ctx, part, image->channel_names[c], EXR_PIXEL_FLOAT,
                                           EXR_PERCEPTUALLY_LINEAR, 1, 1);
    }
    if (rv != EXR_ERR_SUCCESS) {
        exr_finish(&ctx);
        return write_failed(path, s, rv, "the header", err);
    }
    for (int a = 0; a < image->attr_count; a++) {
        const wx_attr *attr = &image->attrs[a];
        if (attr->type == WX_ATTR_M44F) {
            exr_attr_m44f_t m;
            memcpy(m.m, attr->m44f, sizeof m.m);
            rv = exr_attr_set_m44f(ctx, part, attr->name, &m);
        } else {
            rv = exr_attr_set_string(ctx, part, attr->name, attr->string);
        }
        if (rv != EXR_ERR_SUCCESS) {
            exr_finish(&ctx);
            return wx_fail(err, WX_CAUSE_IO, "%s: cannot write attribute %s (%s)", path, attr->name,
                           wx_exr_stream_detail(s, rv));
        }
    }
    rv = exr_write_header(ctx);
    if (rv != EXR_ERR_SUCCESS) {
        exr_finish(&ctx);
        return write_failed(path, s, rv, "the header", err);
    }

    int32_t lines = 0;
    rv = exr_get_scanlines_per_chunk(ctx, part, &lines);
    if (rv == EXR_ERR_SUCCESS && lines <= 0) {
        rv = EXR_ERR_INVALID_ARGUMENT;
    }
    if (rv != EXR_ERR_SUCCESS) {
        exr_finish(&ctx);
        return write_failed(path, s, rv, "", err);
    }
    rv = write_chunks(ctx, part, lines, image, image->threads > 1 ? image->threads : 1);
    if (rv != EXR_ERR_SUCCESS) {
        exr_finish(&ctx);
        return write_failed(path, s, rv, "", err);
    }
    rv = exr_finish(&ctx); // writes the chunk offset table
    if (rv != EXR_ERR_SUCCESS || s->io_errno != 0) {
        return write_failed(path, s, rv, "", err);
    }
    return WX_OK;
}

wx_result wx_exr_write(const char *path, const wx_image *image, wx_error *err)
{
    wx_result result = check_image(path, image, err);
    if (result != WX_OK) {
        return result;
    }
    const char *slash = strrchr(path, '/');
    if ((slash != NULL ? slash[1] : path[0]) == '\0') {
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "%s: not a file name", path);
    }
    char tmp_path[WX_PATH_MAX];
    wx_temp_path(path, tmp_path);

    exr_stream s;
    memset(&s, 0, sizeof s);
    s.fd = open(tmp_path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (s.fd < 0) {
        return wx_fail(err, WX_CAUSE_IO, "%s: cannot create %s (%s)", path, tmp_path,
                       strerror(errno));
    }
    wx_temp_created(tmp_path);
    exr_stream *outer = wx_exr_stream_bind(&s);
    result = write_body(&s, path, tmp_path, image, err);
    wx_exr_stream_unbind(outer);
    if (close(s.fd) != 0 && result == WX_OK) {
        result = wx_fail(err, WX_CAUSE_IO, "%s: cannot write (%s)", path, strerror(errno));
    }
    if (result != WX_OK) {
        unlink(tmp_path);
        return result;
    }
    // Flushes to disk and renames over the final name; removes the temporary on failure.
    return wx_atomic_commit(tmp_path, path, err);
}
