// make_bad_maps.c: writes the bad EXR maps of tests/bad/maps/ (run once; the
// maps are committed). Each is a 4 x 4 map broken in one way:
//
//   make build/libweathering.a
//   cc -std=c11 -D_POSIX_C_SOURCE=200809L -Isrc -I/usr/include/OpenEXR
//      tests/bad/maps/make_bad_maps.c build/libweathering.a -lOpenEXRCore-3_1
//      -lxml2 -lassimp -lOSMesa -lpng -lm -lpthread -o /tmp/make_bad_maps
//   /tmp/make_bad_maps tests/bad/maps
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/exr.h"

static const char *dir;

static const char *at(const char *name)
{
    static char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    return path;
}

// A 4 x 4 map with the given channels, every value `fill`, and `bad` at texel (1, 2)
// of the first channel.
static void write_map(const char *name, const char *const *channels, int count, float fill,
                      float bad)
{
    wx_image image;
    wx_error err;
    memset(&image, 0, sizeof image);
    if (wx_image_alloc(&image, 4, 4, count, channels, &err) != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
        exit(1);
    }
    for (int c = 0; c < count; c++) {
        for (int t = 0; t < 16; t++) {
            image.channels[c][t] = fill;
        }
    }
    image.channels[0][2 * 4 + 1] = bad;
    if (wx_exr_write(at(name), &image, &err) != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
        exit(1);
    }
    wx_image_free(&image);
}

static unsigned char *read_all(const char *path, long *size)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        exit(1);
    }
    fseek(f, 0, SEEK_END);
    *size = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *data = malloc((size_t)*size);
    if (data == NULL || fread(data, 1, (size_t)*size, f) != (size_t)*size) {
        exit(1);
    }
    fclose(f);
    return data;
}

static void write_all(const char *name, const unsigned char *data, long size)
{
    FILE *f = fopen(at(name), "wb");
    if (f == NULL || fwrite(data, 1, (size_t)size, f) != (size_t)size || fclose(f) != 0) {
        exit(1);
    }
}

static void put_i32(unsigned char *p, int v)
{
    unsigned u = (unsigned)v;
    p[0] = (unsigned char)u;
    p[1] = (unsigned char)(u >> 8);
    p[2] = (unsigned char)(u >> 16);
    p[3] = (unsigned char)(u >> 24);
}

// Rewrites the data and display windows of a copy of `good` (box2i: xmin ymin xmax ymax).
static void patch_windows(const char *name, const unsigned char *good, long size, int xmin,
                          int ymin, int xmax, int ymax)
{
    unsigned char *data = malloc((size_t)size);
    memcpy(data, good, (size_t)size);
    const char *names[2] = { "dataWindow", "displayWindow" };
    for (int k = 0; k < 2; k++) {
        size_t len = strlen(names[k]) + 1 + strlen("box2i") + 1 + 4;
        for (long i = 8; i + (long)len + 16 <= size; i++) {
            if (memcmp(data + i, names[k], strlen(names[k]) + 1) == 0 &&
                memcmp(data + i + strlen(names[k]) + 1, "box2i", 6) == 0) {
                unsigned char *box = data + i + len;
                put_i32(box, xmin);
                put_i32(box + 4, ymin);
                put_i32(box + 8, xmax);
                put_i32(box + 12, ymax);
                break;
            }
        }
    }
    write_all(name, data, size);
    free(data);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: make_bad_maps FOLDER\n");
        return 2;
    }
    dir = argv[1];
    static const char *const rgb[] = { "R", "G", "B" };
    static const char *const rg[] = { "R", "G" };
    static const char *const y[] = { "Y" };
    // Good maps, with one bad value.
    write_map("good.exr", rgb, 3, 0.5f, 0.5f);
    write_map("normal_nan.exr", rgb, 3, 0.0f, NAN);
    write_map("impact_nan.exr", rgb, 3, 0.5f, NAN);
    write_map("impact_inf.exr", rgb, 3, 0.5f, INFINITY);
    write_map("dirt_nan.exr", rgb, 3, 0.0f, NAN);
    write_map("dirt_inf.exr", rgb, 3, 0.0f, -INFINITY);
    // Missing channels.
    write_map("only_y.exr", y, 1, 1.0f, 1.0f);
    write_map("only_rg.exr", rg, 2, 0.5f, 0.5f);

    long size = 0;
    unsigned char *good = read_all(at("good.exr"), &size);
    write_all("empty.exr", good, 0);
    write_all("header_cut.exr", good, 40);
    write_all("pixels_cut.exr", good, size - 12);
    // The right magic number, then noise.
    unsigned char noise[512];
    unsigned state = 12345u;
    for (size_t i = 0; i < sizeof noise; i++) {
        state = state * 1103515245u + 12345u;
        noise[i] = (unsigned char)(state >> 16);
    }
    memcpy(noise, good, 8); // magic and version
    write_all("garbage.exr", noise, (long)sizeof noise);
    // Absurd and negative sizes in an otherwise good header.
    patch_windows("absurd_size.exr", good, size, 0, 0, 99999, 99999);
    patch_windows("wide.exr", good, size, 0, 0, 19999, 0);
    patch_windows("negative_size.exr", good, size, 0, 0, -5, 3);
    free(good);
    return 0;
}
