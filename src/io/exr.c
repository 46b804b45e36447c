// exr.c: float maps in and out of OpenEXR files with the OpenEXR Core C API.
//
// The library does the file I/O through our own read/write callbacks on a file
// descriptor we opened: that gives clear "cannot open" messages, an fsync before
// the rename of a written file, and a place (the stream) where the library's
// error messages are collected instead of being printed on stderr.
//
// Reading checks every size in the header before anything is allocated and then
// decodes chunk by chunk straight into the caller's planes (the library converts
// half to float while unpacking). Only the first part of a file is read; tiled and
// deep parts are refused. A data window whose origin is not (0, 0) is accepted: the
// image is the data window, its top scanline is row 0, the origin is dropped.
//
// This file reads, and holds the stream both directions use; exr_write.c
// writes (exr_internal.h).
#include "io/exr.h"
#include "core/big_alloc.h"

#include "core/atomic_file.h"
#include "core/input_file.h"
#include "core/parallel.h"

#include <assert.h>
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
// Stream: our file descriptor, plus what went wrong (errno, library message).

void wx_exr_stream_reset(exr_stream *s)
{
    s->io_errno = 0;
    s->message[0] = '\0';
}

// The stream of the file this thread is reading or writing, where the error
// handler records the library's message. The handler must not ask the library
// for it (exr_get_user_data): OpenEXR calls the handler while it holds the
// context's lock, and asking again waits on that lock forever (a channel name
// over 31 characters hung every run this way, issue 24). A worker thread of a
// parallel decode or encode has none bound: its messages are dropped, and the
// failure is reported with the library's default message for its code.
static _Thread_local exr_stream *bound_stream;

// Binds `s` to the calling thread; returns the stream bound before, for wx_exr_stream_unbind.
exr_stream *wx_exr_stream_bind(exr_stream *s)
{
    exr_stream *outer = bound_stream;
    bound_stream = s;
    return outer;
}

void wx_exr_stream_unbind(exr_stream *outer)
{
    bound_stream = outer;
}

void wx_exr_stream_on_error(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt; // never call into the library from here (see bound_stream)
    exr_stream *s = bound_stream;
    if (s == NULL) {
        return;
    }
    if (!s->quiet && s->message[0] == '\0') {
        snprintf(s->message, sizeof s->message, "%s",
                 msg != NULL ? msg : exr_get_default_error_message(code));
        // The library quotes bytes of a corrupt header: keep the message one
        // printable line.
        for (char *c = s->message; *c != '\0'; ++c) {
            if ((unsigned char)*c < 0x20 || (unsigned char)*c >= 0x7f) {
                *c = '?';
            }
        }
    }
}

// Reads or writes `size` bytes at `offset` of the stream's file, retrying short
// transfers. A read stops at the end of the file (the library reports the short
// read); a write that makes no progress is an error (EIO).
static int64_t stream_transfer(exr_stream *s, uint8_t *bytes, uint64_t size, uint64_t offset,
                               bool write)
{
    if (size > (uint64_t)INT64_MAX || offset > (uint64_t)INT64_MAX - size) {
        return -1;
    }
    uint64_t done = 0;
    while (done < size) {
        size_t want = (size_t)(size - done);
        off_t at = (off_t)(offset + done);
        ssize_t n =
            write ? pwrite(s->fd, bytes + done, want, at) : pread(s->fd, bytes + done, want, at);
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n < 0 || (n == 0 && write)) {
            if (!s->quiet && s->io_errno == 0) {
                s->io_errno = n < 0 ? errno : EIO;
            }
            return -1;
        }
        if (n == 0) {
            break;
        }
        done += (uint64_t)n;
    }
    return (int64_t)done;
}

static int64_t stream_read(exr_const_context_t ctxt, void *user, void *buffer, uint64_t size,
                           uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    (void)ctxt;
    (void)error_cb;
    return stream_transfer(user, buffer, size, offset, false);
}

static int64_t stream_size(exr_const_context_t ctxt, void *user)
{
    (void)ctxt;
    exr_stream *s = user;
    struct stat st;
    if (fstat(s->fd, &st) != 0) {
        return -1;
    }
    return (int64_t)st.st_size;
}

int64_t wx_exr_stream_write(exr_const_context_t ctxt, void *user, const void *buffer, uint64_t size,
                            uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    (void)ctxt;
    (void)error_cb;
    return stream_transfer(user, (uint8_t *)(uintptr_t)buffer, size, offset, true);
}

const char *wx_exr_stream_detail(const exr_stream *s, exr_result_t rv)
{
    if (s->io_errno != 0) {
        return strerror(s->io_errno);
    }
    if (s->message[0] != '\0') {
        return s->message;
    }
    return exr_get_default_error_message(rv);
}

// ---------------------------------------------------------------------------
// Opening a file for reading and checking its header.

typedef struct exr_reader {
    exr_stream stream;
    exr_context_t ctx;
    int width;
    int height;
    int min_y; // data window origin: file scanline of row 0
    bool bound;               // the stream is bound to this thread (wx_exr_stream_bind)
    exr_stream *outer_stream; // what was bound before
} exr_reader;

static void reader_close(exr_reader *r)
{
    exr_finish(&r->ctx); // safe on NULL
    if (r->stream.fd >= 0) {
        close(r->stream.fd);
        r->stream.fd = -1;
    }
    if (r->bound) {
        wx_exr_stream_unbind(r->outer_stream);
        r->bound = false;
    }
}

static const uint8_t exr_magic[4] = {0x76, 0x2f, 0x31, 0x01};

// Opens `path`, parses the header and checks the part type and the data window.
// On failure everything is released and the message names the file.
static wx_result reader_open(exr_reader *r, const char *path, wx_error *err)
{
    memset(r, 0, sizeof *r);
    r->outer_stream = wx_exr_stream_bind(&r->stream);
    r->bound = true;
    char why[WX_INPUT_WHY_MAX];
    wx_cause cause = WX_CAUSE_NONE;
    r->stream.fd = wx_open_regular(path, why, &cause); // a FIFO is refused, never waited on
    if (r->stream.fd < 0) {
        reader_close(r);
        return wx_fail(err, cause, "%s: %s", path, why);
    }
    struct stat st;
    if (fstat(r->stream.fd, &st) != 0) {
        int e = errno;
        reader_close(r);
        return wx_fail(err, WX_CAUSE_UNREADABLE, "%s: cannot open (%s)", path, strerror(e));
    }
    uint8_t magic[4];
    int64_t got = stream_read(NULL, &r->stream, magic, sizeof magic, 0, NULL);
    if (got != (int64_t)sizeof magic || memcmp(magic, exr_magic, sizeof magic) != 0) {
        reader_close(r);
        if (got < 0) {
            return wx_fail(err, WX_CAUSE_UNREADABLE, "%s: cannot read (%s)", path,
                                strerror(r->stream.io_errno));
        }
        return wx_fail(err, WX_CAUSE_BAD_MAP, "%s: not an OpenEXR file%s", path,
                            st.st_size == 0 ? " (empty file)" : "");
    }

    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = wx_exr_stream_on_error;
    init.user_data = &r->stream;
    init.read_fn = stream_read;
    init.size_fn = stream_size;
    init.flags = EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;
    wx_exr_stream_reset(&r->stream);
    exr_result_t rv = exr_start_read(&r->ctx, path, &init);
    if (rv != EXR_ERR_SUCCESS) {
        wx_cause failure = rv == EXR_ERR_OUT_OF_MEMORY ? WX_CAUSE_OUT_OF_MEMORY : WX_CAUSE_BAD_MAP;
        wx_result code = wx_fail(err, failure, "%s: corrupt OpenEXR header (%s)", path,
                                 wx_exr_stream_detail(&r->stream, rv));
        reader_close(r);
        return code;
    }

    exr_storage_t storage = EXR_STORAGE_LAST_TYPE;
    exr_attr_box2i_t dw;
    if (exr_get_storage(r->ctx, 0, &storage) != EXR_ERR_SUCCESS ||
        exr_get_data_window(r->ctx, 0, &dw) != EXR_ERR_SUCCESS) {
        reader_close(r);
        return wx_fail(err, WX_CAUSE_BAD_MAP, "%s: corrupt OpenEXR header", path);
    }
    if (storage != EXR_STORAGE_SCANLINE) {
        reader_close(r);
        return wx_fail(err, WX_CAUSE_BAD_MAP,
                       "%s: %s OpenEXR files are not supported (write scanline files)", path,
                       storage == EXR_STORAGE_TILED ? "tiled" : "deep");
    }
    int64_t width = (int64_t)dw.max.x - (int64_t)dw.min.x + 1;
    int64_t height = (int64_t)dw.max.y - (int64_t)dw.min.y + 1;
    if (width <= 0 || height <= 0) {
        reader_close(r);
        return wx_fail(err, WX_CAUSE_BAD_MAP, "%s: empty data window (%d %d - %d %d)", path,
                            dw.min.x, dw.min.y, dw.max.x, dw.max.y);
    }
    if (width > WX_MAP_MAX_SIDE || height > WX_MAP_MAX_SIDE || width * height > WX_MAP_MAX_TEXELS) {
        reader_close(r);
        return wx_fail(err, WX_CAUSE_MAP_SIZE,
                       "%s: %lld x %lld exceeds the largest map size %d x %d", path,
                       (long long)width, (long long)height, WX_MAP_MAX_SIDE, WX_MAP_MAX_SIDE);
    }
    r->width = (int)width;
    r->height = (int)height;
    r->min_y = dw.min.y;
    return WX_OK;
}

static void copy_string(char *dst, size_t cap, const exr_attr_string_t *s)
{
    int len = s->length < 0 ? 0 : s->length;
    snprintf(dst, cap, "%.*s", len, s->str != NULL ? s->str : "");
}

// Collects the m44f and string attributes of part 0 (file order) into out->attrs.
static void reader_collect_attrs(exr_reader *r, wx_image *out)
{
    int32_t count = 0;
    if (exr_get_attribute_count(r->ctx, 0, &count) != EXR_ERR_SUCCESS) {
        return;
    }
    for (int32_t i = 0; i < count && out->attr_count < WX_IMAGE_MAX_ATTRS; i++) {
        const exr_attribute_t *a = NULL;
        if (exr_get_attribute_by_index(r->ctx, 0, EXR_ATTR_LIST_FILE_ORDER, i, &a) !=
                EXR_ERR_SUCCESS ||
            a == NULL || a->name == NULL || strlen(a->name) >= WX_NAME_MAX ||
            strcmp(a->name, "type") == 0 || strcmp(a->name, "name") == 0) {
            continue; // "type" and "name" describe the part, they are not map data
        }
        if (a->type == EXR_ATTR_M44F && a->m44f != NULL) {
            wx_attr *dst = &out->attrs[out->attr_count++];
            memset(dst, 0, sizeof *dst);
            snprintf(dst->name, sizeof dst->name, "%s", a->name);
            dst->type = WX_ATTR_M44F;
            memcpy(dst->m44f, a->m44f->m, sizeof dst->m44f);
        } else if (a->type == EXR_ATTR_STRING && a->string != NULL) {
            wx_attr *dst = &out->attrs[out->attr_count++];
            memset(dst, 0, sizeof *dst);
            snprintf(dst->name, sizeof dst->name, "%s", a->name);
            dst->type = WX_ATTR_STRING;
            copy_string(dst->string, sizeof dst->string, a->string);
        }
    }
}

static bool name_equals(const exr_attr_string_t *s, const char *name, size_t len)
{
    return s->length >= 0 && (size_t)s->length == len && s->str != NULL &&
           memcmp(s->str, name, len) == 0;
}

// "B, G, R" into buf.
static void list_channels(const exr_attr_chlist_t *chlist, char *buf, size_t cap)
{
    size_t used = 0;
    buf[0] = '\0';
    for (int c = 0; c < chlist->num_channels && used + 1 < cap; c++) {
        const exr_attr_string_t *n = &chlist->entries[c].name;
        int w = snprintf(buf + used, cap - used, "%s%.*s", c > 0 ? ", " : "",
                         n->length < 0 ? 0 : n->length, n->str != NULL ? n->str : "");
        if (w < 0) {
            break;
        }
        used += (size_t)w;
    }
    if (chlist->num_channels == 0) {
        snprintf(buf, cap, "none");
    }
}

// "R or Z" into buf.
static void list_alternatives(const char *wanted, char *buf, size_t cap)
{
    size_t used = 0;
    buf[0] = '\0';
    for (const char *p = wanted; used + 1 < cap;) {
        const char *bar = strchr(p, '|');
        size_t len = bar != NULL ? (size_t)(bar - p) : strlen(p);
        int w = snprintf(buf + used, cap - used, "%s%.*s", p == wanted ? "" : " or ", (int)len, p);
        if (w < 0 || bar == NULL) {
            break;
        }
        used += (size_t)w;
        p = bar + 1;
    }
}

// Finds the channel for `wanted` ("R|Z": the first alternative the file has).
// Returns its index in the channel list, or -1 with the error set.
/// Channel c when its pixels can be read as floats, else -1 with the reason.
static int check_channel(const char *path, const exr_attr_chlist_t *chlist, int c, wx_error *err)
{
    const exr_attr_chlist_entry_t *e = &chlist->entries[c];
    int len = e->name.length > 0 ? e->name.length : 0;
    const char *name = e->name.str != NULL ? e->name.str : "";
    if (e->pixel_type != EXR_PIXEL_FLOAT && e->pixel_type != EXR_PIXEL_HALF) {
        wx_fail(err, WX_CAUSE_BAD_MAP, "%s: channel %.*s holds integers (float or half expected)",
                path, len, name);
        return -1;
    }
    if (e->x_sampling != 1 || e->y_sampling != 1) {
        wx_fail(err, WX_CAUSE_BAD_MAP,
                "%s: channel %.*s is subsampled (%d x %d), which is not supported", path, len,
                name, e->x_sampling, e->y_sampling);
        return -1;
    }
    return c;
}

static int find_channel(const char *path, const exr_attr_chlist_t *chlist, const char *wanted,
                        wx_error *err)
{
    for (const char *p = wanted;;) {
        const char *bar = strchr(p, '|');
        size_t len = bar != NULL ? (size_t)(bar - p) : strlen(p);
        for (int c = 0; c < chlist->num_channels; c++) {
            if (name_equals(&chlist->entries[c].name, p, len)) {
                return check_channel(path, chlist, c, err);
            }
        }
        if (bar == NULL) {
            break;
        }
        p = bar + 1;
    }
    char alternatives[256];
    char has[512];
    list_alternatives(wanted, alternatives, sizeof alternatives);
    list_channels(chlist, has, sizeof has);
    wx_fail(err, WX_CAUSE_BAD_MAP, "%s: no channel %s (has: %s)", path, alternatives, has);
    return -1;
}

// One channel to decode: texel (i, j) of channel `name` goes to base[(j*width+i)*stride].
typedef struct read_target {
    const exr_attr_string_t *name;
    float *base;
    int stride;
} read_target;

// Decodes the chunk of part 0 that starts at data-window row `row` into the
// targets with pipeline `dec` (initialised on its first chunk).
static exr_result_t decode_chunk(exr_reader *r, const read_target *targets, int target_count,
                                 int64_t row, exr_decode_pipeline_t *dec, bool *initialized,
                                 exr_chunk_info_t *ci)
{
    const size_t width = (size_t)r->width;
    memset(ci, 0, sizeof *ci);
    exr_result_t rv = exr_read_scanline_chunk_info(r->ctx, 0, (int)(r->min_y + row), ci);
    if (rv == EXR_ERR_SUCCESS) {
        rv = *initialized ? exr_decoding_update(r->ctx, 0, ci, dec)
                          : exr_decoding_initialize(r->ctx, 0, ci, dec);
        *initialized = true;
    }
    if (rv == EXR_ERR_SUCCESS) {
        // The chunk must lie inside the data window: never write outside the planes.
        int64_t chunk_row = (int64_t)ci->start_y - r->min_y;
        if (ci->width != r->width || chunk_row != row || ci->height <= 0 ||
            chunk_row + ci->height > r->height) {
            rv = EXR_ERR_CORRUPT_CHUNK;
        }
        for (int c = 0; rv == EXR_ERR_SUCCESS && c < dec->channel_count; c++) {
            exr_coding_channel_info_t *ch = &dec->channels[c];
            ch->decode_to_ptr = NULL;
            for (int t = 0; t < target_count; t++) {
                const exr_attr_string_t *n = targets[t].name;
                if (ch->channel_name == NULL ||
                    !name_equals(n, ch->channel_name, strlen(ch->channel_name))) {
                    continue;
                }
                size_t stride = (size_t)targets[t].stride;
                ch->decode_to_ptr = (uint8_t *)(targets[t].base + (size_t)row * width * stride);
                ch->user_pixel_stride = (int32_t)(stride * sizeof(float));
                ch->user_line_stride = (int32_t)(width * stride * sizeof(float));
                ch->user_data_type = EXR_PIXEL_FLOAT;
                ch->user_bytes_per_element = (int16_t)sizeof(float);
                if (ch->height != ci->height || ch->width != r->width) {
                    rv = EXR_ERR_CORRUPT_CHUNK;
                }
            }
        }
    }
    if (rv == EXR_ERR_SUCCESS) {
        rv = exr_decoding_choose_default_routines(r->ctx, 0, dec);
    }
    if (rv == EXR_ERR_SUCCESS) {
        rv = exr_decoding_run(r->ctx, 0, dec);
    }
    return rv;
}

// Decodes every chunk of part 0 into the targets, one after the other; a
// failure names the chunk's scanlines.
static wx_result decode_serial(exr_reader *r, const char *path, const read_target *targets,
                               int target_count, int32_t lines, wx_error *err)
{
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    bool initialized = false;
    wx_result result = WX_OK;
    for (int64_t row = 0; row < r->height; row += lines) {
        int64_t last = row + lines - 1 < r->height - 1 ? row + lines - 1 : r->height - 1;
        exr_chunk_info_t ci;
        wx_exr_stream_reset(&r->stream);
        exr_result_t rv = decode_chunk(r, targets, target_count, row, &dec, &initialized, &ci);
        if (rv == EXR_ERR_OUT_OF_MEMORY) {
            // The decoders also say "out of memory" for corrupt compressed data
            // (found by fuzzing: a B44A chunk): it is one only if a buffer twice
            // the chunk's size cannot be had either.
            void *probe = ci.unpacked_size < ((uint64_t)1 << 40)
                              ? malloc(2 * (size_t)ci.unpacked_size + 1)
                              : NULL;
            if (probe != NULL) {
                rv = EXR_ERR_CORRUPT_CHUNK;
            }
            free(probe);
        }
        if (rv != EXR_ERR_SUCCESS) {
            if (rv == EXR_ERR_OUT_OF_MEMORY) {
                result = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY,
                                 "%s: out of memory (reading scanlines %lld-%lld)", path,
                                 (long long)row, (long long)last);
            } else {
                result =
                    wx_fail(err, WX_CAUSE_BAD_MAP,
                            "%s: truncated or corrupt (reading scanlines %lld-%lld: %s)", path,
                            (long long)row, (long long)last, wx_exr_stream_detail(&r->stream, rv));
            }
            break;
        }
    }
    if (initialized) {
        exr_decoding_destroy(r->ctx, &dec);
    }
    return result;
}

// The chunks of one read, decoded by the workers of wx_parallel_for: each
// worker has its own pipeline; every chunk writes its own rows of the planes.
typedef struct decode_batch {
    exr_reader *r;
    const read_target *targets;
    int target_count;
    int32_t lines;
    exr_decode_pipeline_t *pipelines; // one per worker
    bool *initialized;
    _Atomic bool failed;
} decode_batch;

static void decode_chunks(int64_t begin, int64_t end, int worker, void *context)
{
    decode_batch *b = context;
    for (int64_t k = begin; k < end && !atomic_load(&b->failed); ++k) {
        exr_chunk_info_t ci;
        exr_result_t rv = decode_chunk(b->r, b->targets, b->target_count, k * b->lines,
                                       &b->pipelines[worker], &b->initialized[worker], &ci);
        if (rv != EXR_ERR_SUCCESS) {
            atomic_store(&b->failed, true);
        }
    }
}

// Decodes every chunk of part 0 into the targets, on `threads` workers; the
// planes are the same for any count. A failure is decoded again in order on
// one thread, which gives the message a serial read gives.
static wx_result reader_decode(exr_reader *r, const char *path, const read_target *targets,
                               int target_count, int threads, wx_error *err)
{
    int32_t lines = 0;
    if (exr_get_scanlines_per_chunk(r->ctx, 0, &lines) != EXR_ERR_SUCCESS || lines <= 0) {
        return wx_fail(err, WX_CAUSE_BAD_MAP, "%s: corrupt OpenEXR header", path);
    }
    int64_t chunks = (r->height + lines - 1) / lines;
    if (threads <= 1 || chunks < 2) {
        return decode_serial(r, path, targets, target_count, lines, err);
    }
    threads = chunks < threads ? (int)chunks : threads;
    decode_batch b = { .r = r, .targets = targets, .target_count = target_count, .lines = lines };
    b.pipelines = malloc((size_t)threads * sizeof *b.pipelines);
    b.initialized = calloc((size_t)threads, sizeof *b.initialized);
    if (b.pipelines == NULL || b.initialized == NULL) {
        free(b.pipelines);
        free(b.initialized);
        return decode_serial(r, path, targets, target_count, lines, err);
    }
    for (int w = 0; w < threads; ++w) {
        b.pipelines[w] = (exr_decode_pipeline_t)EXR_DECODE_PIPELINE_INITIALIZER;
    }
    atomic_init(&b.failed, false);
    r->stream.quiet = true;
    wx_parallel_for(threads, chunks, 1, decode_chunks, &b);
    r->stream.quiet = false;
    for (int w = 0; w < threads; ++w) {
        if (b.initialized[w]) {
            exr_decoding_destroy(r->ctx, &b.pipelines[w]);
        }
    }
    bool failed = atomic_load(&b.failed);
    free(b.pipelines);
    free(b.initialized);
    return failed ? decode_serial(r, path, targets, target_count, lines, err) : WX_OK;
}

// reader_open, then the channel list of part 0.
static wx_result reader_open_channels(exr_reader *r, const char *path,
                                      const exr_attr_chlist_t **chlist, wx_error *err)
{
    wx_result result = reader_open(r, path, err);
    if (result != WX_OK) {
        return result;
    }
    *chlist = NULL;
    if (exr_get_channels(r->ctx, 0, chlist) != EXR_ERR_SUCCESS || *chlist == NULL) {
        reader_close(r);
        return wx_fail(err, WX_CAUSE_BAD_MAP, "%s: corrupt OpenEXR header (no channel list)",
                       path);
    }
    return WX_OK;
}

// Reads the wanted channels of `path`. With `planar`, each channel into its own plane
// out->channels[i]; otherwise into one interleaved buffer returned in *interleaved.
static wx_result read_channels(const char *path, const char *const *wanted, int wanted_count,
                               bool planar, int threads, wx_image *out, float **interleaved,
                               wx_error *err)
{
    if ((wanted != NULL && wanted_count < 1) || wanted_count > WX_IMAGE_MAX_CHANNELS) {
        return wx_fail(err, WX_CAUSE_INTERNAL, "%s: cannot read %d channels (1 to %d)", path,
                            wanted_count, WX_IMAGE_MAX_CHANNELS);
    }
    exr_reader r;
    const exr_attr_chlist_t *chlist = NULL;
    wx_result result = reader_open_channels(&r, path, &chlist, err);
    if (result != WX_OK) {
        return result;
    }
    if (wanted == NULL) { // every channel, in the file's order
        wanted_count = chlist->num_channels;
        if (wanted_count > WX_IMAGE_MAX_CHANNELS) {
            reader_close(&r);
            return wx_fail(err, WX_CAUSE_BAD_MAP, "%s: %d channels, more than the %d supported",
                           path, wanted_count, WX_IMAGE_MAX_CHANNELS);
        }
    }
    read_target targets[WX_IMAGE_MAX_CHANNELS];
    for (int i = 0; i < wanted_count; i++) {
        // (entry i exists only when every channel is read, in the file's order)
        int length = wanted == NULL ? chlist->entries[i].name.length : 0;
        if (wanted == NULL && length >= WX_NAME_MAX) {
            reader_close(&r); // frees chlist
            return wx_fail(err, WX_CAUSE_BAD_MAP,
                           "%s: channel %d's name has %d characters, more than the %d supported",
                           path, i + 1, length, WX_NAME_MAX - 1);
        }
        int c = wanted != NULL ? find_channel(path, chlist, wanted[i], err)
                               : check_channel(path, chlist, i, err);
        if (c < 0) {
            reader_close(&r);
            return WX_BAD_INPUT;
        }
        for (int k = 0; k < i; k++) {
            if (targets[k].name == &chlist->entries[c].name) {
                reader_close(&r);
                return wx_fail(err, WX_CAUSE_INTERNAL, "%s: channel %s asked for twice", path,
                                    out->channel_names[k]);
            }
        }
        targets[i].name = &chlist->entries[c].name;
        targets[i].stride = planar ? 1 : wanted_count;
        targets[i].base = NULL;
        copy_string(out->channel_names[i], sizeof out->channel_names[i], targets[i].name);
    }

    // The chunk table is read and checked against the file size with the first
    // chunk: do it before allocating, so a small broken file costs no memory.
    exr_chunk_info_t first;
    wx_exr_stream_reset(&r.stream);
    exr_result_t rv = exr_read_scanline_chunk_info(r.ctx, 0, r.min_y, &first);
    if (rv != EXR_ERR_SUCCESS) {
        result =
            wx_fail(err, rv == EXR_ERR_OUT_OF_MEMORY ? WX_CAUSE_OUT_OF_MEMORY : WX_CAUSE_BAD_MAP,
                    "%s: truncated or corrupt (reading the chunk table: %s)", path,
                    wx_exr_stream_detail(&r.stream, rv));
        reader_close(&r);
        return result;
    }

    // Sizes were checked in reader_open: texels <= 2^28, so no overflow below.
    size_t texels = (size_t)r.width * (size_t)r.height;
    if (planar) {
        for (int i = 0; i < wanted_count; i++) {
            out->channels[i] = wx_big_malloc(texels * sizeof(float));
            if (out->channels[i] == NULL) {
                result = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY,
                                 "%s: out of memory for %d x %d texels", path, r.width, r.height);
                break;
            }
            targets[i].base = out->channels[i];
        }
    } else {
        *interleaved = wx_big_malloc(texels * (size_t)wanted_count * sizeof(float));
        if (*interleaved == NULL) {
            result = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory for %d x %d texels",
                             path, r.width, r.height);
        }
        for (int i = 0; i < wanted_count && result == WX_OK; i++) {
            targets[i].base = *interleaved + i;
        }
    }
    if (result == WX_OK) {
        result = reader_decode(&r, path, targets, wanted_count, threads, err);
    }
    if (result == WX_OK) {
        out->width = r.width;
        out->height = r.height;
        out->channel_count = wanted_count;
        reader_collect_attrs(&r, out);
    }
    reader_close(&r);
    return result;
}

wx_result wx_exr_read_header(const char *path, wx_image *out, wx_error *err)
{
    memset(out, 0, sizeof *out);
    exr_reader r;
    const exr_attr_chlist_t *chlist = NULL;
    wx_result result = reader_open_channels(&r, path, &chlist, err);
    if (result != WX_OK) {
        return result;
    }
    if (chlist->num_channels > WX_IMAGE_MAX_CHANNELS) {
        reader_close(&r);
        return wx_fail(err, WX_CAUSE_BAD_MAP, "%s: %d channels, more than the %d supported", path,
                            chlist->num_channels, WX_IMAGE_MAX_CHANNELS);
    }
    for (int c = 0; c < chlist->num_channels; c++) {
        const exr_attr_string_t *name = &chlist->entries[c].name;
        int length = name->length;
        if (length >= WX_NAME_MAX) {
            reader_close(&r); // frees chlist
            return wx_fail(err, WX_CAUSE_BAD_MAP,
                           "%s: channel %d's name has %d characters, more than the %d supported",
                           path, c + 1, length, WX_NAME_MAX - 1);
        }
        copy_string(out->channel_names[c], sizeof out->channel_names[c], name);
    }
    out->channel_count = chlist->num_channels;
    out->width = r.width;
    out->height = r.height;
    reader_collect_attrs(&r, out);
    reader_close(&r);
    return WX_OK;
}

wx_result wx_exr_read(const char *path, const char *const *wanted, int wanted_count, wx_image *out,
                      wx_error *err)
{
    return wx_exr_read_parallel(path, wanted, wanted_count, 1, out, err);
}

wx_result wx_exr_read_all(const char *path, wx_image *out, wx_error *err)
{
    return wx_exr_read_parallel(path, NULL, 0, 1, out, err);
}

wx_result wx_exr_read_parallel(const char *path, const char *const *wanted, int wanted_count,
                               int threads, wx_image *out, wx_error *err)
{
    memset(out, 0, sizeof *out);
    wx_result result = read_channels(path, wanted, wanted_count, true, threads, out, NULL, err);
    if (result != WX_OK) {
        wx_image_free(out);
    }
    return result;
}

wx_result wx_exr_read_interleaved(const char *path, const char *const *wanted, int wanted_count,
                                  int threads, float **out_texels, int *out_width,
                                  int *out_height, wx_error *err)
{
    *out_texels = NULL;
    *out_width = 0;
    *out_height = 0;
    wx_image *info = malloc(sizeof *info); // large (attributes): keep it off the stack
    if (info == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    memset(info, 0, sizeof *info);
    float *texels = NULL;
    wx_result result =
        read_channels(path, wanted, wanted_count, false, threads, info, &texels, err);
    if (result == WX_OK) {
        *out_texels = texels;
        *out_width = info->width;
        *out_height = info->height;
    } else {
        free(texels);
    }
    free(info);
    return result;
}
