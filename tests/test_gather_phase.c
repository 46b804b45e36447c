// test_gather_phase.c: the gather phase on files (pipeline/gather_phase.h):
// a scene of flat quads (gather_fixture.h) whose maps are written as EXR, then
// gathered into the output camera's mask file (its header's matrices, its
// values, its preview) as `weathering gather` does.
#include <math.h>
#include <png.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "core/limits.h"
#include "core/matrix.h"
#include "ensure.h"
#include "gather_fixture.h"
#include "io/exr.h"
#include "model/image.h"
#include "model/scene.h"
#include "pipeline/gather_phase.h"
#include "pipeline/pipeline.h"

// ---------------------------------------------------------------------------
// The gather phase on files.

static wx_result write_maps(const char *dir, const char *name, const test_maps *m, bool dirt)
{
    char path[WX_PATH_MAX];
    wx_image img;
    wx_error err;
    size_t n = (size_t)m->w * m->h;
    static const char *const depth_names[] = { "R" };
    static const char *const rgb[] = { "R", "G", "B" };
    wx_result r = wx_image_alloc(&img, m->w, m->h, 1, depth_names, &err);
    if (r != WX_OK) {
        return r;
    }
    memcpy(img.channels[0], m->depth, n * sizeof(float));
    snprintf(path, sizeof path, "%s/%s_depth.exr", dir, name);
    r = wx_exr_write(path, &img, &err);
    wx_image_free(&img);
    if (r == WX_OK) {
        r = wx_image_alloc(&img, m->w, m->h, 3, rgb, &err);
    }
    if (r == WX_OK) {
        for (size_t t = 0; t < n; ++t) {
            for (int k = 0; k < 3; ++k) {
                img.channels[k][t] = m->normal[3 * t + k];
            }
        }
        snprintf(path, sizeof path, "%s/%s_normal.exr", dir, name);
        r = wx_exr_write(path, &img, &err);
        wx_image_free(&img);
    }
    if (r == WX_OK && dirt) {
        r = wx_image_alloc(&img, m->w, m->h, 3, rgb, &err);
        if (r == WX_OK) {
            memcpy(img.channels[0], m->dirt, n * sizeof(float));
            snprintf(path, sizeof path, "%s/%s_dirt.exr", dir, name);
            r = wx_exr_write(path, &img, &err);
            wx_image_free(&img);
        }
    }
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    return r;
}

static double patch_density(const double p[3], int q)
{
    (void)q;
    // 4 per m^2 in the rectangle x in [0.5, 1.5], y in [0, 0.8] of the wall.
    return p[0] > 0.5 && p[0] < 1.5 && p[1] > 0.0 && p[1] < 0.8 ? 4.0 : 0.0;
}

typedef struct file_scene {
    wx_scene scene;
    wx_scene_camera cams[2];
    wx_run_def opts;
    test_maps in, out;
    char dir[2048];
    char paths[6][WX_PATH_MAX]; ///< the maps' and the scene's paths the structs point at
} file_scene;

// Input camera "front" (maps in dir/maps, simulated dirt in dir/out unless
// `no_simulated`), output camera "out" looking 30 degrees from the side.
static bool make_file_scene(file_scene *fs, const char *tag, bool no_simulated)
{
    memset(fs, 0, sizeof *fs);
    snprintf(fs->dir, sizeof fs->dir, "%s/%s", ensure_tmpdir(), tag);
    char maps_dir[2100], out_dir[2100];
    snprintf(maps_dir, sizeof maps_dir, "%s/maps", fs->dir);
    snprintf(out_dir, sizeof out_dir, "%s/out", fs->dir);
    mkdir(fs->dir, 0777);
    mkdir(maps_dir, 0777);
    mkdir(out_dir, 0777);
    quad wall = big_wall();
    fs->in = render(make_camera(0, 0, 10, 0, 0, 0, 0, 1, 0, 6, 4, 60, 40), &wall, 1, patch_density);
    float a = 30.0f * (float)PI / 180.0f;
    fs->out = render(make_camera(-10 * sinf(a), 0, 10 * cosf(a), 0, 0, 0, 0, 1, 0, 4, 3, 40, 30),
                     &wall, 1, NULL);
    // The scene's own dirt map: clean when simulate's is there, so that reading
    // the wrong one shows.
    test_maps clean = fs->in;
    size_t n = (size_t)clean.w * clean.h;
    clean.dirt = calloc(n, sizeof(float));
    wx_result written = write_maps(maps_dir, "front", no_simulated ? &fs->in : &clean, true);
    free(clean.dirt);
    if (written != WX_OK || write_maps(maps_dir, "out", &fs->out, false) != WX_OK) {
        return false;
    }
    if (!no_simulated) {
        // `simulate` left a dirt map: the same dirt, in the output folder.
        if (write_maps(out_dir, "front", &fs->in, true) != WX_OK) {
            return false;
        }
        char path[WX_PATH_MAX];
        snprintf(path, sizeof path, "%s/front_depth.exr", out_dir);
        remove(path);
        snprintf(path, sizeof path, "%s/front_normal.exr", out_dir);
        remove(path);
    }
    wx_scene_camera *in = &fs->cams[0], *out = &fs->cams[1];
    snprintf(in->name, sizeof in->name, "front");
    in->camera = fs->in.cam;
    snprintf(fs->paths[0], WX_PATH_MAX, "%s/front_depth.exr", maps_dir);
    snprintf(fs->paths[1], WX_PATH_MAX, "%s/front_normal.exr", maps_dir);
    snprintf(fs->paths[2], WX_PATH_MAX, "%s/front_dirt.exr", maps_dir);
    in->depth_path = fs->paths[0];
    in->normal_path = fs->paths[1];
    in->dirt_path = fs->paths[2];
    snprintf(out->name, sizeof out->name, "out");
    out->is_output = true;
    out->camera = fs->out.cam;
    snprintf(fs->paths[3], WX_PATH_MAX, "%s/out_depth.exr", maps_dir);
    snprintf(fs->paths[4], WX_PATH_MAX, "%s/out_normal.exr", maps_dir);
    out->depth_path = fs->paths[3];
    out->normal_path = fs->paths[4];
    snprintf(out->output_file, sizeof out->output_file, "mask.exr");
    out->output_width = 40;
    out->output_height = 30;
    out->radius = 0.0f;
    snprintf(fs->paths[5], WX_PATH_MAX, "%s/scene.xml", fs->dir);
    fs->scene.path = fs->paths[5];
    fs->scene.cameras = fs->cams;
    fs->scene.camera_count = 2;
    fs->scene.input_count = 1;
    fs->scene.output_index = 1;
    snprintf(fs->opts.out_dir, WX_PATH_MAX, "%s", out_dir);
    fs->opts.threads = 2;
    fs->opts.quiet = true;
    return true;
}

static void free_file_scene(file_scene *fs)
{
    maps_free(&fs->in);
    maps_free(&fs->out);
}

TEST(mask_file_projects_world_points_onto_their_texel)
{
    file_scene fs;
    ENSURE(make_file_scene(&fs, "project", false));
    wx_error err;
    wx_result r = wx_gather_scene(&fs.scene, &fs.opts, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    char path[WX_PATH_MAX];
    snprintf(path, sizeof path, "%s/out/mask.exr", fs.dir);
    static const char *const y[] = { "Y" };
    wx_image img;
    ENSURE(wx_exr_read(path, y, 1, &img, &err) == WX_OK);
    ENSURE(img.width == 40 && img.height == 30);
    const wx_attr *ndc = wx_image_find_attr(&img, "worldToNDC");
    const wx_attr *wtc = wx_image_find_attr(&img, "WTCMatrix");
    const wx_attr *ctw = wx_image_find_attr(&img, "CTWMatrix");
    const wx_attr *w2c = wx_image_find_attr(&img, "worldToCamera");
    const wx_attr *name = wx_image_find_attr(&img, "cameraName");
    bool header_ok = ndc != NULL && ndc->type == WX_ATTR_M44F && wtc != NULL && ctw != NULL &&
                     w2c != NULL && name != NULL && strcmp(name->string, "out") == 0;
    bool wtc_ok = header_ok && memcmp(wtc->m44f, fs.out.cam.wtc, sizeof wtc->m44f) == 0 &&
                  memcmp(ctw->m44f, fs.out.cam.ctw, sizeof ctw->m44f) == 0;
    // World points on the wall: inside the dirty patch (1, 0.4, 0), (0.7, 0.55, 0)
    // and outside it (1, -0.4, 0) (its mirror image), (-1, 0.5, 0), (0.2, 0.4, 0).
    // An output texel spans 0.115 x 0.1 m of wall and bilinear taps reach one
    // input texel (0.1 m) further: each point is at least 0.2 m from an edge.
    const float points[5][3] = {
        { 1, 0.4f, 0 }, { 0.7f, 0.55f, 0 }, { 1, -0.4f, 0 }, { -1, 0.5f, 0 }, { 0.2f, 0.4f, 0 }
    };
    const float expected[5] = { 4.0f, 4.0f, 0.0f, 0.0f, 0.0f };
    bool values_ok = header_ok;
    for (int k = 0; k < 5 && values_ok; ++k) {
        float ndc_p[3];
        values_ok = wx_transform_point(ndc->m44f, points[k], ndc_p);
        int i = (int)floorf(ndc_p[0] * 40.0f), j = (int)floorf(ndc_p[1] * 30.0f);
        values_ok = values_ok && i >= 0 && i < 40 && j >= 0 && j < 30;
        if (values_ok) {
            float value = img.channels[0][j * 40 + i];
            values_ok = fabsf(value - expected[k]) <= 1e-4f;
            if (!values_ok) {
                fprintf(stderr, "point %d: texel (%d, %d) holds %g, expected %g\n", k, i, j, value,
                        expected[k]);
            }
        }
    }
    wx_image_free(&img);
    free_file_scene(&fs);
    ENSURE(header_ok);
    ENSURE(wtc_ok);
    ENSURE(values_ok);
}

TEST(preview_png_decodes_with_the_mask_size)
{
    file_scene fs;
    ENSURE(make_file_scene(&fs, "preview", true)); // no simulated dirt: scene dirt map
    wx_error err;
    ENSURE(wx_gather_scene(&fs.scene, &fs.opts, &err) == WX_OK);
    char path[WX_PATH_MAX];
    snprintf(path, sizeof path, "%s/out/mask.png", fs.dir);
    png_image image;
    memset(&image, 0, sizeof image);
    image.version = PNG_IMAGE_VERSION;
    ENSURE(png_image_begin_read_from_file(&image, path) != 0);
    ENSURE(image.width == 40 && image.height == 30);
    image.format = PNG_FORMAT_GA;
    unsigned char *pixels = malloc(PNG_IMAGE_SIZE(image));
    ENSURE(png_image_finish_read(&image, NULL, pixels, 0, NULL) != 0);
    // Every texel sees the wall (opaque); the dirty patch is white (its value 4 is
    // the 99th percentile of the positive values), clean wall black.
    int white = 0, black = 0, transparent = 0;
    for (int t = 0; t < 40 * 30; ++t) {
        white += pixels[2 * t] == 255;
        black += pixels[2 * t] == 0;
        transparent += pixels[2 * t + 1] != 255;
    }
    free(pixels);
    free_file_scene(&fs);
    ENSURE(transparent == 0);
    ENSURE(white > 50 && black > 500);
}

TEST(missing_output_camera_is_an_error)
{
    file_scene fs;
    ENSURE(make_file_scene(&fs, "nooutput", false));
    fs.scene.output_index = -1;
    wx_error err;
    wx_result r = wx_gather_scene(&fs.scene, &fs.opts, &err);
    free_file_scene(&fs);
    ENSURE(r == WX_BAD_INPUT);
    ENSURE(ensure_contains(err.message, "output camera"));
    ENSURE_CAUSE(err, MISSING);
}

int main(void)
{
    RUN(mask_file_projects_world_points_onto_their_texel);
    RUN(preview_png_decodes_with_the_mask_size);
    RUN(missing_output_camera_is_an_error);
    return ensure_summary();
}
