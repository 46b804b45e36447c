// geometry.c: the scene's meshes matched to their <Surface>s (geometry.h).
#include "model/geometry.h"

#include "core/matrix.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>


static const char *color_use_name(wx_color_use use)
{
    return use == WX_COLOR_IMPACT ? "impact" : "dirt";
}

wx_result wx_geometry_match(const wx_scene *scene, int mesh_index, wx_geometry_mesh *g,
                            bool *has_dirt, wx_error *err)
{
    const wx_mesh *mesh = &scene->meshes[mesh_index];
    const wx_mesh_data *data = &g->data;
    for (int m = 0; m < data->material_count; ++m) {
        const char *name = data->material_names[m];
        int match = -1, any = -1;
        for (int s = 0; s < mesh->surface_count; ++s) {
            const wx_surface *surf = &mesh->surfaces[s];
            if (strcmp(surf->material, name) == 0 && match < 0) {
                match = s;
            } else if (strcmp(surf->material, "*") == 0 && any < 0) {
                any = s;
            }
        }
        match = match >= 0 ? match : any;
        if (match < 0) {
            char list[512] = "";
            for (int k = 0; k < data->material_count; ++k) {
                wx_list_append(list, sizeof list, data->material_names[k]);
            }
            return wx_fail(err, WX_CAUSE_UNMATCHED_MATERIAL,
                           "%s:%d: mesh '%s' has material '%s' that no <Surface> matches "
                           "(materials in the file: %s)",
                           scene->path, mesh->line, wx_mesh_display_name(scene, mesh), name, list);
        }
        const wx_surface *surf = &mesh->surfaces[match];
        if (surf->colors != WX_COLOR_NONE && !data->material_colored[m]) {
            return wx_fail(err, WX_CAUSE_UNMATCHED_MATERIAL,
                           "%s:%d: <Surface material=\"%s\"> takes its %s values from vertex "
                           "colours, but mesh '%s' has none for material '%s'",
                           scene->path, surf->line, surf->material, color_use_name(surf->colors),
                           wx_mesh_display_name(scene, mesh), name);
        }
        int substances = scene->substance_count > 1 ? scene->substance_count : 1;
        for (int s = 0; s < substances; ++s) {
            *has_dirt = *has_dirt || surf->initial[s] > 0.0f;
        }
        if (surf->colors == WX_COLOR_DIRT || wx_scene_has_grow(scene)) {
            *has_dirt = true; // Grow needs the same record of who owns each point
        }
        g->surface[m] = match;
    }
    return WX_OK;
}

void wx_geometry_free(wx_geometry *geometry)
{
    for (int i = 0; i < geometry->count; ++i) {
        wx_mesh_data_free(&geometry->meshes[i].data);
        free(geometry->meshes[i].surface);
    }
    free(geometry->meshes);
    memset(geometry, 0, sizeof *geometry);
}

double wx_geometry_texels_seen(const wx_mesh_data *mesh, const wx_camera *camera)
{
    double m[16];
    if (mesh->positions == NULL || mesh->indices == NULL ||
        !wx_matrix_is_orthographic(camera->wtc)) {
        return 0.0;
    }
    // Texel coordinates of a position relative to the mesh's origin, in double.
    wx_matrix_fold_origin(camera->wtc, mesh->origin, m);
    const double w = m[15], W = camera->width, H = camera->height;
    double total = 0.0;
    for (int64_t t = 0; t < mesh->triangle_count; ++t) {
        double x[3], y[3];
        bool reaches = false;
        for (int k = 0; k < 3; ++k) {
            const float *p = &mesh->positions[3 * (size_t)mesh->indices[3 * t + k]];
            double u = (p[0] * m[0] + p[1] * m[4] + p[2] * m[8] + m[12]) / w;
            double v = (p[0] * m[1] + p[1] * m[5] + p[2] * m[9] + m[13]) / w;
            x[k] = u * W;
            y[k] = v * H;
            reaches = reaches || (u >= 0.0 && u <= 1.0 && v >= 0.0 && v <= 1.0);
        }
        if (reaches) {
            total += 0.5 * fabs((x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]));
        }
    }
    return total;
}
