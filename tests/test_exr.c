// test_exr.c: reading and writing float maps as OpenEXR files.
#include <dirent.h>
#include <errno.h>
#include <float.h>
#include <signal.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <openexr.h>

#include "ensure.h"
#include "io/exr.h"
#include "model/image.h"

// ---------------------------------------------------------------------------
// Helpers.

static uint32_t bits_of(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

static const char *path_in(const char *name)
{
    static char paths[8][4096];
    static int next;
    char *p = paths[next];
    next = (next + 1) % 8;
    snprintf(p, 4096, "%s/%s", ensure_tmpdir(), name);
    return p;
}

static bool write_bytes(const char *path, const void *bytes, size_t size)
{
    FILE *f = fopen(path, "wb");
    if (f == NULL) {
        return false;
    }
    bool ok = fwrite(bytes, 1, size, f) == size;
    return fclose(f) == 0 && ok;
}

// Reads a whole file; *size gets its length. NULL on failure.
static unsigned char *read_bytes(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        return NULL;
    }
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *bytes = malloc(n > 0 ? (size_t)n : 1);
    if (bytes != NULL && fread(bytes, 1, (size_t)n, f) != (size_t)n) {
        free(bytes);
        bytes = NULL;
    }
    fclose(f);
    *size = (size_t)n;
    return bytes;
}

// Number of entries of `dir` whose name starts with '.' and contains ".tmp";
// -1 when the folder cannot be read (never an empty folder's 0).
static int count_temporaries(const char *dir)
{
    DIR *d = opendir(dir);
    if (d == NULL) {
        fprintf(stderr, "        %s: cannot be read\n", dir);
        return -1;
    }
    int count = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        if (e->d_name[0] == '.' && strstr(e->d_name, ".tmp") != NULL) {
            count++;
        }
    }
    closedir(d);
    return count;
}

static void quiet_handler(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt;
    (void)code;
    (void)msg;
}

// An EXR written directly with the Core API, for what wx_exr_write never writes:
// half channels, other compressions, a shifted data window, tiles, decreasing y.
typedef struct raw_exr {
    int min_x, min_y, width, height;
    exr_compression_t compression;
    exr_pixel_type_t type; // EXR_PIXEL_HALF (uint16_t planes) or EXR_PIXEL_FLOAT
    exr_lineorder_t lineorder;
    bool tiled; // one tile holding the whole image
    int channel_count;
    const char *names[8];
    const void *planes[8]; // width*height values each, row 0 = top
} raw_exr;

static bool write_raw_exr(const char *path, const raw_exr *raw)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = quiet_handler;
    exr_context_t ctx = NULL;
    if (exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init) != EXR_ERR_SUCCESS) {
        return false;
    }
    int part = 0;
    exr_attr_box2i_t dw;
    dw.min.x = raw->min_x;
    dw.min.y = raw->min_y;
    dw.max.x = raw->min_x + raw->width - 1;
    dw.max.y = raw->min_y + raw->height - 1;
    exr_attr_v2f_t center;
    center.x = 0.0f;
    center.y = 0.0f;
    bool ok = exr_add_part(ctx, NULL, raw->tiled ? EXR_STORAGE_TILED : EXR_STORAGE_SCANLINE,
                           &part) == EXR_ERR_SUCCESS;
    ok = ok && exr_initialize_required_attr(ctx, part, &dw, &dw, 1.0f, &center, 1.0f,
                                            raw->lineorder, raw->compression) == EXR_ERR_SUCCESS;
    if (raw->tiled) {
        ok = ok &&
             exr_set_tile_descriptor(ctx, part, (uint32_t)raw->width, (uint32_t)raw->height,
                                     EXR_TILE_ONE_LEVEL, EXR_TILE_ROUND_DOWN) == EXR_ERR_SUCCESS;
    }
    for (int c = 0; ok && c < raw->channel_count; c++) {
        ok = exr_add_channel(ctx, part, raw->names[c], raw->type, EXR_PERCEPTUALLY_LINEAR, 1, 1) ==
             0;
    }
    ok = ok && exr_write_header(ctx) == EXR_ERR_SUCCESS;
    int32_t lines = raw->height;
    if (ok && !raw->tiled) {
        ok = exr_get_scanlines_per_chunk(ctx, part, &lines) == EXR_ERR_SUCCESS;
    }
    size_t bytes = raw->type == EXR_PIXEL_HALF ? 2 : 4;
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    bool started = false;
    // Core 3.1 takes the chunks in index order even for decreasing y.
    for (int row = 0; ok && row < raw->height; row += lines) {
        exr_chunk_info_t ci;
        ok = (raw->tiled ? exr_write_tile_chunk_info(ctx, part, 0, 0, 0, 0, &ci)
                         : exr_write_scanline_chunk_info(ctx, part, raw->min_y + row, &ci)) ==
             EXR_ERR_SUCCESS;
        ok = ok && (started ? exr_encoding_update(ctx, part, &ci, &enc)
                            : exr_encoding_initialize(ctx, part, &ci, &enc)) == EXR_ERR_SUCCESS;
        started = started || ok;
        for (int c = 0; ok && c < enc.channel_count; c++) {
            exr_coding_channel_info_t *ch = &enc.channels[c];
            for (int k = 0; k < raw->channel_count; k++) {
                if (strcmp(ch->channel_name, raw->names[k]) == 0) {
                    ch->encode_from_ptr =
                        (const uint8_t *)raw->planes[k] + (size_t)row * (size_t)raw->width * bytes;
                }
            }
            ch->user_pixel_stride = (int32_t)bytes;
            ch->user_line_stride = (int32_t)(bytes * (size_t)raw->width);
            ch->user_data_type = (uint16_t)raw->type;
            ch->user_bytes_per_element = (int16_t)bytes;
        }
        ok = ok && exr_encoding_choose_default_routines(ctx, part, &enc) == EXR_ERR_SUCCESS;
        ok = ok && exr_encoding_run(ctx, part, &enc) == EXR_ERR_SUCCESS;
    }
    if (started) {
        exr_encoding_destroy(ctx, &enc);
    }
    return exr_finish(&ctx) == EXR_ERR_SUCCESS && ok;
}

// A w x h float image whose channel c holds value(i, j, c) = 1000*c + 10*j + i.
static bool make_image(wx_image *image, int w, int h, int count, const char *const *names)
{
    if (wx_image_alloc(image, w, h, count, names, NULL) != WX_OK) {
        return false;
    }
    for (int c = 0; c < count; c++) {
        for (int j = 0; j < h; j++) {
            for (int i = 0; i < w; i++) {
                image->channels[c][j * w + i] = (float)(1000 * c + 10 * j + i);
            }
        }
    }
    return true;
}

// A valid 64 x 64 ZIP file with noisy data (so it does not compress to nothing).
static bool write_noisy_file(const char *path)
{
    static const char *const names[] = {"R"};
    wx_image image;
    if (wx_image_alloc(&image, 64, 64, 1, names, NULL) != WX_OK) {
        return false;
    }
    uint32_t state = 12345u;
    for (int t = 0; t < 64 * 64; t++) {
        state = state * 1664525u + 1013904223u;
        image.channels[0][t] = (float)(state >> 8) / 16777216.0f;
    }
    bool ok = wx_exr_write(path, &image, NULL) == WX_OK;
    wx_image_free(&image);
    return ok;
}

// Expects reading `path` to fail for `cause` (a bad input), a message naming the
// file and containing `needle`, and the image left empty; decoding the chunks
// on three threads fails the same way, with the same message.
static bool read_fails(const char *path, wx_cause cause, const char *needle)
{
    static const char *const wanted[] = {"R"};
    wx_image image, parallel;
    wx_error err = { 0 }, perr = { 0 };
    wx_result r = wx_exr_read(path, wanted, 1, &image, &err);
    wx_result pr = wx_exr_read_parallel(path, wanted, 1, 3, &parallel, &perr);
    bool ok = r == WX_BAD_INPUT && err.cause == cause && ensure_contains(err.message, path) &&
              ensure_contains(err.message, needle) && image.channels[0] == NULL && image.width == 0;
    bool same = pr == r && perr.cause == err.cause && strcmp(perr.message, err.message) == 0 &&
                parallel.channels[0] == NULL;
    if (!ok || !same) {
        fprintf(stderr, "    reading %s: result %d, cause %s, message \"%s\"\n", path, (int)r,
                wx_cause_name(err.cause), err.message);
        fprintf(stderr, "    on 3 threads: result %d, message \"%s\"\n", (int)pr, perr.message);
    }
    return ok && same;
}

// ---------------------------------------------------------------------------
// Round trips.

TEST(float_round_trip_is_bit_exact)
{
    enum { W = 37, H = 19 }; // 16-line ZIP chunks: one full, one partial
    static const char *const names[] = {"R", "G", "B", "Y", "Z"};
    wx_image image;
    ENSURE(make_image(&image, W, H, 5, names));
    // Special values in channel Y at known texels.
    float *y = image.channels[3];
    y[0] = INFINITY;
    y[1] = -INFINITY;
    y[2] = NAN;
    y[3] = -0.0f;
    y[4] = FLT_TRUE_MIN; // smallest denormal
    y[5] = 1e-40f;       // denormal
    y[6] = -FLT_MIN * 0.5f;
    y[7] = FLT_MAX;
    y[W * H - 1] = 0.1f; // last texel of the partial chunk
    const char *path = path_in("round.exr");
    wx_error err = { 0 };
    ENSURE(wx_exr_write(path, &image, &err) == WX_OK);

    static const char *const wanted[] = {"Z", "B", "Y", "R", "G"};
    static const int source[] = {4, 2, 3, 0, 1};
    wx_image back;
    ENSURE(wx_exr_read(path, wanted, 5, &back, &err) == WX_OK);
    ENSURE(back.width == W && back.height == H && back.channel_count == 5);
    int mismatches = 0;
    for (int c = 0; c < 5; c++) {
        ENSURE(strcmp(back.channel_names[c], wanted[c]) == 0);
        const float *a = image.channels[source[c]];
        const float *b = back.channels[c];
        for (int t = 0; t < W * H; t++) {
            bool same = isnan(a[t]) ? isnan(b[t]) : bits_of(a[t]) == bits_of(b[t]);
            mismatches += same ? 0 : 1;
        }
    }
    ENSURE(mismatches == 0);
    // Spot checks worked out by hand: Z (channel 4) at i=36, j=18; R at i=5, j=17.
    ENSURE(back.channels[0][18 * W + 36] == 4000.0f + 180.0f + 36.0f);
    ENSURE(back.channels[3][17 * W + 5] == 175.0f);
    ENSURE(bits_of(back.channels[2][3]) == 0x80000000u);
    ENSURE(bits_of(back.channels[2][4]) == 1u);
    ENSURE(isinf(back.channels[2][0]) && back.channels[2][0] > 0.0f);
    ENSURE(isnan(back.channels[2][2]));

    // The file stores the channels alphabetically.
    wx_image header;
    ENSURE(wx_exr_read_header(path, &header, &err) == WX_OK);
    ENSURE(header.width == W && header.height == H && header.channel_count == 5);
    ENSURE(header.channels[0] == NULL);
    ENSURE(strcmp(header.channel_names[0], "B") == 0 && strcmp(header.channel_names[1], "G") == 0 &&
           strcmp(header.channel_names[2], "R") == 0 && strcmp(header.channel_names[3], "Y") == 0 &&
           strcmp(header.channel_names[4], "Z") == 0);
    wx_image_free(&back);
    wx_image_free(&image);
}

TEST(interleaved_read_orders_channels_as_asked)
{
    enum { W = 5, H = 33 }; // three ZIP chunks, the last one of 1 line
    static const char *const names[] = {"R", "G", "B"};
    wx_image image;
    ENSURE(make_image(&image, W, H, 3, names));
    const char *path = path_in("interleaved.exr");
    ENSURE(wx_exr_write(path, &image, NULL) == WX_OK);
    wx_image_free(&image);

    static const char *const wanted[] = {"G", "B", "R"};
    float *texels = NULL;
    int w = 0;
    int h = 0;
    wx_error err = { 0 };
    ENSURE(wx_exr_read_interleaved(path, wanted, 3, 1, &texels, &w, &h, &err) == WX_OK);
    ENSURE(w == W && h == H);
    // Texel (i=4, j=32): G = 1000 + 324, B = 2000 + 324, R = 324.
    const float *t = texels + (32 * W + 4) * 3;
    bool right = t[0] == 1324.0f && t[1] == 2324.0f && t[2] == 324.0f;
    // Texel (i=1, j=16): first line of the second chunk.
    t = texels + (16 * W + 1) * 3;
    right = right && t[0] == 1161.0f && t[1] == 2161.0f && t[2] == 161.0f;
    free(texels);
    ENSURE(right);
}

TEST(half_channels_are_read_as_float)
{
    enum { W = 3, H = 2 };
    // Half bit patterns: 0.1 (0x2E66 = 0.0999755859375), 1.5, 1000, -2, 65504, +inf.
    static const uint16_t r[W * H] = {0x2E66, 0x3E00, 0x63D0, 0xC000, 0x7BFF, 0x7C00};
    static const uint16_t g[W * H] = {0x3C00, 0x4000, 0x4200, 0x4400, 0x4500, 0x0001};
    static const float want_r[W * H] = {0.1f, 1.5f, 1000.0f, -2.0f, 65504.0f, INFINITY};
    static const float want_g[W * H] = {1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 5.9604644775390625e-8f};
    const exr_compression_t compressions[] = {EXR_COMPRESSION_NONE, EXR_COMPRESSION_ZIP,
                                              EXR_COMPRESSION_PIZ, EXR_COMPRESSION_RLE};
    for (int k = 0; k < 4; k++) {
        raw_exr raw = {0};
        raw.width = W;
        raw.height = H;
        raw.compression = compressions[k];
        raw.type = EXR_PIXEL_HALF;
        raw.channel_count = 2;
        raw.names[0] = "R";
        raw.names[1] = "G";
        raw.planes[0] = r;
        raw.planes[1] = g;
        char name[64];
        snprintf(name, sizeof name, "half%d.exr", k);
        const char *path = path_in(name);
        ENSURE(write_raw_exr(path, &raw));

        static const char *const wanted[] = {"R", "G"};
        wx_image image;
        wx_error err = { 0 };
        ENSURE(wx_exr_read(path, wanted, 2, &image, &err) == WX_OK);
        bool right = image.width == W && image.height == H;
        for (int t = 0; right && t < W * H; t++) {
            float a = image.channels[0][t];
            float b = image.channels[1][t];
            right =
                isinf(want_r[t]) ? a == want_r[t] : fabsf(a - want_r[t]) < 1e-3f * fabsf(want_r[t]);
            right = right && fabsf(b - want_g[t]) <= 1e-3f * fabsf(want_g[t]);
        }
        wx_image_free(&image);
        ENSURE(right);
    }
}

TEST(other_float_compressions_and_decreasing_lines_are_read)
{
    enum { W = 7, H = 70 }; // PIZ: 32 lines a chunk, so three chunks
    float plane[W * H];
    for (int t = 0; t < W * H; t++) {
        plane[t] = (float)t * 0.25f - 3.0f;
    }
    const exr_compression_t compressions[] = {EXR_COMPRESSION_PIZ, EXR_COMPRESSION_RLE,
                                              EXR_COMPRESSION_NONE, EXR_COMPRESSION_ZIP};
    for (int k = 0; k < 4; k++) {
        raw_exr raw = {0};
        raw.width = W;
        raw.height = H;
        raw.compression = compressions[k];
        raw.type = EXR_PIXEL_FLOAT;
        raw.lineorder = k >= 2 ? EXR_LINEORDER_DECREASING_Y : EXR_LINEORDER_INCREASING_Y;
        raw.channel_count = 1;
        raw.names[0] = "Z";
        raw.planes[0] = plane;
        char name[64];
        snprintf(name, sizeof name, "float%d.exr", k);
        const char *path = path_in(name);
        ENSURE(write_raw_exr(path, &raw));
        static const char *const wanted[] = {"R|Z"};
        wx_image image;
        ENSURE(wx_exr_read(path, wanted, 1, &image, NULL) == WX_OK);
        bool same = image.width == W && image.height == H &&
                    memcmp(image.channels[0], plane, sizeof plane) == 0;
        wx_image_free(&image);
        ENSURE(same);
    }
}

// Every compression wx_exr_write offers gives back the same bits, and the file
// says which one it used (a zero-initialised image is written as ZIP).
TEST(every_write_compression_round_trips_bit_exact)
{
    enum { W = 37, H = 19 };
    static const char *const names[] = {"R", "G", "B", "Y", "Z"};
    static const wx_exr_compression modes[] = {WX_EXR_ZIP, WX_EXR_NONE, WX_EXR_RLE,
                                               WX_EXR_ZIPS, WX_EXR_PIZ};
    static const exr_compression_t stored[] = {EXR_COMPRESSION_ZIP, EXR_COMPRESSION_NONE,
                                               EXR_COMPRESSION_RLE, EXR_COMPRESSION_ZIPS,
                                               EXR_COMPRESSION_PIZ};
    ENSURE(WX_EXR_ZIP == 0);
    for (int m = 0; m < 5; m++) {
        wx_image image;
        ENSURE(make_image(&image, W, H, 5, names));
        image.channels[3][0] = INFINITY;
        image.channels[3][1] = NAN;
        image.channels[3][2] = -0.0f;
        image.channels[3][3] = FLT_TRUE_MIN;
        image.compression = modes[m];
        const char *path = path_in("compressed.exr");
        ENSURE(wx_exr_write(path, &image, NULL) == WX_OK);

        exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
        exr_context_t ctx = NULL;
        exr_compression_t compression = EXR_COMPRESSION_LAST_TYPE;
        ENSURE(exr_start_read(&ctx, path, &init) == EXR_ERR_SUCCESS);
        ENSURE(exr_get_compression(ctx, 0, &compression) == EXR_ERR_SUCCESS);
        exr_finish(&ctx);
        ENSURE(compression == stored[m]);

        wx_image back;
        ENSURE(wx_exr_read(path, names, 5, &back, NULL) == WX_OK);
        int mismatches = 0;
        for (int c = 0; c < 5; c++) {
            for (int t = 0; t < W * H; t++) {
                float a = image.channels[c][t], b = back.channels[c][t];
                mismatches += (isnan(a) ? isnan(b) : bits_of(a) == bits_of(b)) ? 0 : 1;
            }
        }
        ENSURE(mismatches == 0);
        wx_image_free(&back);
        wx_image_free(&image);
    }
}

TEST(zlib_stream_as_long_as_the_raw_data_round_trips)
{
    // These 7 floats compress to exactly 28 bytes: OpenEXR Core 3.1 would store the
    // zlib stream where readers expect raw data (openexr issue #2306).
    static const char *const names[] = {"Z"};
    wx_image image;
    ENSURE(wx_image_alloc(&image, 7, 1, 1, names, NULL) == WX_OK);
    for (int i = 0; i < 7; i++) {
        image.channels[0][i] = (float)i * 0.25f - 3.0f;
    }
    const char *path = path_in("ambiguous.exr");
    ENSURE(wx_exr_write(path, &image, NULL) == WX_OK);
    wx_image_free(&image);
    static const char *const wanted[] = {"Z"};
    wx_image back;
    ENSURE(wx_exr_read(path, wanted, 1, &back, NULL) == WX_OK);
    bool right = back.width == 7 && back.height == 1;
    for (int i = 0; right && i < 7; i++) {
        right = back.channels[0][i] == (float)i * 0.25f - 3.0f;
    }
    wx_image_free(&back);
    ENSURE(right);
}

TEST(data_window_origin_is_dropped)
{
    enum { W = 4, H = 3 };
    static const float plane[W * H] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
    raw_exr raw = {0};
    raw.min_x = -10;
    raw.min_y = 20;
    raw.width = W;
    raw.height = H;
    raw.compression = EXR_COMPRESSION_ZIP;
    raw.type = EXR_PIXEL_FLOAT;
    raw.channel_count = 1;
    raw.names[0] = "R";
    raw.planes[0] = plane;
    const char *path = path_in("shifted.exr");
    ENSURE(write_raw_exr(path, &raw));
    static const char *const wanted[] = {"R"};
    wx_image image;
    ENSURE(wx_exr_read(path, wanted, 1, &image, NULL) == WX_OK);
    bool same = image.width == W && image.height == H &&
                memcmp(image.channels[0], plane, sizeof plane) == 0;
    wx_image_free(&image);
    ENSURE(same);
}

TEST(attributes_round_trip)
{
    static const char *const names[] = {"R"};
    wx_image image;
    ENSURE(make_image(&image, 2, 2, 1, names));
    float wtc[16];
    for (int k = 0; k < 16; k++) {
        wtc[k] = (float)k * 1.5f - 7.0f;
    }
    wtc[15] = 1.0f / 3.0f;
    float ndc[16] = {0};
    ndc[0] = ndc[5] = ndc[10] = ndc[15] = -2.5f;
    char long_text[WX_ATTR_STRING_MAX];
    memset(long_text, 'x', sizeof long_text - 1);
    long_text[sizeof long_text - 1] = '\0';
    wx_image_set_m44f(&image, "worldToCamera", wtc);
    wx_image_set_string(&image, "cameraName", "front");
    wx_image_set_m44f(&image, "worldToNDC", ndc);
    wx_image_set_string(&image, "note", long_text);
    wx_image_set_string(&image, "cameraName", "back"); // replaces, does not add
    ENSURE(image.attr_count == 4);
    const char *path = path_in("attrs.exr");
    wx_error err = { 0 };
    ENSURE(wx_exr_write(path, &image, &err) == WX_OK);
    wx_image_free(&image);

    wx_image back;
    ENSURE(wx_exr_read_header(path, &back, &err) == WX_OK);
    // Only the m44f and string attributes: not channels, compression, windows...
    ENSURE(back.attr_count == 4);
    const wx_attr *a = wx_image_find_attr(&back, "worldToCamera");
    ENSURE(a != NULL && a->type == WX_ATTR_M44F);
    ENSURE(memcmp(a->m44f, wtc, sizeof wtc) == 0);
    a = wx_image_find_attr(&back, "worldToNDC");
    ENSURE(a != NULL && a->type == WX_ATTR_M44F && a->m44f[10] == -2.5f && a->m44f[11] == 0.0f);
    a = wx_image_find_attr(&back, "cameraName");
    ENSURE(a != NULL && a->type == WX_ATTR_STRING && strcmp(a->string, "back") == 0);
    a = wx_image_find_attr(&back, "note");
    ENSURE(a != NULL && a->type == WX_ATTR_STRING && strcmp(a->string, long_text) == 0);
    ENSURE(wx_image_find_attr(&back, "compression") == NULL);

    static const char *const wanted[] = {"R"};
    ENSURE(wx_exr_read(path, wanted, 1, &back, &err) == WX_OK);
    a = wx_image_find_attr(&back, "worldToCamera");
    bool right = back.attr_count == 4 && a != NULL && a->m44f[15] == 1.0f / 3.0f &&
                 back.channels[0][3] == 11.0f;
    wx_image_free(&back);
    ENSURE(right);
}

// ---------------------------------------------------------------------------
// Channel alternatives.

TEST(depth_alternatives_read_z)
{
    static const char *const names[] = {"Z"};
    wx_image image;
    ENSURE(make_image(&image, 3, 2, 1, names));
    image.channels[0][4] = 42.5f;
    const char *path = path_in("depth_z.exr");
    ENSURE(wx_exr_write(path, &image, NULL) == WX_OK);
    wx_image_free(&image);
    static const char *const wanted[] = {"R|Z"};
    wx_image back;
    wx_error err = { 0 };
    ENSURE(wx_exr_read(path, wanted, 1, &back, &err) == WX_OK);
    bool right = strcmp(back.channel_names[0], "Z") == 0 && back.channels[0][4] == 42.5f &&
                 back.channels[0][5] == 12.0f;
    wx_image_free(&back);
    ENSURE(right);
    // Two entries naming the same channel are refused (a caller's mistake).
    static const char *const twice[] = {"R|Z", "Z"};
    ENSURE(wx_exr_read(path, twice, 2, &back, &err) == WX_FAIL);
    ENSURE_CAUSE(err, INTERNAL);
    ENSURE(ensure_contains(err.message, "channel Z asked for twice"));
    ENSURE(back.channels[0] == NULL);
}

TEST(missing_channel_lists_what_the_file_has)
{
    static const char *const names[] = {"G", "B"};
    wx_image image;
    ENSURE(make_image(&image, 3, 2, 2, names));
    const char *path = path_in("no_depth.exr");
    ENSURE(wx_exr_write(path, &image, NULL) == WX_OK);
    wx_image_free(&image);
    static const char *const wanted[] = {"R|Z"};
    wx_image back;
    wx_error err = { 0 };
    ENSURE(wx_exr_read(path, wanted, 1, &back, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_MAP);
    ENSURE(ensure_contains(err.message, path));
    ENSURE(ensure_contains(err.message, ": no channel R or Z (has: B, G)"));
    ENSURE(back.channels[0] == NULL);
    static const char *const two[] = {"G", "A"};
    ENSURE(wx_exr_read(path, two, 2, &back, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_MAP);
    ENSURE(ensure_contains(err.message, "no channel A (has: B, G)"));
    ENSURE(back.channels[0] == NULL);
}

// ---------------------------------------------------------------------------
// Bad files.

TEST(missing_file_is_bad_input)
{
    ENSURE(read_fails(path_in("does_not_exist.exr"), WX_CAUSE_FILE_MISSING,
                      "cannot open (No such file or directory)"));
    wx_image image;
    wx_error err = { 0 };
    const char *path = path_in("does_not_exist_either.exr");
    ENSURE(wx_exr_read_header(path, &image, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, FILE_MISSING);
    ENSURE(ensure_contains(err.message, path));
}

TEST(empty_file_is_bad_input)
{
    const char *path = ensure_write_file(ensure_tmpdir(), "empty.exr", "");
    ENSURE(read_fails(path, WX_CAUSE_BAD_MAP, "not an OpenEXR file"));
}

TEST(text_file_is_bad_input)
{
    const char *path = ensure_write_file(ensure_tmpdir(), "text.exr", "depth map goes here\n");
    ENSURE(read_fails(path, WX_CAUSE_BAD_MAP, "not an OpenEXR file"));
    ENSURE(read_fails(ensure_tmpdir(), WX_CAUSE_NOT_REGULAR_FILE, "not a regular file"));
}

TEST(truncated_file_is_bad_input)
{
    const char *path = path_in("truncated.exr");
    ENSURE(write_noisy_file(path));
    size_t size = 0;
    unsigned char *bytes = read_bytes(path, &size);
    ENSURE(bytes != NULL);
    bool written = write_bytes(path, bytes, size / 2);
    free(bytes);
    ENSURE(written);
    ENSURE(read_fails(path, WX_CAUSE_BAD_MAP, "truncated or corrupt (reading scanlines "));
}

// A valid 64 x 64 ZIP file with smooth data, which compresses well.
static bool write_smooth_file(const char *path)
{
    static const char *const names[] = {"R"};
    wx_image image;
    if (wx_image_alloc(&image, 64, 64, 1, names, NULL) != WX_OK) {
        return false;
    }
    for (int t = 0; t < 64 * 64; t++) {
        image.channels[0][t] = 1.0f + (float)(t % 64) / 64.0f + (float)(t / 64) / 8.0f;
    }
    bool ok = wx_exr_write(path, &image, NULL) == WX_OK;
    wx_image_free(&image);
    return ok;
}

// File offset of the leader (y, then size) of the chunk holding scanline y.
static long chunk_leader_offset(const char *path, int y)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = quiet_handler;
    exr_context_t ctx = NULL;
    exr_chunk_info_t ci;
    long offset = -1;
    if (exr_start_read(&ctx, path, &init) == EXR_ERR_SUCCESS &&
        exr_read_scanline_chunk_info(ctx, 0, y, &ci) == EXR_ERR_SUCCESS) {
        offset = (long)ci.data_offset - 8;
    }
    exr_finish(&ctx);
    return offset;
}

// Chunks decoded on several threads give the same planes, planar and
// interleaved (64 rows: four ZIP chunks of 16).
TEST(parallel_decoding_gives_the_same_planes)
{
    const char *path = path_in("parallel.exr");
    ENSURE(write_smooth_file(path));
    static const char *const wanted[] = {"R"};
    wx_image one, four;
    ENSURE(wx_exr_read_parallel(path, wanted, 1, 1, &one, NULL) == WX_OK);
    ENSURE(wx_exr_read_parallel(path, wanted, 1, 4, &four, NULL) == WX_OK);
    bool same = one.width == 64 && four.width == 64 &&
                memcmp(one.channels[0], four.channels[0], 64 * 64 * sizeof(float)) == 0 &&
                one.channels[0][64 * 40 + 3] == 1.0f + 3.0f / 64.0f + 40.0f / 8.0f;
    float *a = NULL, *b = NULL;
    int w = 0, h = 0;
    ENSURE(wx_exr_read_interleaved(path, wanted, 1, 1, &a, &w, &h, NULL) == WX_OK);
    ENSURE(wx_exr_read_interleaved(path, wanted, 1, 3, &b, &w, &h, NULL) == WX_OK);
    same = same && memcmp(a, b, 64 * 64 * sizeof(float)) == 0 &&
           memcmp(a, one.channels[0], 64 * 64 * sizeof(float)) == 0;
    free(a);
    free(b);
    wx_image_free(&one);
    wx_image_free(&four);
    ENSURE(same);
}

TEST(corrupt_chunk_is_bad_input)
{
    const char *path = path_in("corrupt.exr");
    ENSURE(write_smooth_file(path));
    long leader = chunk_leader_offset(path, 32);
    size_t size = 0;
    unsigned char *bytes = read_bytes(path, &size);
    ENSURE(bytes != NULL && leader > 0 && (size_t)leader + 40 < size);
    // Scramble the compressed data of the chunk of scanlines 32-47.
    for (size_t k = (size_t)leader + 12; k < (size_t)leader + 40; k++) {
        bytes[k] = (unsigned char)(k * 7u + 3u);
    }
    ENSURE(write_bytes(path, bytes, size));
    ENSURE(read_fails(path, WX_CAUSE_BAD_MAP, "truncated or corrupt (reading scanlines 32-47"));

    // The same chunk claiming 2 GB of data.
    ENSURE(write_smooth_file(path));
    free(bytes);
    bytes = read_bytes(path, &size);
    ENSURE(bytes != NULL);
    bytes[leader + 4] = 0xf0;
    bytes[leader + 5] = 0xff;
    bytes[leader + 6] = 0xff;
    bytes[leader + 7] = 0x7f;
    bool written = write_bytes(path, bytes, size);
    free(bytes);
    ENSURE(written);
    ENSURE(read_fails(path, WX_CAUSE_BAD_MAP, "truncated or corrupt (reading scanlines 32-47"));
}

TEST(garbage_after_magic_is_bad_input)
{
    unsigned char bytes[300];
    bytes[0] = 0x76;
    bytes[1] = 0x2f;
    bytes[2] = 0x31;
    bytes[3] = 0x01;
    for (size_t k = 4; k < sizeof bytes; k++) {
        bytes[k] = (unsigned char)(k * 37u + 11u);
    }
    const char *path = path_in("garbage.exr");
    ENSURE(write_bytes(path, bytes, sizeof bytes));
    ENSURE(read_fails(path, WX_CAUSE_BAD_MAP, "corrupt OpenEXR header"));
    // Magic and version 2, then garbage.
    bytes[4] = 2;
    bytes[5] = bytes[6] = bytes[7] = 0;
    ENSURE(write_bytes(path, bytes, sizeof bytes));
    ENSURE(read_fails(path, WX_CAUSE_BAD_MAP, "corrupt OpenEXR header"));
}

// Rewrites the dataWindow of the EXR at `path` to (0, 0) - (max_x, max_y).
static bool patch_data_window(const char *path, int32_t max_x, int32_t max_y)
{
    size_t size = 0;
    unsigned char *bytes = read_bytes(path, &size);
    if (bytes == NULL) {
        return false;
    }
    static const char key[] = "dataWindow\0box2i"; // then int32 size 16, then 4 int32
    bool found = false;
    for (size_t k = 0; !found && k + sizeof key + 4 + 16 <= size; k++) {
        if (memcmp(bytes + k, key, sizeof key) == 0) {
            unsigned char *box = bytes + k + sizeof key + 4;
            int32_t v[4] = {0, 0, max_x, max_y};
            for (int n = 0; n < 4; n++) { // little-endian
                uint32_t u = (uint32_t)v[n];
                for (int b = 0; b < 4; b++) {
                    box[4 * n + b] = (unsigned char)(u >> (8 * b));
                }
            }
            found = true;
        }
    }
    bool ok = found && write_bytes(path, bytes, size);
    free(bytes);
    return ok;
}

TEST(absurd_size_is_bad_input)
{
    const char *path = path_in("huge.exr");
    ENSURE(write_noisy_file(path));
    ENSURE(patch_data_window(path, 99999, 99999));
    ENSURE(read_fails(path, WX_CAUSE_MAP_SIZE,
                      "100000 x 100000 exceeds the largest map size 16384 x 16384"));
    wx_image image;
    wx_error err = { 0 };
    ENSURE(wx_exr_read_header(path, &image, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, MAP_SIZE);
    ENSURE(ensure_contains(err.message, "exceeds the largest map size"));
    // One side over the limit is enough.
    ENSURE(write_noisy_file(path));
    ENSURE(patch_data_window(path, 16384, 15));
    ENSURE(read_fails(path, WX_CAUSE_MAP_SIZE, "16385 x 16 exceeds"));
}

TEST(tiled_file_is_refused)
{
    enum { W = 4, H = 4 };
    static const float plane[W * H] = {0};
    raw_exr raw = {0};
    raw.width = W;
    raw.height = H;
    raw.compression = EXR_COMPRESSION_ZIP;
    raw.type = EXR_PIXEL_FLOAT;
    raw.tiled = true;
    raw.channel_count = 1;
    raw.names[0] = "R";
    raw.planes[0] = plane;
    const char *path = path_in("tiled.exr");
    ENSURE(write_raw_exr(path, &raw));
    ENSURE(read_fails(path, WX_CAUSE_BAD_MAP, "tiled OpenEXR files are not supported"));
}

// ---------------------------------------------------------------------------
// Writing.

TEST(write_to_missing_folder_fails_cleanly)
{
    static const char *const names[] = {"R"};
    wx_image image;
    ENSURE(make_image(&image, 4, 4, 1, names));
    const char *path = path_in("no_such_folder/out.exr");
    wx_error err = { 0 };
    wx_result r = wx_exr_write(path, &image, &err);
    wx_image_free(&image);
    ENSURE(r == WX_FAIL);
    ENSURE_CAUSE(err, IO);
    ENSURE(ensure_contains(err.message, path));
    ENSURE(ensure_contains(err.message, "No such file or directory"));
    struct stat st;
    ENSURE(stat(path_in("no_such_folder"), &st) != 0);
    ENSURE(count_temporaries(ensure_tmpdir()) == 0);
}

TEST(write_replaces_existing_file_whole)
{
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/replace", ensure_tmpdir());
    ENSURE(mkdir(dir, 0777) == 0);
    char path[4300];
    snprintf(path, sizeof path, "%s/map.exr", dir);
    static const char *const names[] = {"R", "G"};
    wx_image big;
    ENSURE(make_image(&big, 37, 19, 2, names));
    ENSURE(wx_exr_write(path, &big, NULL) == WX_OK);
    wx_image_free(&big);
    ENSURE(count_temporaries(dir) == 0);

    static const char *const one[] = {"Z"};
    wx_image small;
    ENSURE(make_image(&small, 5, 3, 1, one));
    small.channels[0][14] = -1.25f;
    ENSURE(wx_exr_write(path, &small, NULL) == WX_OK);
    wx_image_free(&small);
    ENSURE(count_temporaries(dir) == 0);

    wx_image back;
    ENSURE(wx_exr_read_header(path, &back, NULL) == WX_OK);
    ENSURE(back.width == 5 && back.height == 3 && back.channel_count == 1);
    ENSURE(strcmp(back.channel_names[0], "Z") == 0);
    static const char *const wanted[] = {"Z"};
    ENSURE(wx_exr_read(path, wanted, 1, &back, NULL) == WX_OK);
    bool right = back.channels[0][14] == -1.25f && back.channels[0][13] == 23.0f;
    wx_image_free(&back);
    ENSURE(right);

    // A bare file name (no folder) writes into the working directory.
    char cwd[4096];
    ENSURE(getcwd(cwd, sizeof cwd) != NULL);
    ENSURE(chdir(dir) == 0);
    ENSURE(make_image(&small, 2, 2, 1, one));
    wx_result r = wx_exr_write("bare.exr", &small, NULL);
    wx_image_free(&small);
    ENSURE(chdir(cwd) == 0);
    ENSURE(r == WX_OK);
    snprintf(path, sizeof path, "%s/bare.exr", dir);
    ENSURE(wx_exr_read_header(path, &back, NULL) == WX_OK && back.width == 2);
    ENSURE(count_temporaries(dir) == 0);
}

TEST(write_failure_keeps_the_old_file)
{
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/full", ensure_tmpdir());
    ENSURE(mkdir(dir, 0777) == 0);
    char path[4300];
    snprintf(path, sizeof path, "%s/map.exr", dir);
    static const char *const names[] = {"R"};
    wx_image image;
    ENSURE(make_image(&image, 8, 8, 1, names));
    ENSURE(wx_exr_write(path, &image, NULL) == WX_OK);
    wx_image_free(&image);
    size_t old_size = 0;
    unsigned char *old_bytes = read_bytes(path, &old_size);
    ENSURE(old_bytes != NULL);

    // A large noisy image, with files limited to 16 KiB: the write runs out of room.
    ENSURE(wx_image_alloc(&image, 256, 256, 1, names, NULL) == WX_OK);
    uint32_t state = 99u;
    for (int t = 0; t < 256 * 256; t++) {
        state = state * 1664525u + 1013904223u;
        image.channels[0][t] = (float)state;
    }
    struct rlimit saved;
    ENSURE(getrlimit(RLIMIT_FSIZE, &saved) == 0);
    struct rlimit small = saved;
    small.rlim_cur = 16384;
    void (*old_handler)(int) = signal(SIGXFSZ, SIG_IGN);
    ENSURE(setrlimit(RLIMIT_FSIZE, &small) == 0);
    wx_error err = { 0 };
    wx_result r = wx_exr_write(path, &image, &err);
    setrlimit(RLIMIT_FSIZE, &saved);
    signal(SIGXFSZ, old_handler);
    wx_image_free(&image);
    ENSURE(r == WX_FAIL);
    ENSURE_CAUSE(err, IO);
    ENSURE(ensure_contains(err.message, path));
    ENSURE(ensure_contains(err.message, strerror(EFBIG)));
    ENSURE(count_temporaries(dir) == 0);
    size_t new_size = 0;
    unsigned char *new_bytes = read_bytes(path, &new_size);
    bool same =
        new_bytes != NULL && new_size == old_size && memcmp(new_bytes, old_bytes, old_size) == 0;
    free(old_bytes);
    free(new_bytes);
    ENSURE(same);
}

TEST(image_alloc_checks_sizes)
{
    static const char *const names[] = {"R", "G"};
    wx_image image;
    wx_error err = { 0 };
    ENSURE(wx_image_alloc(&image, 16385, 1, 1, names, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, MAP_SIZE);
    ENSURE(image.channels[0] == NULL);
    ENSURE(wx_image_alloc(&image, 0, 5, 1, names, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, MAP_SIZE);
    // One channel more than an image holds: refused before any name is read.
    ENSURE(wx_image_alloc(&image, 5, 5, WX_IMAGE_MAX_CHANNELS + 1, names, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_ARGUMENT);
    ENSURE(wx_image_alloc(&image, 3, 2, 2, names, &err) == WX_OK);
    bool right = image.width == 3 && image.height == 2 && image.channel_count == 2 &&
                 strcmp(image.channel_names[1], "G") == 0 && image.channels[1][5] == 0.0f;
    wx_image_free(&image);
    ENSURE(right);
    ENSURE(image.channels[0] == NULL && image.width == 0);
}

// ---------------------------------------------------------------------------
// Long names (issue 24): OpenEXR refuses names over 31 characters unless told;
// its refusal used to hang the writer (the error handler asked the library for
// its user data while the library held its lock). SIGALRM ends the program if a
// write hangs again: tests/run.sh then counts it as failed.

enum { HANG_GUARD_S = 20 };

// The file's version field (bytes 4-7): 2, plus 0x400 when it holds long names.
static uint32_t version_field(const char *path)
{
    size_t size = 0;
    unsigned char *bytes = read_bytes(path, &size);
    uint32_t v = bytes != NULL && size >= 8 ? (uint32_t)bytes[4] | (uint32_t)bytes[5] << 8 |
                                                  (uint32_t)bytes[6] << 16 |
                                                  (uint32_t)bytes[7] << 24
                                            : 0;
    free(bytes);
    return v;
}

// The longest names the program writes: a 32-character substance's channels,
// with a layer prefix (design.md section 14), and the longest name an image
// holds (WX_NAME_MAX - 1).
static const char *const long_names[] = {
    "abcdefghijklmnopqrstuvwxyz012345.Y",                              // 34
    "layer7.abcdefghijklmnopqrstuvwxyz012345.deposit",                 // 47
    "n23456789012345678901234567890123456789012345678901234567890123", // 63
    "short",
};

TEST(long_channel_names_round_trip)
{
    const char *const *names = long_names;
    ENSURE(strlen(names[2]) == WX_NAME_MAX - 1);
    wx_image image;
    ENSURE(make_image(&image, 9, 40, 4, names));
    image.threads = 2;
    wx_image_set_string(&image, "anAttributeNameOfMoreThan31Characters", "x");
    const char *path = path_in("long_names.exr");
    wx_error err = { 0 };
    alarm(HANG_GUARD_S);
    wx_result r = wx_exr_write(path, &image, &err);
    alarm(0);
    if (r != WX_OK) {
        fprintf(stderr, "        %s\n", err.message);
    }
    ENSURE(r == WX_OK);
    ENSURE(version_field(path) == (2u | 0x400u));

    const char *const wanted[] = { names[1], names[2], names[0] };
    wx_image back;
    ENSURE(wx_exr_read(path, wanted, 3, &back, &err) == WX_OK);
    bool right = back.channel_count == 3 && strcmp(back.channel_names[1], names[2]) == 0 &&
                 back.channels[0][39 * 9 + 8] == image.channels[1][39 * 9 + 8] &&
                 back.channels[1][5] == image.channels[2][5] &&
                 back.channels[2][9] == image.channels[0][9];
    const wx_attr *a = wx_image_find_attr(&back, "anAttributeNameOfMoreThan31Characters");
    right = right && a != NULL && strcmp(a->string, "x") == 0;
    wx_image_free(&back);

    // Names of 31 characters and less keep the flag off: the file reads in
    // every OpenEXR, and the program's other files keep their bytes.
    static const char *const short_names[] = {"n234567890123456789012345678901"};
    wx_image small;
    ENSURE(make_image(&small, 3, 3, 1, short_names));
    const char *short_path = path_in("short_names.exr");
    ENSURE(wx_exr_write(short_path, &small, &err) == WX_OK);
    wx_image_free(&small);
    ENSURE(version_field(short_path) == 2u);
    wx_image_free(&image);
    ENSURE(right);
}

// Another reader: oiiotool (Debian's openimageio-tools, on the C++ OpenEXR that
// Blender uses too) lists the long names. Not a dependency of the build: a
// counted skip where it is not installed.
TEST(long_channel_names_read_in_oiiotool)
{
    char log[4096];
    if (ensure_shell(log, sizeof log, "command -v oiiotool >/dev/null") != 0) {
        SKIP("oiiotool is not installed (Debian's openimageio-tools)");
    }
    wx_image image;
    ENSURE(make_image(&image, 9, 40, 4, long_names));
    const char *path = path_in("long_names_oiiotool.exr");
    wx_error err = { 0 };
    wx_result r = wx_exr_write(path, &image, &err);
    wx_image_free(&image);
    ENSURE(r == WX_OK);
    ENSURE(ensure_shell(log, sizeof log, "oiiotool --info -v '%s' 2>&1", path) == 0);
    ENSURE(ensure_contains(log, long_names[1]) && ensure_contains(log, long_names[2]));
}

TEST(library_error_inside_its_lock_is_reported)
{
    // Setting "compression" as a string makes OpenEXR report a type clash from
    // inside its lock: the message must come back, not a hang.
    static const char *const names[] = {"R"};
    wx_image image;
    ENSURE(make_image(&image, 4, 4, 1, names));
    wx_image_set_string(&image, "compression", "zip");
    const char *path = path_in("clash.exr");
    wx_error err = { 0 };
    alarm(HANG_GUARD_S);
    wx_result r = wx_exr_write(path, &image, &err);
    alarm(0);
    wx_image_free(&image);
    ENSURE(r == WX_FAIL);
    ENSURE_CAUSE(err, IO);
    ENSURE(ensure_contains(err.message, path));
    ENSURE(ensure_contains(err.message, "compression"));
    struct stat st;
    ENSURE(stat(path, &st) != 0);
    ENSURE(count_temporaries(ensure_tmpdir()) == 0);
}

int main(void)
{
    RUN(float_round_trip_is_bit_exact);
    RUN(interleaved_read_orders_channels_as_asked);
    RUN(half_channels_are_read_as_float);
    RUN(other_float_compressions_and_decreasing_lines_are_read);
    RUN(every_write_compression_round_trips_bit_exact);
    RUN(zlib_stream_as_long_as_the_raw_data_round_trips);
    RUN(data_window_origin_is_dropped);
    RUN(attributes_round_trip);
    RUN(depth_alternatives_read_z);
    RUN(missing_channel_lists_what_the_file_has);
    RUN(missing_file_is_bad_input);
    RUN(empty_file_is_bad_input);
    RUN(text_file_is_bad_input);
    RUN(truncated_file_is_bad_input);
    RUN(parallel_decoding_gives_the_same_planes);
    RUN(corrupt_chunk_is_bad_input);
    RUN(garbage_after_magic_is_bad_input);
    RUN(absurd_size_is_bad_input);
    RUN(tiled_file_is_refused);
    RUN(write_to_missing_folder_fails_cleanly);
    RUN(write_replaces_existing_file_whole);
    RUN(write_failure_keeps_the_old_file);
    RUN(image_alloc_checks_sizes);
    RUN(long_channel_names_round_trip);
    RUN(long_channel_names_read_in_oiiotool);
    RUN(library_error_inside_its_lock_is_reported);
    return ensure_summary();
}
