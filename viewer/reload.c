// reload.c: the worlds the viewer runs (app.h): the first one loaded (and
// baked) before any window opens, and R's reload, baked in the background
// while the last good world keeps running.
#include "app.h"

#include <stdio.h>
#include <stdlib.h>

#include "core/progress.h"

bool vw_app_reset_camera_visibility(vw_app *a)
{
    int n = a->world->scene.camera_count;
    bool *visible = realloc(a->camera_visible, (size_t)(n > 0 ? n : 1) * sizeof *visible);
    if (visible == NULL) {
        return false;
    }
    for (int c = 0; c < n; ++c) {
        visible[c] = true;
    }
    a->camera_visible = visible;
    a->show.cameras = visible;
    return true;
}

// Makes a completed world the running one (reload).
static void adopt_world(vw_app *a, vw_world *world)
{
    int old_cameras = a->world->scene.camera_count;
    vw_world_keep_substance(world, vw_world_substance_name(a->world));
    // The mask shown (or about to be) is shown again by name, computed anew
    // for the new maps after the next frame.
    int old_mask = a->mask_request >= 0 ? a->mask_request : a->world->mask;
    int mask = old_mask >= 0 ? vw_world_find_mask(world, a->world->scene.masks[old_mask].name) : -1;
    a->mask_request = mask;
    vw_world_free(a->world);
    free(a->world);
    a->world = world;
    wx_error err;
    if (vw_draw_set_world(&a->draw, world, &err) != WX_OK) {
        vw_app_report(a, true, "%s", err.message);
    }
    if (world->scene.camera_count != old_cameras && !vw_app_reset_camera_visibility(a)) {
        vw_app_report(a, true, "out of memory");
    }
    if (a->show.layer >= world->max_layers) {
        a->show.layer = -1; // the new scene has fewer layers: show them all
    }
    vw_app_reset_rates(a);
    a->playing = true;
    if (mask >= 0) {
        char prefix[WX_PATH_MAX + 32];
        snprintf(prefix, sizeof prefix, "reloaded %s; ", world->scene.path);
        vw_app_report_computing(a, prefix, mask);
    } else {
        vw_app_report(a, false, "reloaded %s", world->scene.path);
    }
}

static void finish_reload(vw_app *a, vw_world *world)
{
    wx_error err;
    if (vw_world_finish(world, &a->settings, &err) != WX_OK) {
        vw_app_report(a, true, "reload failed, the last good scene keeps running: %s", err.message);
        vw_world_free(world);
        free(world);
        return;
    }
    adopt_world(a, world);
}

void vw_app_cancel_pending(vw_app *a)
{
    if (a->pending != NULL) {
        vw_bake_cancel(&a->bake);
        vw_world_free(a->pending);
        free(a->pending);
        a->pending = NULL;
    }
}

void vw_app_reload(vw_app *a)
{
    vw_app_cancel_pending(a);
    vw_world *world = calloc(1, sizeof *world);
    if (world == NULL) {
        vw_app_report(a, true, "reload failed: out of memory");
        return;
    }
    wx_error err;
    if (vw_world_parse(world, &a->settings, &err) != WX_OK) {
        vw_app_report(a, true, "reload failed, the last good scene keeps running: %s", err.message);
        free(world);
        return;
    }
    if (!vw_world_needs_bake(world, a->world)) {
        finish_reload(a, world);
        return;
    }
    if (vw_bake_start(&a->bake, a->exe_dir, world->scene.path, world->opts.out_dir, &err) !=
        WX_OK) {
        vw_app_report(a, true, "reload failed: %s", err.message);
        vw_world_free(world);
        free(world);
        return;
    }
    a->pending = world;
    vw_app_report(a, false, "baking the maps of %s in %s ...", world->scene.path,
                  world->opts.out_dir);
}

void vw_app_poll_pending(vw_app *a)
{
    int status = 0;
    if (a->pending == NULL || !vw_bake_poll(&a->bake, false, &status)) {
        return;
    }
    vw_world *world = a->pending;
    a->pending = NULL;
    if (status != 0) {
        vw_app_report(a, true, "reload failed: `weathering bake` exited with status %d%s%s", status,
                      a->bake.last_line[0] ? ": " : "", a->bake.last_line);
        vw_world_free(world);
        free(world);
        return;
    }
    finish_reload(a, world);
}

// Runs the first load to completion; returns an exit status, or -1 on success.
int vw_app_load_first_world(vw_app *a)
{
    a->world = calloc(1, sizeof *a->world);
    if (a->world == NULL) {
        fprintf(stderr, "weathering-viewer: out of memory\n");
        return WX_FAIL;
    }
    wx_error err;
    wx_result r = vw_world_parse(a->world, &a->settings, &err);
    if (r != WX_OK) {
        fprintf(stderr, "weathering-viewer: %s\n", err.message);
        return r;
    }
    int substance = a->substance != NULL ? vw_world_find_substance(a->world, a->substance) : 0;
    if (substance < 0) {
        const wx_scene *scene = &a->world->scene;
        fprintf(stderr, "weathering-viewer: --substance %s: %s has no such substance (it has",
                a->substance, scene->path);
        for (int s = 0; s < scene->substance_count; ++s) {
            fprintf(stderr, "%s %s", s > 0 ? "," : "", scene->substances[s]);
        }
        fprintf(stderr, ")\n");
        return WX_BAD_INPUT;
    }
    int mask = a->mask != NULL ? vw_world_find_mask(a->world, a->mask) : -1;
    if (a->mask != NULL && mask < 0) {
        const wx_scene *scene = &a->world->scene;
        fprintf(stderr, "weathering-viewer: --mask %s: %s has no such mask (%s", a->mask,
                scene->path, scene->mask_count > 0 ? "it has" : "it has no <Masks>");
        for (int m = 0; m < scene->mask_count; ++m) {
            fprintf(stderr, "%s %s", m > 0 ? "," : "", scene->masks[m].name);
        }
        fprintf(stderr, ")\n");
        return WX_BAD_INPUT;
    }
    if (vw_world_needs_bake(a->world, NULL)) {
        fprintf(stderr, "weathering-viewer: baking the maps of %s into %s\n",
                a->world->scene.path, a->world->opts.out_dir);
        r = vw_bake_start(&a->bake, a->exe_dir, a->world->scene.path, a->world->opts.out_dir,
                          &err);
        if (r != WX_OK) {
            fprintf(stderr, "weathering-viewer: %s\n", err.message);
            return r;
        }
        int status = 0;
        vw_bake_poll(&a->bake, true, &status);
        if (status != 0) {
            fprintf(stderr, "weathering-viewer: `weathering bake %s` failed (exit status %d)\n",
                    a->world->scene.path, status);
            return status == WX_BAD_INPUT ? WX_BAD_INPUT : WX_FAIL;
        }
    }
    r = vw_world_finish(a->world, &a->settings, &err);
    if (r != WX_OK) {
        fprintf(stderr, "weathering-viewer: %s\n", err.message);
        return r;
    }
    vw_world_show_substance(a->world, substance);
    if (mask >= 0) {
        vw_app_report_computing(a, "", mask);
        double t0 = wx_now_s();
        r = vw_world_show_mask(a->world, mask, &err);
        if (r != WX_OK) {
            fprintf(stderr, "weathering-viewer: mask %s: %s\n", a->mask, err.message);
            return r;
        }
        vw_app_report_mask(a, wx_now_s() - t0);
    }
    return -1;
}
