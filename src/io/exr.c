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
#include "io/exr.h"

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


// ---------------------------------------------------------------------------
// Stream: our file descriptor, plus what went wrong (errno, library message).

typedef struct exr_stream {
    int fd;
    int io_errno;      // errno of the first failed read or write, 0 if none
    char message[512]; // first library message since the last stream_reset
    // While chunks are decoded on several threads nothing is recorded (a
    // failure is decoded again on one thread, which records it).
    bool quiet;
} exr_stream;

static void stream_reset(exr_stream *s)
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

// Binds `s` to the calling thread; returns the stream bound before, for stream_unbind.
static exr_stream *stream_bind(exr_stream *s)
{
    exr_stream *outer = bound_stream;
    bound_stream = s;
    return outer;
}

static void stream_unbind(exr_stream *outer)
{
    bound_stream = outer;
}

static void stream_on_error(exr_const_context_t ctxt, exr_result_t code, const char *msg)
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

static int64_t stream_write(exr_const_context_t ctxt, void *user, const void *buffer, uint64_t size,
                            uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    (void)ctxt;
    (void)error_cb;
    return stream_transfer(user, (uint8_t *)(uintptr_t)buffer, size, offset, true);
}

static const char *stream_detail(const exr_stream *s, exr_result_t rv)
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
    bool bound;               // the stream is bound to this thread (stream_bind)
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
        stream_unbind(r->outer_stream);
        r->bound = false;
    }
}

static const uint8_t exr_magic[4] = {0x76, 0x2f, 0x31, 0x01};

// Opens `path`, parses the header and checks the part type and the data window.
// On failure everything is released and the message names the file.
static wx_result reader_open(exr_reader *r, const char *path, wx_error *err)
{
    memset(r, 0, sizeof *r);
    r->outer_stream = stream_bind(&r->stream);
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
    init.error_handler_fn = stream_on_error;
    init.user_data = &r->stream;
    init.read_fn = stream_read;
    init.size_fn = stream_size;
    init.flags = EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;
    stream_reset(&r->stream);
    exr_result_t rv = exr_start_read(&r->ctx, path, &init);
    if (rv != EXR_ERR_SUCCESS) {
        wx_cause failure = rv == EXR_ERR_OUT_OF_MEMORY ? WX_CAUSE_OUT_OF_MEMORY : WX_CAUSE_BAD_MAP;
        wx_result code = wx_fail(err, failure, "%s: corrupt OpenEXR header (%s)", path,
                                 stream_detail(&r->stream, rv));
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
        stream_reset(&r->stream);
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
                result = wx_fail(err, WX_CAUSE_BAD_MAP,
                                 "%s: truncated or corrupt (reading scanlines %lld-%lld: %s)", path,
                                 (long long)row, (long long)last, stream_detail(&r->stream, rv));
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
    stream_reset(&r.stream);
    exr_result_t rv = exr_read_scanline_chunk_info(r.ctx, 0, r.min_y, &first);
    if (rv != EXR_ERR_SUCCESS) {
        result =
            wx_fail(err, rv == EXR_ERR_OUT_OF_MEMORY ? WX_CAUSE_OUT_OF_MEMORY : WX_CAUSE_BAD_MAP,
                    "%s: truncated or corrupt (reading the chunk table: %s)", path,
                    stream_detail(&r.stream, rv));
        reader_close(&r);
        return result;
    }

    // Sizes were checked in reader_open: texels <= 2^28, so no overflow below.
    size_t texels = (size_t)r.width * (size_t)r.height;
    if (planar) {
        for (int i = 0; i < wanted_count; i++) {
            out->channels[i] = malloc(texels * sizeof(float));
            if (out->channels[i] == NULL) {
                result = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY,
                                 "%s: out of memory for %d x %d texels", path, r.width, r.height);
                break;
            }
            targets[i].base = out->channels[i];
        }
    } else {
        *interleaved = malloc(texels * (size_t)wanted_count * sizeof(float));
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
    int y;          ///< first scanline
    void *data;     ///< malloc'd copy of the compressed (or raw) chunk
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
    const void *bytes = enc->compressed_buffer != NULL ? enc->compressed_buffer
                                                       : enc->packed_buffer;
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
                        stream_detail(s, rv));
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
    exr_result_t rv = batch.workers != NULL && batch.slots != NULL ? EXR_ERR_SUCCESS
                                                                   : EXR_ERR_OUT_OF_MEMORY;
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
    init.error_handler_fn = stream_on_error;
    init.user_data = s;
    init.write_fn = stream_write;
    exr_context_t ctx = NULL;
    stream_reset(s);
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
            return wx_fail(err, WX_CAUSE_IO, "%s: cannot write attribute %s (%s)", path,
                                attr->name, stream_detail(s, rv));
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
    exr_stream *outer = stream_bind(&s);
    result = write_body(&s, path, tmp_path, image, err);
    stream_unbind(outer);
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
