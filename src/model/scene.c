// scene.c: the scene's defaults and its memory (scene.h).
#include "model/scene.h"

#include <stdlib.h>
#include <string.h>

wx_collider_def wx_default_collider_def(void)
{
    return (wx_collider_def){ .resilience = 0.5f, .friction = 0.8f, .adherence = 1.0f,
                                 .deposit = 1.0f, .erosion = 1.0f };
}

double wx_scene_duration(const wx_scene *scene)
{
    return (double)scene->steps * scene->time_step;
}

const char *wx_mesh_display_name(const wx_scene *scene, const wx_mesh *mesh)
{
    size_t n = strlen(scene->dir);
    if (n > 0 && strncmp(mesh->path, scene->dir, n) == 0 && mesh->path[n] == '/') {
        return mesh->path + n + 1;
    }
    return mesh->path;
}

void wx_scene_free(wx_scene *scene)
{
    if (scene == NULL) {
        return;
    }
    for (int m = 0; m < scene->mesh_count; ++m) {
        free(scene->meshes[m].surfaces);
    }
    free(scene->meshes);
    free(scene->cameras);
    free(scene->emitters);
    free(scene->fields);
    memset(scene, 0, sizeof *scene);
}
