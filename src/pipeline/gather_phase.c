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
#include "model/naming.h"
#include "pipeline/load.h"
#include "core/progress.h"
#include "pipeline/masks_phase.h"
#include "pipeline/outputs.h"
#include "pipeline/tiles.h"
#include "pipeline/texture_phase.h"

static wx_result write_mask(const wx_scene *scene, const wx_run_def *opts, const wx_maps *in_maps,
                            const wx_maps *given_out, wx_mask_context *masks, int frame,
                            wx_phase_detail *detail, wx_noise_report *noise, wx_error *err);

wx_result wx_gather_scene(const wx_scene *scene, const wx_run_def *opts, wx_error *err)
{
    int input_count = scene->input_count;
    wx_maps *in_maps = calloc((size_t)input_count + 1, sizeof *in_maps);
    if (in_maps == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "gather: out of memory");
    }
    wx_result result = wx_load_gather_maps(scene, opts, in_maps, err);
    if (result == WX_OK) {
        result = wx_gather_maps(scene, opts, in_maps, NULL, NULL, NULL, NULL, NULL, err);
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

wx_result wx_gather_maps(const wx_scene *scene, const wx_run_def *opts, const wx_maps *in_maps,
                         const wx_maps *given_out, const wx_textures *textures,
                         wx_mask_context *masks, wx_phase_detail *detail, wx_noise_report *noise,
                         wx_error *err)
{
    return wx_gather_frame(scene, opts, in_maps, given_out, textures, masks, 0, detail, noise, err);
}

wx_result wx_gather_frame(const wx_scene *scene, const wx_run_def *opts, const wx_maps *in_maps,
                          const wx_maps *given_out, const wx_textures *textures,
                          wx_mask_context *given_masks, int frame, wx_phase_detail *detail,
                          wx_noise_report *noise, wx_error *err)
{
    wx_phase_detail local;
    detail = detail != NULL ? detail : &local;
    memset(detail, 0, sizeof *detail);
    bool has_output = scene->output_index >= 0 && scene->output_index < scene->camera_count;
    if (!has_output && (textures == NULL || textures->count == 0)) {
        return wx_fail(err, WX_CAUSE_MISSING,
                       "%s: no output camera (an <Ortho out=\"true\">) and no <TextureMap>; "
                       "gather needs one",
                       scene->path);
    }
    // The derived masks' collider, shared by the mask and every texture: the
    // caller's, kept over the frames, or one for this frame.
    wx_mask_context own;
    wx_mask_context *masks = given_masks;
    wx_result r = WX_OK;
    if (masks == NULL) {
        masks = &own;
        r = wx_mask_context_init(scene, in_maps, false, &own, err);
    }
    masks->frame = frame; // what <Term age> reads
    // Every layer of a camera is gathered as an input camera of its own; the
    // derived masks' collider above reads the layers together.
    wx_layer_scene layered;
    memset(&layered, 0, sizeof layered);
    if (r == WX_OK) {
        r = wx_layer_scene_init(scene, in_maps, opts->threads, &layered, err);
    }
    if (r == WX_OK && has_output) {
        int every = scene->cameras[scene->output_index].every;
        if (frame == 0 || (every > 0 && frame % every == 0)) {
            r = write_mask(&layered.scene, opts, layered.maps, given_out, masks, frame, detail,
                           noise, err);
        }
    }
    if (r == WX_OK) {
        r = wx_textures_write(&layered.scene, opts, textures, layered.maps, masks, frame, detail,
                              noise, err);
    }
    wx_layer_scene_free(&layered);
    if (masks == &own) {
        wx_mask_context_free(&own);
    }
    return r;
}

// The mask of frame `frame` (0: the final file and its previews).
static wx_result write_mask(const wx_scene *scene, const wx_run_def *opts, const wx_maps *in_maps,
                            const wx_maps *given_out, wx_mask_context *masks, int frame,
                            wx_phase_detail *detail, wx_noise_report *noise, wx_error *err)
{
    double t0 = wx_now_s();
    const wx_scene_camera *out = &scene->cameras[scene->output_index];
    char names[WX_IMAGE_MAX_CHANNELS][WX_NAME_MAX];
    const char *channel_names[WX_IMAGE_MAX_CHANNELS];
    int channels = wx_mask_channels(scene, names);
    for (int c = 0; c < channels; ++c) {
        channel_names[c] = names[c];
    }
    char mask_path[WX_PATH_MAX], png_path[WX_PATH_MAX];
    char frame_name[WX_OUTPUT_NAME_MAX];
    wx_frame_name(out->output_file, frame, frame_name, sizeof frame_name);
    wx_result result =
        wx_output_path(scene, opts, frame > 0 ? frame_name : out->output_file, mask_path, err);
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

    const wx_maps *om = given_out != NULL ? given_out : &out_maps;
    if (given_out == NULL) {
        result = wx_maps_load(&out_maps, WX_MAPS_DEPTH | WX_MAPS_NORMAL, opts->threads,
                              out->depth_path, out->normal_path, NULL, NULL, err);
    }
    if (result != WX_OK) {
        wx_error_prefix(err, "output camera '%s'", out->name);
    } else if (om->width != out->output_width || om->height != out->output_height) {
        result = wx_fail(err, WX_CAUSE_MAP_SIZE,
                         "%s: output camera '%s': its maps are %d x %d but <OutputMap> "
                         "asks for %d x %d",
                         scene->path, out->name, om->width, om->height, out->output_width,
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
        result = wx_image_alloc(image, om->width, om->height, channels, channel_names, err);
    }
    // One gather per substance: its amount and baseline planes (model/maps.h),
    // the hits all substances share.
    // A scene made in memory may leave substance_count 0: the one substance.
    const int substances = scene->substance_count > 0 ? scene->substance_count : 1;
    for (int s = 0; s < substances && result == WX_OK; ++s) {
        wx_gather_views_of_substance(views, in_maps, k, s);
        wx_gather_def def = wx_default_gather_def();
        def.target = wx_target_from_camera(&out->camera, om);
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
        // The final mask's first substance reports its noise (--stats, and a
        // note when much of it is capped).
        const bool report = s == 0 && frame == 0 && def.adaptive;
        wx_gather_stats st;
        result = wx_gather_compute(&def, image->channels[s], report ? &st : NULL, err);
        if (result == WX_OK && report) {
            wx_noise_figures figures = wx_gather_noise_figures(out->output_file, out->noise, &st);
            result = wx_noise_report_add(noise, &figures, err);
        }
        if (result == WX_OK && report && st.surface_texels > 0 &&
            10 * st.capped_texels > st.surface_texels) {
            wx_note(opts->quiet,
                    "gather: %.0f%% of the mask's surface holds fewer than the %.0f impacts "
                    "within maxRadius (%g m) that %g%% noise needs: its noise there is about "
                    "%.2g%% (the median); where that shows, fly more particles or raise "
                    "maxRadius",
                    100.0 * (double)st.capped_texels / (double)st.surface_texels, st.target_hits,
                    (double)out->max_radius, 100.0 * (double)out->noise, 100.0 * st.capped_noise);
        }
    }
    // The derived masks after the substances (a Combine reads them).
    if (result == WX_OK && scene->mask_count > 0) {
        result = wx_masks_at_camera(scene, opts, masks, WX_MASK_SLOT_OUTPUT, &out->camera, om,
                                    (const float *const *)image->channels,
                                    image->channels + substances, err);
    }
    // A tile's run writes only the points its <Tile> owns (docs/tiles.md).
    if (result == WX_OK) {
        wx_tile_restrict_camera(scene, &out->camera, om->depth, image);
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
        image->threads = opts->threads; // the chunks compressed in parallel: the same bytes
        result = wx_image_check_finite(image, mask_path, err);
    }
    if (result == WX_OK) {
        result = wx_exr_write(mask_path, image, err);
    }
    // The final file's previews, one per channel (frames have none).
    char previews[WX_MAX_PREVIEWS][WX_OUTPUT_NAME_MAX];
    int preview_count = frame == 0 ? wx_preview_names(scene, out->output_file, previews) : 0;
    for (int c = 0; c < preview_count && result == WX_OK; ++c) {
        result = wx_output_path(scene, opts, previews[c], png_path, err);
        if (result == WX_OK) {
            result = wx_preview_write_png(png_path, image->channels[c], om->depth, om->width,
                                          om->height, err);
        }
    }
    detail->write = wx_now_s() - t2;

    wx_image_free(image);
    free(image);
    free(views);
    wx_maps_free(&out_maps);
    return result;
}
