// world_stale.c: a world's staleness (world.h, vw_world_needs_bake): whether
// `weathering bake` must run before the maps can be loaded, from the maps'
// times and what changed since the running world.
#include "world_internal.h"

#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "core/limits.h"
#include "model/naming.h"

static bool file_mtime(const char *path, struct timespec *out)
{
    struct stat st;
    if (!wx_has_path(path) || stat(path, &st) != 0) {
        return false;
    }
    *out = st.st_mtim;
    return true;
}

static bool newer(const struct timespec *a, const struct timespec *b)
{
    return a->tv_sec > b->tv_sec || (a->tv_sec == b->tv_sec && a->tv_nsec > b->tv_nsec);
}

static bool same_view(const wx_view *a, const wx_view *b)
{
    for (int k = 0; k < 3; ++k) {
        if (a->eye[k] != b->eye[k] || a->target[k] != b->target[k] || a->up[k] != b->up[k]) {
            return false;
        }
    }
    return a->width_ws == b->width_ws && a->height_ws == b->height_ws &&
           a->width_px == b->width_px && a->height_px == b->height_px;
}

static bool same_surface(const wx_surface *a, const wx_surface *b)
{
    return strcmp(a->material, b->material) == 0 && a->absorption == b->absorption &&
           a->bounce == b->bounce &&
           memcmp(a->initial, b->initial, sizeof a->initial) == 0 &&
           memcmp(a->deposit, b->deposit, sizeof a->deposit) == 0 &&
           memcmp(a->erosion, b->erosion, sizeof a->erosion) == 0 && a->colors == b->colors;
}

// True when what `weathering bake` reads (cameras and geometry) is the same.
static bool same_bake_input(const wx_scene *a, const wx_scene *b)
{
    if (a->camera_count != b->camera_count || a->mesh_count != b->mesh_count ||
        a->collider.deposit != b->collider.deposit || a->collider.erosion != b->collider.erosion) {
        return false;
    }
    for (int c = 0; c < a->camera_count; ++c) {
        const wx_scene_camera *ca = &a->cameras[c], *cb = &b->cameras[c];
        if (strcmp(ca->name, cb->name) != 0 || ca->is_output != cb->is_output ||
            ca->layers != cb->layers || ca->has_view != cb->has_view || (ca->has_view && !same_view(&ca->view, &cb->view))) {
            return false;
        }
    }
    for (int m = 0; m < a->mesh_count; ++m) {
        const wx_mesh *ma = &a->meshes[m], *mb = &b->meshes[m];
        if (strcmp(ma->path, mb->path) != 0 || ma->surface_count != mb->surface_count) {
            return false;
        }
        for (int s = 0; s < ma->surface_count; ++s) {
            if (!same_surface(&ma->surfaces[s], &mb->surfaces[s])) {
                return false;
            }
        }
    }
    return true;
}

bool vw_world_needs_bake(const vw_world *world, const vw_world *running)
{
    const wx_scene *scene = &world->scene;
    const wx_scene *previous = running != NULL ? &running->scene : NULL;
    bool any = false;
    struct timespec oldest = { 0, 0 };
    for (int c = 0; c < scene->camera_count; ++c) {
        const wx_scene_camera *cam = &scene->cameras[c];
        if (!cam->has_view || wx_has_path(cam->depth_path)) {
            continue;
        }
        int count = cam->is_output ? WX_MAP_IMPACT : WX_MAP_KINDS;
        for (int k = 0; k < count; ++k) {
            char name[WX_PATH_MAX], path[2 * WX_PATH_MAX + 2];
            wx_map_file_name(cam->name, k, name, sizeof name);
            snprintf(path, sizeof path, "%s/%s", world->opts.out_dir, name);
            struct timespec t;
            if (!file_mtime(path, &t)) {
                return true;
            }
            if (!any || newer(&oldest, &t)) {
                oldest = t;
            }
            any = true;
        }
    }
    if (!any) {
        return false;
    }
    if (previous != NULL && !same_bake_input(scene, previous)) {
        return true;
    }
    struct timespec t;
    if (previous == NULL && file_mtime(scene->path, &t) && newer(&t, &oldest)) {
        return true;
    }
    for (int m = 0; m < scene->mesh_count; ++m) {
        if (file_mtime(scene->meshes[m].path, &t) && newer(&t, &oldest)) {
            return true;
        }
    }
    return false;
}
