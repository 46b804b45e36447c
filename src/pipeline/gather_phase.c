// gather_phase.c: the `gather` phase on files (gather_phase.h): the maps in, the
// gather (gather/gather.c) on them, the mask and its preview out.
#include "pipeline/gather_phase.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gather/gather.h"
#include "io/exr.h"
#include "io/maps_file.h"
#include "io/png_preview.h"
#include "pipeline/load.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "pipeline/outputs.h"

wx_result wx_gather_scene(const wx_scene *scene, const wx_run_def *opts, wx_error *err)
{
    int input_count = scene->input_count;
    wx_maps *in_maps = calloc((size_t)input_count + 1, sizeof *in_maps);
    if (in_maps == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "gather: out of memory");
    }
    wx_result result = wx_load_gather_maps(scene, opts, in_maps, err);
    if (result == WX_OK) {
        result = wx_gather_maps(scene, opts, in_maps, NULL, err);
    }
    for (int c = 0; c < input_count; ++c) {
        wx_maps_free(&in_maps[c]);
    }
    free(in_maps);
    return result;
}

wx_result wx_gather_check(const wx_scene *scene, wx_error *err)
{
    if (scene->output_index < 0 || scene->output_index >= scene->camera_count) {
        return WX_OK;
    }
    const wx_scene_camera *out = &scene->cameras[scene->output_index];
    wx_target target = { .kind = WX_TARGET_CAMERA,
                         .camera = &out->camera,
                         .width = out->output_width,
                         .height = out->output_height };
    int texels = 0;
    // The adaptive smoothing's neighbourhood reaches max_radius.
    wx_result r = wx_gather_check_radius(&target, out->adaptive ? out->max_radius : out->radius,
                                         &texels, err);
    if (r != WX_OK) {
        wx_error_prefix(err, "%s:%d: <OutputMap> of camera '%s'", scene->path, out->line,
                        out->name);
    }
    return r;
}

// The two files of a mask: item 0 the EXR, item 1 the PNG preview.
typedef struct mask_files {
    const wx_image *image;
    const char *mask_path, *png_path;
    const float *depth;
    wx_result result[2];
    wx_error err[2];
} mask_files;

static void write_mask_files(int64_t begin, int64_t end, int worker, void *context)
{
    (void)worker;
    mask_files *f = context;
    for (int64_t k = begin; k < end; ++k) {
        f->result[k] = k == 0 ? wx_exr_write(f->mask_path, f->image, &f->err[k])
                              : wx_preview_write_png(f->png_path, f->image->channels[0], f->depth,
                                                     f->image->width, f->image->height,
                                                     &f->err[k]);
    }
}

wx_result wx_gather_maps(const wx_scene *scene, const wx_run_def *opts, const wx_maps *in_maps,
                         wx_phase_detail *detail, wx_error *err)
{
    wx_phase_detail local;
    detail = detail != NULL ? detail : &local;
    memset(detail, 0, sizeof *detail);
    double t0 = wx_now_s();
    if (scene->output_index < 0 || scene->output_index >= scene->camera_count) {
        return wx_fail(err, WX_CAUSE_MISSING,
                       "%s: no output camera (an <Ortho out=\"true\">); gather needs one",
                       scene->path);
    }
    const wx_scene_camera *out = &scene->cameras[scene->output_index];
    char mask_path[WX_PATH_MAX], png_path[WX_PATH_MAX], png_name[WX_OUTPUT_NAME_MAX];
    wx_preview_name(out->output_file, png_name, sizeof png_name);
    wx_result result = wx_output_path(scene, opts, out->output_file, mask_path, err);
    if (result == WX_OK) {
        result = wx_output_path(scene, opts, png_name, png_path, err);
    }
    if (result != WX_OK) {
        return result;
    }

    int input_count = scene->input_count;
    wx_maps out_maps;
    memset(&out_maps, 0, sizeof out_maps);
    wx_gather_view *views = calloc((size_t)input_count + 1, sizeof *views);
    wx_image *image = calloc(1, sizeof *image);
    if (views == NULL || image == NULL) {
        free(views);
        free(image);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "gather: out of memory");
    }

    result = wx_maps_load(&out_maps, WX_MAPS_DEPTH | WX_MAPS_NORMAL, opts->threads, out->depth_path,
                          out->normal_path, NULL, NULL, err);
    if (result != WX_OK) {
        wx_error_prefix(err, "output camera '%s'", out->name);
    } else if (out_maps.width != out->output_width || out_maps.height != out->output_height) {
        result = wx_fail(err, WX_CAUSE_MAP_SIZE,
                         "%s: output camera '%s': its maps are %d x %d but <OutputMap> "
                         "asks for %d x %d",
                         scene->path, out->name, out_maps.width, out_maps.height, out->output_width,
                         out->output_height);
    }
    int k = 0;
    for (int c = 0; c < scene->camera_count && result == WX_OK; ++c) {
        const wx_scene_camera *cam = &scene->cameras[c];
        if (!cam->is_output) {
            views[k] = wx_gather_view_from_maps(&cam->camera, &in_maps[k]);
            k++;
        }
    }
    double t1 = wx_now_s();
    detail->read = t1 - t0;
    if (result == WX_OK) {
        static const char *const names[] = { "Y" };
        result = wx_image_alloc(image, out_maps.width, out_maps.height, 1, names, err);
    }
    if (result == WX_OK) {
        wx_gather_def def = wx_default_gather_def();
        def.target = wx_target_from_camera(&out->camera, &out_maps);
        def.inputs = views;
        def.input_count = k;
        def.radius = out->radius;
        def.adaptive = out->adaptive;
        def.noise = out->noise;
        def.max_radius = out->max_radius;
        def.second_pass = out->second_pass;
        def.normalize = out->normalize;
        def.threads = opts->threads;
        def.quiet = opts->quiet;
        wx_gather_stats st;
        result = wx_gather_compute(&def, image->channels[0], &st, err);
        if (result == WX_OK && def.adaptive && st.surface_texels > 0 &&
            10 * st.capped_texels > st.surface_texels) {
            wx_note(opts->quiet,
                    "gather: %.0f%% of the mask's surface holds fewer than the %.0f impacts "
                    "within maxRadius (%g m) that %g%% noise needs: it stays noisier; fly more "
                    "particles or raise maxRadius",
                    100.0 * (double)st.capped_texels / (double)st.surface_texels, st.target_hits,
                    (double)out->max_radius, 100.0 * (double)out->noise);
        }
    }
    double t2 = wx_now_s();
    detail->compute = t2 - t1;
    if (result == WX_OK) {
        float m[16];
        wx_mask_world_to_camera(&out->camera, m);
        wx_image_set_m44f(image, "worldToCamera", m);
        wx_mask_world_to_ndc(&out->camera, m);
        wx_image_set_m44f(image, "worldToNDC", m);
        wx_image_set_m44f(image, "WTCMatrix", out->camera.wtc);
        wx_image_set_m44f(image, "CTWMatrix", out->camera.ctw);
        wx_image_set_string(image, "cameraName", out->name);
        // The mask and its preview are written side by side (the mask's chunks
        // on the other workers when there are more than two): the same bytes.
        mask_files files = { .image = image, .mask_path = mask_path, .png_path = png_path,
                             .depth = out_maps.depth };
        image->threads = opts->threads > 2 ? opts->threads - 1 : 1;
        wx_parallel_for(opts->threads > 1 ? 2 : 1, 2, 1, write_mask_files, &files);
        result = files.result[0] != WX_OK ? files.result[0] : files.result[1];
        if (result != WX_OK && err != NULL) {
            *err = files.result[0] != WX_OK ? files.err[0] : files.err[1];
        }
    }
    detail->write = wx_now_s() - t2;

    wx_image_free(image);
    free(image);
    free(views);
    wx_maps_free(&out_maps);
    return result;
}
