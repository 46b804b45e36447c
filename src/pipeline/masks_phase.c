// masks_phase.c: the derived masks at the targets of a frame (masks_phase.h).
#include "pipeline/masks_phase.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "model/naming.h"
#include "sim/noise.h"

bool wx_masks_worth_keeping(const wx_scene *scene)
{
    if (scene->mask_count == 0) {
        return false;
    }
    for (int frame = 1; frame < scene->iterations; ++frame) {
        if (wx_frame_wanted(scene, frame)) {
            return true;
        }
    }
    return false;
}

int wx_mask_slot_texture(const wx_scene *scene, int t, int f)
{
    int slot = 1;
    for (int k = 0; k < t; ++k) {
        slot += wx_texture_file_count(&scene->textures[k]);
    }
    return slot + f;
}

// Without the meshes' sample: the input cameras' surface texels (every layer),
// each weighted by the area of surface it records (its footprint over the
// cosine between its normal and the camera's axis, the cosine kept above 0.05
// where the surface is seen edge-on), at most WX_NOISE_SAMPLE_POINTS of them
// at an even stride. A surface that several cameras record counts once per
// camera: the remap is then uniform over the recorded area, not the true one.
static wx_result sample_maps(const wx_scene *scene, const wx_maps *in_maps, double **points,
                             double **weights, size_t *count, wx_error *err)
{
    size_t all = 0;
    for (int k = 0; k < scene->input_count; ++k) {
        all += (size_t)in_maps[k].width * (size_t)in_maps[k].height *
               (size_t)wx_maps_layers(&in_maps[k]);
    }
    size_t stride = all / WX_NOISE_SAMPLE_POINTS + 1, cap = all / stride + 1;
    *points = malloc(3 * cap * sizeof **points);
    *weights = malloc(cap * sizeof **weights);
    *count = 0;
    if (*points == NULL || *weights == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "masks: out of memory (noise sample)");
    }
    size_t index = 0;
    int k = 0;
    for (int c = 0; c < scene->camera_count; ++c) {
        if (scene->cameras[c].is_output) {
            continue;
        }
        const wx_camera *cam = &scene->cameras[c].camera;
        const wx_maps *m = &in_maps[k++];
        const size_t texels = (size_t)m->width * (size_t)m->height;
        float frame_w, frame_h, a[3], b[3];
        wx_camera_frame_size(cam, &frame_w, &frame_h);
        const double footprint = (double)frame_w / m->width * (double)frame_h / m->height;
        wx_camera_map_to_world(cam, (const float[3]){ 0.5f, 0.5f, 0.0f }, a);
        wx_camera_map_to_world(cam, (const float[3]){ 0.5f, 0.5f, 1.0f }, b);
        double axis[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
        double length = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
        for (int l = 0; l < wx_maps_layers(m); ++l) {
            for (size_t t = 0; t < texels; ++t, ++index) {
                size_t at = (size_t)l * texels + t;
                const float *n = &m->normal[3 * at];
                float d = m->depth[at];
                if (index % stride != 0 || wx_depth_is_empty(d) ||
                    (n[0] == 0.0f && n[1] == 0.0f && n[2] == 0.0f) || *count >= cap) {
                    continue;
                }
                float uvd[3] = { 0.0f, 0.0f, d }, p[3];
                wx_map_texel_center(m->width, m->height, (int)(t % (size_t)m->width),
                                    (int)(t / (size_t)m->width), &uvd[0], &uvd[1]);
                wx_camera_map_to_world(cam, uvd, p);
                double cosine =
                    length > 0.0 ? fabs(n[0] * axis[0] + n[1] * axis[1] + n[2] * axis[2]) / length
                                 : 1.0;
                for (int x = 0; x < 3; ++x) {
                    (*points)[3 * *count + x] = p[x];
                }
                (*weights)[*count] = footprint / fmax(cosine, 0.05);
                (*count)++;
            }
        }
    }
    return WX_OK;
}

// The remap table of every Noise mask of the scene (wx_mask_context's
// noise_tables): from the meshes' sample when the run made one, else from the
// input cameras' texels.
static wx_result noise_tables_init(const wx_scene *scene, const wx_maps *in_maps,
                                   wx_mask_context *ctx, wx_error *err)
{
    bool any = false;
    for (int m = 0; m < scene->mask_count; ++m) {
        any = any || scene->masks[m].kind == WX_MASK_NOISE;
    }
    if (!any) {
        return WX_OK;
    }
    double *own_points = NULL, *weights = NULL;
    const double *points = scene->surface_sample;
    size_t count = (size_t)scene->surface_sample_count;
    wx_result r = WX_OK;
    if (points == NULL || count == 0) {
        r = sample_maps(scene, in_maps, &own_points, &weights, &count, err);
        points = own_points;
    }
    for (int m = 0; r == WX_OK && m < scene->mask_count; ++m) {
        if (scene->masks[m].kind != WX_MASK_NOISE) {
            continue;
        }
        ctx->noise_tables[m] = malloc(WX_NOISE_TABLE_SIZE * sizeof *ctx->noise_tables[m]);
        r = ctx->noise_tables[m] == NULL
                ? wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "masks: out of memory (noise table)")
                : wx_noise_table_build(&scene->masks[m], points, weights, count,
                                       ctx->noise_tables[m], err);
    }
    free(own_points);
    free(weights);
    return r;
}

wx_result wx_mask_context_init(const wx_scene *scene, const wx_maps *in_maps, bool keep,
                               wx_mask_context *ctx, wx_error *err)
{
    memset(ctx, 0, sizeof *ctx);
    const int n = scene->input_count;
    // Without masks the collider still tells, with layers, which faces the
    // layers hold are enclosed (a TextureMap's seen: wx_masks_unsee_enclosed).
    bool layered = false;
    for (int k = 0; k < n; ++k) {
        layered = layered || wx_maps_layers(&in_maps[k]) > 1;
    }
    if (scene->mask_count == 0 && !(layered && scene->texture_count > 0)) {
        return WX_OK;
    }
    wx_camera *cams = calloc((size_t)n + 1, sizeof *cams);
    wx_maps *maps = calloc((size_t)n + 1, sizeof *maps);
    size_t largest = 0;
    for (int k = 0; k < n; ++k) {
        size_t texels = (size_t)in_maps[k].width * (size_t)in_maps[k].height *
                        (size_t)wx_maps_layers(&in_maps[k]);
        largest = texels > largest ? texels : largest;
    }
    ctx->zero_impact = calloc(2 * largest + 1, sizeof *ctx->zero_impact);
    if (keep) {
        ctx->mask_count = scene->mask_count;
        ctx->slots = wx_mask_slot_texture(scene, scene->texture_count, 0);
        ctx->known = calloc((size_t)ctx->slots * (size_t)scene->mask_count, sizeof *ctx->known);
    }
    wx_result r = WX_OK;
    if (cams == NULL || maps == NULL || ctx->zero_impact == NULL ||
        (keep && ctx->known == NULL)) {
        r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "masks: out of memory");
    }
    double ylo = INFINITY, yhi = -INFINITY;
    int k = 0;
    for (int c = 0; c < scene->camera_count && r == WX_OK; ++c) {
        if (scene->cameras[c].is_output) {
            continue;
        }
        cams[k] = scene->cameras[c].camera;
        // The maps as the collider reads them: depth and normal borrowed.
        maps[k].width = in_maps[k].width;
        maps[k].height = in_maps[k].height;
        maps[k].layers = in_maps[k].layers;
        maps[k].outward = in_maps[k].outward;
        maps[k].depth = in_maps[k].depth;
        maps[k].normal = in_maps[k].normal;
        maps[k].impact = ctx->zero_impact;
        for (int j = 0; !scene->has_bounds && j < maps[k].height; ++j) {
            for (int i = 0; i < maps[k].width; ++i) {
                float d = maps[k].depth[(size_t)j * (size_t)maps[k].width + (size_t)i];
                if (wx_depth_is_empty(d)) {
                    continue;
                }
                float uvd[3], p[3];
                wx_map_texel_center(maps[k].width, maps[k].height, i, j, &uvd[0], &uvd[1]);
                uvd[2] = d;
                wx_camera_map_to_world(&cams[k], uvd, p);
                ylo = fmin(ylo, p[1]);
                yhi = fmax(yhi, p[1]);
            }
        }
        k++;
    }
    if (r == WX_OK) {
        r = wx_collider_init(&ctx->collider, cams, maps, n, false, err);
    }
    if (r == WX_OK && scene->tile.present) {
        float lo[3], hi[3];
        wx_scene_particle_box(scene, lo, hi);
        const double dlo[3] = { lo[0], lo[1], lo[2] }, dhi[3] = { hi[0], hi[1], hi[2] };
        wx_collider_frame_box(&ctx->collider, dlo, dhi);
    }
    if (r == WX_OK) {
        r = noise_tables_init(scene, in_maps, ctx, err);
    }
    free(cams);
    free(maps);
    if (r != WX_OK) {
        wx_mask_context_free(ctx);
        return r;
    }
    ctx->height_min = (float)(scene->has_bounds ? scene->bounds_min[1] : ylo);
    ctx->height_max = (float)(scene->has_bounds ? scene->bounds_max[1] : yhi);
    ctx->ready = true;
    return WX_OK;
}

void wx_mask_context_free(wx_mask_context *ctx)
{
    if (ctx->ready || ctx->collider.cameras != NULL) {
        wx_collider_free(&ctx->collider);
    }
    free(ctx->zero_impact);
    for (int k = 0; ctx->known != NULL && k < ctx->slots * ctx->mask_count; ++k) {
        free(ctx->known[k]);
    }
    free(ctx->known);
    for (int m = 0; m < WX_MAX_MASKS; ++m) {
        free(ctx->noise_tables[m]);
    }
    memset(ctx, 0, sizeof *ctx);
}

wx_result wx_masks_at_points(const wx_scene *scene, const wx_run_def *opts, wx_mask_context *ctx,
                             int slot, const wx_mask_points *points,
                             const float *const *substances, float *const *out, wx_error *err)
{
    const bool keep = ctx->known != NULL && slot >= 0 && slot < ctx->slots;
    float **known = keep ? ctx->known + (size_t)slot * (size_t)scene->mask_count : NULL;
    wx_masks_def def = { .scene = scene,
                         .collider = ctx->ready ? &ctx->collider : NULL,
                         .points = *points,
                         .substances = substances,
                         .height_min = ctx->height_min,
                         .height_max = ctx->height_max,
                         .known = (const float *const *)known,
                         .noise_tables = (const double *const *)ctx->noise_tables,
                         .age = ctx->frame > 0 && scene->iterations > 0
                                    ? (double)ctx->frame / (double)scene->iterations
                                    : 1.0,
                         .seed = opts->seed,
                         .threads = opts->threads,
                         .quiet = opts->quiet };
    wx_result r = wx_masks_compute(&def, out, err);
    // The geometric masks computed now are kept for the next frames (a copy
    // that fails for want of memory only means computing them again).
    const size_t texels = (size_t)points->width * (size_t)points->height;
    for (int m = 0; r == WX_OK && keep && m < scene->mask_count; ++m) {
        if (known[m] == NULL && wx_mask_is_geometric(scene, m)) {
            known[m] = malloc(texels * sizeof *known[m] + 1);
            if (known[m] != NULL) {
                memcpy(known[m], out[m], texels * sizeof *known[m]);
            }
        }
    }
    return r;
}

wx_result wx_masks_at_camera(const wx_scene *scene, const wx_run_def *opts, wx_mask_context *ctx,
                             int slot, const wx_camera *camera, const wx_maps *maps,
                             const float *const *substances, float *const *out, wx_error *err)
{
    const int W = maps->width, H = maps->height;
    const size_t texels = (size_t)W * (size_t)H;
    double *position = malloc(3 * texels * sizeof *position);
    unsigned char *valid = malloc(texels);
    if (position == NULL || valid == NULL) {
        free(position);
        free(valid);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "masks: out of memory (%zu texels)", texels);
    }
    for (int j = 0; j < H; ++j) {
        for (int i = 0; i < W; ++i) {
            size_t t = (size_t)j * (size_t)W + (size_t)i;
            float d = maps->depth[t];
            const float *n = &maps->normal[3 * t];
            valid[t] = !wx_depth_is_empty(d) && (n[0] != 0.0f || n[1] != 0.0f || n[2] != 0.0f);
            float uvd[3] = { 0.0f, 0.0f, valid[t] ? d : 0.0f }, p[3];
            wx_map_texel_center(W, H, i, j, &uvd[0], &uvd[1]);
            wx_camera_map_to_world(camera, uvd, p);
            for (int k = 0; k < 3; ++k) {
                position[3 * t + k] = p[k];
            }
        }
    }
    float frame_w, frame_h;
    wx_camera_frame_size(camera, &frame_w, &frame_h);
    wx_mask_points points = { .width = W,
                              .height = H,
                              .position = position,
                              .normal = maps->normal,
                              .valid = valid,
                              .texel = frame_w / (float)W };
    wx_result r = wx_masks_at_points(scene, opts, ctx, slot, &points, substances, out, err);
    free(position);
    free(valid);
    return r;
}
