// fuzz_exr.c: libFuzzer target for EXR maps: the header, then the four maps of a
// camera loaded from the input (wx_maps_load, as the simulation and the gather
// read them). Every input must either load or give WX_BAD_INPUT with a message
// that names the file; a loaded map must keep the limits and the depth
// convention (d in (0, 1e30) or +inf).
#define _XOPEN_SOURCE 700 // realpath, mkdtemp
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "core/error.h"
#include "io/exr.h"
#include "fuzz_workspace.h"
#include "model/maps.h"
#include "core/limits.h"
#include "io/maps_file.h"
#include "model/image.h"

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    fuzz_workspace("map.exr");
    return 0;
}

static void check_error(wx_result r, const wx_error *err)
{
    if (r != WX_BAD_INPUT || strstr(err->message, fuzz_input) == NULL) {
        fprintf(stderr, "result %d, message: %s\n", (int)r, err->message);
        __builtin_trap();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_write_input(data, size);
    wx_image header;
    wx_error err;
    memset(&err, 0, sizeof err);
    wx_result r = wx_exr_read_header(fuzz_input, &header, &err);
    wx_image_free(&header);
    if (r != WX_OK) {
        check_error(r, &err);
        return 0;
    }
    wx_maps maps;
    r = wx_maps_load(&maps, WX_MAPS_ALL | WX_MAPS_INITIAL_DIRT, 1, fuzz_input, fuzz_input,
                     fuzz_input, fuzz_input, &err);
    if (r != WX_OK) {
        check_error(r, &err);
        return 0;
    }
    if (maps.width < 1 || maps.height < 1 || maps.width > WX_MAP_MAX_SIDE ||
        maps.height > WX_MAP_MAX_SIDE) {
        __builtin_trap();
    }
    size_t texels = (size_t)maps.width * (size_t)maps.height;
    for (size_t t = 0; t < texels; t++) {
        float d = maps.depth[t];
        if (!(isinf(d) && d > 0.0f) && !(d > 0.0f && d < 1e30f)) {
            __builtin_trap();
        }
        if (!isfinite(maps.dirt[t]) || !isfinite(maps.normal[3 * t]) ||
            !isfinite(maps.impact[2 * t + 1])) {
            __builtin_trap();
        }
    }
    wx_maps_free(&maps);
    return 0;
}
