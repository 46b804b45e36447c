// ageing.c: the ageing rules (docs/design.md section 9): Transfer, Decay and
// Grow on every surface texel after an iteration's last step, on the real
// amounts and on the baseline the surface would hold without the particles.
#include <math.h>
#include <stdlib.h>

#include "sim/solver_internal.h"

// View c's ageing state: the baseline (amounts without the particles)
// when the scene has rules, and the area Grow multiplies: the bake's record of
// the area the camera owns or, for maps the bake did not write, the area every
// surface texel covers (texel area / |N.view|, clamped as the bake clamps it).
wx_result sim_setup_ageing(wx_sim *sim, int c, wx_error *err)
{
    const wx_scene *scene = sim->scene;
    const wx_maps *m = &sim->views[c];
    size_t n = (size_t)m->width * (size_t)m->height;
    int S = sim->substances;
    sim->surface_of[c] = m->surface;
    if (scene->rule_count == 0 && !wx_scene_has_surface_rules(scene)) {
        return WX_OK;
    }
    sim->baseline[c] = malloc((n > 0 ? n : 1) * (size_t)S * sizeof(double));
    if (sim->baseline[c] == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (ageing)");
    }
    for (size_t t = 0; t < n * (size_t)S; ++t) {
        sim->baseline[c][t] = sim->dirt[c].texels[t].dirt;
    }
    if (!wx_scene_has_grow(scene)) {
        return WX_OK;
    }
    if (m->area != NULL) {
        sim->grow_area[c] = m->area;
        return WX_OK;
    }
    float *area = malloc((n > 0 ? n : 1) * sizeof *area);
    if (area == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (ageing)");
    }
    const wx_camera *cam = &scene->cameras[sim->input_camera[sim_view_camera(sim, c)]].camera;
    float view[3], fw, fh;
    wx_camera_view_dir(cam, view);
    wx_camera_frame_size(cam, &fw, &fh);
    float texel_area = (fw / (float)m->width) * (fh / (float)m->height);
    for (size_t t = 0; t < n; ++t) {
        const float *nn = &m->normal[3 * t];
        float cosine = fabsf(nn[0] * view[0] + nn[1] * view[1] + nn[2] * view[2]);
        area[t] = wx_depth_is_empty(m->depth[t]) ? 0.0f : texel_area / fmaxf(cosine, 1e-3f);
    }
    sim->grow_area[c] = area;
    return WX_OK;
}

// After an iteration's last step: the global rules, then the texel's own
// surface's, on every surface texel of every input camera, in texel order (one
// thread: the ledger's sums are the same for any thread count). A scene with
// surface automata (Seed, Spread) runs rule by rule (surface_automata.c).
wx_result sim_age(wx_sim *sim, wx_error *err)
{
    const wx_scene *scene = sim->scene;
    bool surface_rules = wx_scene_has_surface_rules(scene);
    if (scene->rule_count == 0 && !surface_rules) {
        return WX_OK;
    }
    if (wx_scene_has_surface_automata(scene)) {
        return sim_age_automata(sim, err);
    }
    // Surface rules by global surface index.
    const wx_surface **by_index = sim->surfaces;
    const int known = wx_scene_surface_count(scene);
    int S = sim->substances;
    for (int c = 0; c < sim->view_count; ++c) {
        wx_dirt_map *map = &sim->dirt[c];
        size_t n = (size_t)map->width * (size_t)map->height;
        const float *depth = map->depth;
        const float *surface = sim->surface_of[c];
        const float *area = sim->grow_area[c];
        double *baseline = sim->baseline[c];
        for (size_t t = 0; t < n; ++t) {
            if (depth != NULL && !isfinite(depth[t])) {
                continue;
            }
            wx_dirt_texel *x = &map->texels[t * (size_t)S];
            double a[WX_MAX_SUBSTANCES];
            for (int s = 0; s < S; ++s) {
                a[s] = x[s].dirt;
            }
            double *b = baseline != NULL ? &baseline[t * (size_t)S] : NULL;
            double grow = area != NULL ? (double)area[t] : 0.0;
            sim_run_rules(scene->rules, scene->rule_count, a, b, grow, sim->stats.substance);
            int id = surface != NULL ? (int)surface[t] - 1 : -1;
            if (id >= 0 && id < known) {
                sim_run_rules(by_index[id]->rules, by_index[id]->rule_count, a, b, grow,
                              sim->stats.substance);
            }
            for (int s = 0; s < S; ++s) {
                x[s].dirt = a[s];
            }
        }
    }
    return WX_OK;
}
