// geometry.c: imports the scene's meshes and matches their materials to the
// <Surface>s (geometry.h).
#include "geometry.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "progress.h"

const char *wx_mesh_display_name(const wx_scene *scene, const wx_mesh *mesh)
{
    size_t n = strlen(scene->dir);
    if (n > 0 && strncmp(mesh->path, scene->dir, n) == 0 && mesh->path[n] == '/') {
        return mesh->path + n + 1;
    }
    return mesh->path;
}

static const char *color_use_name(wx_color_use use)
{
    return use == WX_COLOR_IMPACT ? "impact" : "dirt";
}

// The <Surface> of each material: the one that names it, else "*".
static wx_result match_surfaces(const wx_scene *scene, const wx_mesh *mesh,
                                wx_geometry_mesh *g, bool *has_dirt, wx_error *err)
{
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
            return wx_error_set(err, WX_BAD_INPUT,
                                "%s:%d: mesh '%s' has material '%s' that no <Surface> matches "
                                "(materials in the file: %s)",
                                scene->path, mesh->line, wx_mesh_display_name(scene, mesh), name,
                                list);
        }
        const wx_surface *surf = &mesh->surfaces[match];
        if (surf->colors != WX_COLOR_NONE && !data->material_colored[m]) {
            return wx_error_set(err, WX_BAD_INPUT,
                                "%s:%d: <Surface material=\"%s\"> takes its %s values from vertex "
                                "colours, but mesh '%s' has none for material '%s'",
                                scene->path, surf->line, surf->material,
                                color_use_name(surf->colors), wx_mesh_display_name(scene, mesh),
                                name);
        }
        if (surf->dirt > 0.0f || surf->colors == WX_COLOR_DIRT) {
            *has_dirt = true;
        }
        g->surface[m] = match;
    }
    return WX_OK;
}

wx_result wx_geometry_load(const wx_scene *scene, bool quiet, wx_geometry *out, wx_error *err)
{
    memset(out, 0, sizeof *out);
    out->meshes = calloc(scene->mesh_count > 0 ? (size_t)scene->mesh_count : 1,
                         sizeof *out->meshes);
    if (out->meshes == NULL) {
        return wx_error_set(err, WX_FAIL, "out of memory (meshes)");
    }
    wx_result r = WX_OK;
    double t0 = wx_now_s();
    for (int i = 0; i < scene->mesh_count && r == WX_OK; ++i) {
        const wx_mesh *mesh = &scene->meshes[i];
        wx_geometry_mesh *g = &out->meshes[i];
        out->count = i + 1;
        struct stat st;
        if (stat(mesh->path, &st) == 0) {
            out->file_bytes += (int64_t)st.st_size;
        }
        r = wx_mesh_import(mesh->path, &g->data, err);
        if (r != WX_OK) {
            wx_error_prefix(err, "%s:%d", scene->path, mesh->line);
            break;
        }
        if (g->data.triangle_count == 0) {
            wx_warn(quiet, "%s:%d: mesh '%s' has no triangles", scene->path, mesh->line,
                    wx_mesh_display_name(scene, mesh));
        }
        int materials = g->data.material_count;
        g->surface = calloc(materials > 0 ? (size_t)materials : 1, sizeof *g->surface);
        if (g->surface == NULL) {
            r = wx_error_set(err, WX_FAIL, "out of memory (meshes)");
            break;
        }
        r = match_surfaces(scene, mesh, g, &out->has_dirt, err);
        out->triangles += g->data.triangle_count;
        out->vertices += g->data.vertex_count;
    }
    out->import_s = wx_now_s() - t0;
    if (r != WX_OK) {
        wx_geometry_free(out);
    }
    return r;
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
