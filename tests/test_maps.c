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

// One texel of a camera looking along -z with `n` crossings (K = 4 layers) at
// depths d[], entering (normal +z, towards the camera) where enter[] says.
static void one_texel(wx_maps *m, float *depth, float *normal, const float *d, const bool *enter,
                      int n)
{
    memset(m, 0, sizeof *m);
    m->width = 1;
    m->height = 1;
    m->layers = 4;
    m->outward = true;
    m->depth = depth;
    m->normal = normal;
    for (int k = 0; k < 4; ++k) {
        depth[k] = k < n ? d[k] : INFINITY;
        normal[3 * k] = normal[3 * k + 1] = 0.0f;
        normal[3 * k + 2] = k < n ? (enter[k] ? 1.0f : -1.0f) : 0.0f;
    }
}

// wx_maps_bury (docs/texture.md, `seen`): a full stack whose outermost solid
// stays open buries every crossing after its entering face, as the collider's
// tail reads it; closed solids keep their outline, contact faces are sealed;
// with room left an open crossing is a sheet and kept.
TEST(bury_reads_a_full_stack_as_the_collider_does)
{
    const float view[3] = { 0.0f, 0.0f, -1.0f };
    float depth[4], normal[12], out[4];
    wx_maps m;
    // A facade box entered at 30.6, a trim inside it from 30.799, the box's
    // back on the core's front at 30.8: the core runs on past the fourth layer.
    const float d1[4] = { 30.6f, 30.799f, 30.8f, 30.8f };
    const bool e1[4] = { true, true, false, true };
    one_texel(&m, depth, normal, d1, e1, 4);
    wx_maps_bury(&m, view, 0.004f, out);
    ENSURE(out[0] == 30.6f && isinf(out[1]) && isinf(out[2]) && isinf(out[3]));
    // Two closed solids touching at 30.8: the contact pair is sealed, the
    // outline's faces stay.
    const float d2[4] = { 30.6f, 30.8f, 30.8f, 36.6f };
    const bool e2[4] = { true, false, true, false };
    one_texel(&m, depth, normal, d2, e2, 4);
    wx_maps_bury(&m, view, 0.004f, out);
    ENSURE(out[0] == 30.6f && isinf(out[1]) && isinf(out[2]) && out[3] == 36.6f);
    // Room left: an entering crossing nothing closes is a sheet, kept.
    const float d3[3] = { 10.0f, 11.0f, 12.0f };
    const bool e3[3] = { true, false, true };
    one_texel(&m, depth, normal, d3, e3, 3);
    wx_maps_bury(&m, view, 0.004f, out);
    ENSURE(out[0] == 10.0f && out[1] == 11.0f && out[2] == 12.0f && isinf(out[3]));
}

// wx_crossing_nearer: a pane at 10 m and the wall 1 mm behind it, both facing
// the camera: the wall's point is not the pane's layer's, whatever the pane's
// tolerance; a point facing the other way ignores the wall's crossing.
TEST(a_layer_does_not_hold_a_point_nearer_another_crossing)
{
    float depth[4], normal[12];
    wx_maps m;
    const float d[2] = { 10.0f, 10.001f };
    const bool e[2] = { true, true };
    one_texel(&m, depth, normal, d, e, 2);
    const float toward[3] = { 0.0f, 0.0f, 1.0f }, away[3] = { 0.0f, 0.0f, -1.0f };
    ENSURE(wx_crossing_nearer(depth, normal, 4, 0, 1, 0, 10.001f, toward));
    ENSURE(!wx_crossing_nearer(depth, normal, 4, 1, 1, 0, 10.001f, toward));
    ENSURE(!wx_crossing_nearer(depth, normal, 4, 0, 1, 0, 10.0f, toward));
    ENSURE(!wx_crossing_nearer(depth, normal, 4, 0, 1, 0, 10.001f, away));
    ENSURE(!wx_crossing_nearer(NULL, NULL, 1, 0, 1, 0, 10.001f, toward));
    // A layer view made by wx_maps_layer_view carries the crossings.
    wx_maps view;
    wx_maps_layer_view(&m, 1, &view);
    ENSURE(view.crossing_depth == depth && view.crossing_layers == 4 && view.crossing_layer == 1);
}

int main(void)
{
    RUN(four_maps_load_in_simulation_layout);
    RUN(depth_is_read_from_z);
    RUN(only_selected_maps_are_loaded);
    RUN(mismatched_sizes_name_both_files);
    RUN(missing_channels_are_errors);
    RUN(a_bad_file_frees_the_maps_already_loaded);
    RUN(bury_reads_a_full_stack_as_the_collider_does);
    RUN(a_layer_does_not_hold_a_point_nearer_another_crossing);
    return ensure_summary();
}
