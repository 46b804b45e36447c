// mesh.c: the memory of a triangle mesh (mesh.h).
#include "model/mesh.h"

#include <stdlib.h>
#include <string.h>

void wx_mesh_data_release_arrays(wx_mesh_data *mesh)
{
    free(mesh->positions);
    free(mesh->normals);
    free(mesh->colors);
    free(mesh->indices);
    free(mesh->materials);
    mesh->positions = mesh->normals = mesh->colors = NULL;
    mesh->indices = NULL;
    mesh->materials = NULL;
    for (int c = 0; c < WX_MESH_MAX_UV_CHANNELS; ++c) {
        free(mesh->uvs[c]);
        mesh->uvs[c] = NULL;
    }
}

void wx_mesh_data_free(wx_mesh_data *mesh)
{
    wx_mesh_data_release_arrays(mesh);
    free(mesh->material_names);
    free(mesh->material_colored);
    memset(mesh, 0, sizeof *mesh);
}
