// estimate.c: what `info` estimates before a run (estimate.h): particles per
// emitter, the masks' rays, a texture's coverage.
#include "pipeline/estimate.h"

#include <math.h>

#include "gather/texture.h"
#include "sim/emitter.h"
#include "sim/masks.h"

int64_t wx_emitter_particles(const wx_scene *scene, int e)
{
    return wx_emitter_count_at(&scene->emitters[e], wx_scene_duration(scene));
}

double wx_masks_rays(const wx_scene *scene, double *points)
{
    *points = 0.0;
    if (scene->output_index >= 0) {
        const wx_scene_camera *out = &scene->cameras[scene->output_index];
        *points += (double)out->output_width * out->output_height;
    }
    for (int t = 0; t < scene->texture_count; ++t) {
        *points += (double)scene->textures[t].width * scene->textures[t].height;
    }
    double rays = 0.0;
    for (int m = 0; m < scene->mask_count; ++m) {
        rays += *points * wx_mask_rays(&scene->masks[m]);
    }
    return rays;
}

wx_result wx_texture_coverage_estimate(const wx_texture_map *t, const wx_mesh_data *mesh, int udim,
                                       wx_texture_coverage *out, wx_error *err)
{
    double scale = fmin(1.0, 1024.0 / (double)(t->width > t->height ? t->width : t->height));
    int w = (int)fmax(1.0, round(t->width * scale)), h = (int)fmax(1.0, round(t->height * scale));
    wx_uv_raster_def rd = { .mesh = mesh,
                            .uv = t->uv,
                            .tiles = t->tiles,
                            .width = w,
                            .height = h,
                            .padding = (int)ceil(t->padding * scale) };
    rd.udim = udim;
    wx_uv_raster r;
    wx_result result = wx_uv_raster_build(&rd, &r, err);
    if (result != WX_OK) {
        return result;
    }
    *out = (wx_texture_coverage){ .width = w,
                                  .height = h,
                                  .covered = r.covered,
                                  .overlapping = r.overlapping,
                                  .padded = r.padded,
                                  .triangles_outside = r.triangles_outside,
                                  .triangles_unusable = r.triangles_unusable };
    wx_uv_raster_free(&r);
    return WX_OK;
}
