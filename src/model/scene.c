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
    size_t n = scene->dir != NULL ? strlen(scene->dir) : 0;
    if (n > 0 && strncmp(mesh->path, scene->dir, n) == 0 && mesh->path[n] == '/') {
        return mesh->path + n + 1;
    }
    return mesh->path;
}

int wx_texture_file_tile(const wx_texture_map *t, int f)
{
    if (t->tiles != WX_TILES_UDIM) {
        return -1;
    }
    for (int k = 0; k < WX_UDIM_TILES; ++k) {
        if (wx_texture_has_tile(t, k) && f-- == 0) {
            return k;
        }
    }
    return -1;
}

bool wx_scene_set_path(char **slot, const char *path)
{
    char *copy = NULL;
    if (path != NULL) {
        size_t n = strlen(path) + 1;
        copy = malloc(n);
        if (copy == NULL) {
            return false;
        }
        memcpy(copy, path, n);
    }
    free(*slot);
    *slot = copy;
    return true;
}

int wx_scene_substance(const wx_scene *scene, const char *name)
{
    for (int s = 0; s < scene->substance_count; ++s) {
        if (strcmp(scene->substances[s], name) == 0) {
            return s;
        }
    }
    return -1;
}

bool wx_scene_has_surface_rules(const wx_scene *scene)
{
    for (int m = 0; m < scene->mesh_count; ++m) {
        for (int k = 0; k < scene->meshes[m].surface_count; ++k) {
            if (scene->meshes[m].surfaces[k].rule_count > 0) {
                return true;
            }
        }
    }
    return false;
}

bool wx_scene_has_ageing(const wx_scene *scene)
{
    return scene->substances_declared || scene->rule_count > 0 ||
           wx_scene_has_surface_rules(scene);
}

static bool rules_grow(const wx_rule *rules, int count)
{
    for (int r = 0; r < count; ++r) {
        if (rules[r].kind != WX_RULE_TRANSFER && rules[r].kind != WX_RULE_DECAY) {
            return true;
        }
    }
    return false;
}

static bool rules_automata(const wx_rule *rules, int count)
{
    for (int r = 0; r < count; ++r) {
        if (rules[r].kind != WX_RULE_TRANSFER && rules[r].kind != WX_RULE_DECAY &&
            rules[r].kind != WX_RULE_GROW) {
            return true;
        }
    }
    return false;
}

// Whether `test` holds for the scene's global rules or for some surface's own.
static bool any_rules(const wx_scene *scene, bool (*test)(const wx_rule *, int))
{
    if (test(scene->rules, scene->rule_count)) {
        return true;
    }
    for (int m = 0; m < scene->mesh_count; ++m) {
        for (int k = 0; k < scene->meshes[m].surface_count; ++k) {
            const wx_surface *sf = &scene->meshes[m].surfaces[k];
            if (test(sf->rules, sf->rule_count)) {
                return true;
            }
        }
    }
    return false;
}

bool wx_scene_has_surface_automata(const wx_scene *scene)
{
    return any_rules(scene, rules_automata);
}

bool wx_scene_has_layers(const wx_scene *scene)
{
    for (int c = 0; c < scene->camera_count; ++c) {
        if (!scene->cameras[c].is_output && scene->cameras[c].layers > 1) {
            return true;
        }
    }
    return false;
}

bool wx_scene_has_grow(const wx_scene *scene)
{
    return any_rules(scene, rules_grow);
}

int wx_scene_surface_base(const wx_scene *scene, int mesh)
{
    int base = 0;
    for (int m = 0; m < mesh && m < scene->mesh_count; ++m) {
        base += scene->meshes[m].surface_count;
    }
    return base;
}

int wx_scene_surface_count(const wx_scene *scene)
{
    return wx_scene_surface_base(scene, scene->mesh_count);
}

const wx_surface **wx_scene_surfaces_by_index(const wx_scene *scene)
{
    const wx_surface **table = malloc(((size_t)wx_scene_surface_count(scene) + 1) * sizeof *table);
    for (int m = 0, g = 0; table != NULL && m < scene->mesh_count; ++m) {
        for (int k = 0; k < scene->meshes[m].surface_count; ++k) {
            table[g++] = &scene->meshes[m].surfaces[k];
        }
    }
    return table;
}

void wx_scene_free(wx_scene *scene)
{
    if (scene == NULL) {
        return;
    }
    for (int m = 0; m < scene->mesh_count; ++m) {
        for (int k = 0; k < scene->meshes[m].surface_count; ++k) {
            free(scene->meshes[m].surfaces[k].rules);
        }
        free(scene->meshes[m].surfaces);
        free(scene->meshes[m].path);
    }
    free(scene->meshes);
    free(scene->textures);
    for (int c = 0; c < scene->camera_count; ++c) {
        wx_scene_camera *cam = &scene->cameras[c];
        free(cam->depth_path);
        free(cam->normal_path);
        free(cam->impact_path);
        free(cam->dirt_path);
    }
    free(scene->cameras);
    free(scene->path);
    free(scene->dir);
    free(scene->emitters);
    free(scene->fields);
    free(scene->rules);
    memset(scene, 0, sizeof *scene);
}
