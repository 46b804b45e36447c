// test_maps.c: loading the four maps of a camera.
#include <math.h>
#include <string.h>

#include "ensure.h"
#include "io/exr.h"
#include "model/maps.h"
#include "io/maps_file.h"
#include "model/image.h"

enum { W = 8, H = 4 };

static const char *path_in(const char *name)
{
    static char paths[8][4096];
    static int next;
    char *p = paths[next];
    next = (next + 1) % 8;
    snprintf(p, 4096, "%s/%s", ensure_tmpdir(), name);
    return p;
}

// Writes a w x h map whose channel c holds 100*c + 10*j + i + 0.5 at texel (i, j),
// except where `override` (channel 0 only, may be NULL) gives another value.
static bool write_map(const char *path, int w, int h, int count, const char *const *names,
                      const float *override0)
{
    wx_image image;
    if (wx_image_alloc(&image, w, h, count, names, NULL) != WX_OK) {
        return false;
    }
    for (int c = 0; c < count; c++) {
        for (int t = 0; t < w * h; t++) {
            image.channels[c][t] = (float)(100 * c + 10 * (t / w) + t % w) + 0.5f;
        }
    }
    if (override0 != NULL) {
        memcpy(image.channels[0], override0, (size_t)(w * h) * sizeof(float));
    }
    bool ok = wx_exr_write(path, &image, NULL) == WX_OK;
    wx_image_free(&image);
    return ok;
}

static const char *const RGB[] = {"R", "G", "B"};

// Depth values of the test camera: row 0 holds the "no surface" values.
static void make_depth(float depth[W * H])
{
    for (int t = 0; t < W * H; t++) {
        depth[t] = 1.0f + (float)t; // 1 .. 32, all surfaces
    }
    depth[0] = NAN;
    depth[1] = 0.0f;
    depth[2] = -1.0f;
    depth[3] = 1e31f;
    depth[4] = INFINITY;
    depth[5] = -INFINITY;
    depth[6] = 1e30f;   // the limit itself means "no surface"
    depth[7] = 9.9e29f; // just below: a surface
}

static bool all_null(const wx_maps *m)
{
    return m->depth == NULL && m->normal == NULL && m->impact == NULL && m->dirt == NULL &&
           m->deposit == NULL && m->erosion == NULL && m->width == 0 && m->height == 0;
}

TEST(four_maps_load_in_simulation_layout)
{
    float depth[W * H];
    make_depth(depth);
    static const char *const R[] = {"R"};
    const char *depth_path = path_in("depth.exr");
    const char *normal_path = path_in("normal.exr");
    const char *impact_path = path_in("impact.exr");
    const char *dirt_path = path_in("dirt.exr");
    ENSURE(write_map(depth_path, W, H, 1, R, depth));
    ENSURE(write_map(normal_path, W, H, 3, RGB, NULL));
    ENSURE(write_map(impact_path, W, H, 2, RGB, NULL));
    ENSURE(write_map(dirt_path, W, H, 3, RGB, NULL));

    wx_maps maps;
    wx_error err = { 0 };
    ENSURE(wx_maps_load(&maps, WX_MAPS_ALL, 1, depth_path, normal_path, impact_path, dirt_path,
                        &err) == WX_OK);
    ENSURE(maps.width == W && maps.height == H);
    // Depth: the "no surface" values became +inf, the others are kept.
    for (int t = 0; t < 7; t++) {
        ENSURE(isinf(maps.depth[t]) && maps.depth[t] > 0.0f);
    }
    ENSURE(maps.depth[7] == 9.9e29f);
    ENSURE(maps.depth[8] == 9.0f);
    ENSURE(maps.depth[W * H - 1] == 32.0f);
    // Normal, texel (i=5, j=2): x y z = R G B = 25.5, 125.5, 225.5.
    const float *n = maps.normal + 3 * (2 * W + 5);
    ENSURE(n[0] == 25.5f && n[1] == 125.5f && n[2] == 225.5f);
    n = maps.normal + 3 * (W * H - 1); // last texel (7, 3)
    ENSURE(n[0] == 37.5f && n[1] == 137.5f && n[2] == 237.5f);
    // Impact, texel (i=7, j=1): absorption R = 17.5, bounce G = 117.5.
    const float *im = maps.impact + 2 * (1 * W + 7);
    ENSURE(im[0] == 17.5f && im[1] == 117.5f);
    ENSURE(maps.impact[0] == 0.5f && maps.impact[1] == 100.5f);
    // Dirt planes, texel (i=3, j=3).
    ENSURE(maps.dirt[3 * W + 3] == 33.5f);
    ENSURE(maps.deposit[3 * W + 3] == 133.5f);
    ENSURE(maps.erosion[3 * W + 3] == 233.5f);
    wx_maps_free(&maps);
    ENSURE(all_null(&maps));
}

TEST(depth_is_read_from_z)
{
    float depth[W * H];
    make_depth(depth);
    static const char *const Z[] = {"Z"};
    const char *path = path_in("depth_z.exr");
    ENSURE(write_map(path, W, H, 1, Z, depth));
    wx_maps maps;
    wx_error err = { 0 };
    ENSURE(wx_maps_load(&maps, WX_MAPS_DEPTH, 1, path, NULL, NULL, NULL, &err) == WX_OK);
    bool right = isinf(maps.depth[0]) && isinf(maps.depth[2]) && maps.depth[9] == 10.0f &&
                 maps.normal == NULL && maps.dirt == NULL && maps.width == W;
    wx_maps_free(&maps);
    ENSURE(right);
}

TEST(only_selected_maps_are_loaded)
{
    const char *dirt_path = path_in("dirt_only.exr");
    const char *impact_path = path_in("impact_only.exr");
    ENSURE(write_map(dirt_path, W, H, 3, RGB, NULL));
    ENSURE(write_map(impact_path, W, H, 2, RGB, NULL));
    wx_maps maps;
    wx_error err = { 0 };
    // The impact path is given but not selected: it is not read.
    ENSURE(wx_maps_load(&maps, WX_MAPS_DIRT, 1, "", NULL, impact_path, dirt_path, &err) == WX_OK);
    bool right = maps.depth == NULL && maps.normal == NULL && maps.impact == NULL &&
                 maps.dirt[W + 1] == 11.5f && maps.erosion[0] == 200.5f && maps.height == H;
    wx_maps_free(&maps);
    ENSURE(right);
    // A selected map without a file is an error.
    ENSURE(wx_maps_load(&maps, WX_MAPS_DIRT | WX_MAPS_NORMAL, 1, NULL, NULL, NULL, dirt_path, &err) ==
           WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_ARGUMENT);
    ENSURE(ensure_contains(err.message, "normal"));
    ENSURE(all_null(&maps));
}

TEST(mismatched_sizes_name_both_files)
{
    static const char *const R[] = {"R"};
    const char *depth_path = path_in("depth84.exr");
    const char *normal_path = path_in("normal168.exr");
    ENSURE(write_map(depth_path, W, H, 1, R, NULL));
    ENSURE(write_map(normal_path, 16, 8, 3, RGB, NULL));
    wx_maps maps;
    wx_error err = { 0 };
    ENSURE(wx_maps_load(&maps, WX_MAPS_DEPTH | WX_MAPS_NORMAL, 1, depth_path, normal_path, NULL, NULL,
                        &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, MAP_SIZE);
    ENSURE(ensure_contains(err.message, depth_path));
    ENSURE(ensure_contains(err.message, normal_path));
    ENSURE(ensure_contains(err.message, "16 x 8"));
    ENSURE(ensure_contains(err.message, "8 x 4"));
    ENSURE(all_null(&maps));
}

TEST(missing_channels_are_errors)
{
    static const char *const R[] = {"R"};
    static const char *const RG[] = {"R", "G"};
    const char *impact_path = path_in("impact_r.exr");
    const char *dirt_path = path_in("dirt_rg.exr");
    const char *depth_path = path_in("depth_g.exr");
    ENSURE(write_map(impact_path, W, H, 1, R, NULL));
    ENSURE(write_map(dirt_path, W, H, 2, RG, NULL));
    ENSURE(write_map(depth_path, W, H, 1, RGB + 1, NULL)); // only G
    wx_maps maps;
    wx_error err = { 0 };
    ENSURE(wx_maps_load(&maps, WX_MAPS_IMPACT, 1, NULL, NULL, impact_path, NULL, &err) ==
           WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_MAP);
    ENSURE(ensure_contains(err.message, impact_path));
    ENSURE(ensure_contains(err.message, "no channel G (has: R)"));
    ENSURE(all_null(&maps));
    ENSURE(wx_maps_load(&maps, WX_MAPS_DIRT, 1, NULL, NULL, NULL, dirt_path, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_MAP);
    ENSURE(ensure_contains(err.message, dirt_path));
    ENSURE(ensure_contains(err.message, "no channel B (has: G, R)"));
    ENSURE(all_null(&maps));
    ENSURE(wx_maps_load(&maps, WX_MAPS_DEPTH, 1, depth_path, NULL, NULL, NULL, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_MAP);
    ENSURE(ensure_contains(err.message, "no channel R or Z (has: G)"));
}

TEST(a_bad_file_frees_the_maps_already_loaded)
{
    static const char *const R[] = {"R"};
    const char *depth_path = path_in("depth_ok.exr");
    const char *dirt_path = ensure_write_file(ensure_tmpdir(), "dirt_text.exr", "not a map\n");
    ENSURE(write_map(depth_path, W, H, 1, R, NULL));
    wx_maps maps;
    wx_error err = { 0 };
    ENSURE(wx_maps_load(&maps, WX_MAPS_DEPTH | WX_MAPS_DIRT, 1, depth_path, NULL, NULL, dirt_path,
                        &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_MAP);
    ENSURE(ensure_contains(err.message, dirt_path));
    ENSURE(ensure_contains(err.message, "not an OpenEXR file"));
    ENSURE(all_null(&maps));
    ENSURE(wx_maps_load(&maps, WX_MAPS_DEPTH, 1, path_in("none.exr"), NULL, NULL, NULL, &err) ==
           WX_BAD_INPUT);
    ENSURE_CAUSE(err, FILE_MISSING);
    ENSURE(ensure_contains(err.message, "none.exr: cannot open"));
}

int main(void)
{
    RUN(four_maps_load_in_simulation_layout);
    RUN(depth_is_read_from_z);
    RUN(only_selected_maps_are_loaded);
    RUN(mismatched_sizes_name_both_files);
    RUN(missing_channels_are_errors);
    RUN(a_bad_file_frees_the_maps_already_loaded);
    return ensure_summary();
}
