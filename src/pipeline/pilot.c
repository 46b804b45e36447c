// pilot.c: the pilot run of `info` (pilot.h).
#include "pipeline/pilot.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/progress.h"
#include "io/maps_file.h"
#include "pipeline/bake_phase.h"
#include "pipeline/outputs.h"
#include "sim/emitter.h"
#include "sim/simulate.h"

// Where the baked maps of the pilot's input cameras go: one wx_maps per input
// camera, in scene order.
typedef struct pilot_maps {
    const wx_scene *scene;
    wx_maps *maps;
} pilot_maps;

// Index among the input cameras of scene camera `camera`.
static int input_index(const wx_scene *scene, int camera)
{
    int k = 0;
    for (int c = 0; c < camera; ++c) {
        k += !scene->cameras[c].is_output;
    }
    return k;
}

// wx_bake_maps_fn: the bake's images of an input camera as simulation maps.
static wx_result keep_maps(int camera, wx_image *images, int count, void *user, wx_error *err)
{
    pilot_maps *pm = user;
    if (pm->scene->cameras[camera].is_output || count < 4) {
        return WX_OK; // the output camera: not flown against
    }
    wx_maps *m = &pm->maps[input_index(pm->scene, camera)];
    int w = images[0].width, h = images[0].height;
    size_t texels = (size_t)w * (size_t)h;
    m->width = w;
    m->height = h;
    m->depth = malloc(texels * sizeof *m->depth);
    m->normal = malloc(3 * texels * sizeof *m->normal);
    m->impact = malloc(2 * texels * sizeof *m->impact);
    // The dirt image in the scene's layout (model/maps.h): three channels per
    // substance, then the surface and area records when the scene has them.
    size_t S = pm->scene->substances_declared ? (size_t)pm->scene->substance_count : 1;
    m->substances = (int)S;
    m->dirt = malloc(S * texels * sizeof *m->dirt);
    m->deposit = malloc(S * texels * sizeof *m->deposit);
    m->erosion = malloc(S * texels * sizeof *m->erosion);
    if (m->depth == NULL || m->normal == NULL || m->impact == NULL || m->dirt == NULL ||
        m->deposit == NULL || m->erosion == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "info: out of memory (pilot maps)");
    }
    for (size_t s = 0; s < S; ++s) {
        memcpy(m->dirt + s * texels, images[3].channels[3 * s], texels * sizeof(float));
        memcpy(m->deposit + s * texels, images[3].channels[3 * s + 1], texels * sizeof(float));
        memcpy(m->erosion + s * texels, images[3].channels[3 * s + 2], texels * sizeof(float));
    }
    for (int c = (int)(3 * S); c < images[3].channel_count; ++c) {
        float **plane = strcmp(images[3].channel_names[c], WX_SURFACE_CHANNEL) == 0 ? &m->surface
                        : strcmp(images[3].channel_names[c], WX_AREA_CHANNEL) == 0  ? &m->area
                                                                                     : NULL;
        if (plane != NULL) {
            *plane = malloc(texels * sizeof **plane);
            if (*plane == NULL) {
                return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "info: out of memory (pilot maps)");
            }
            memcpy(*plane, images[3].channels[c], texels * sizeof(float));
        }
    }
    for (size_t t = 0; t < texels; ++t) {
        float d = images[0].channels[0][t];
        m->depth[t] = wx_depth_is_empty(d) ? INFINITY : d;
        for (int k = 0; k < 3; ++k) {
            m->normal[3 * t + (size_t)k] = images[1].channels[k][t];
        }
        m->impact[2 * t] = images[2].channels[0][t];
        m->impact[2 * t + 1] = images[2].channels[1][t];
    }
    return WX_OK;
}

wx_result wx_pilot_run(const wx_scene *scene, const wx_run_def *opts, wx_geometry *geometry,
                       wx_pilot_report *report, wx_error *err)
{
    memset(report, 0, sizeof *report);
    double start = wx_now_s();
    // Every iteration: particles still flying at the end of one fly on into
    // the next (docs/design.md, "Iterations"), so the share still flying at the
    // end of the run, which the run warns on, is the last iteration's. The
    // thinning counts every iteration's particles.
    const int64_t iterations = scene->iterations > 1 ? scene->iterations : 1;
    double duration = wx_scene_duration(scene), total = 0.0;
    for (int e = 0; e < scene->emitter_count; ++e) {
        // rate x time in double: the count saturates at INT64_MAX (rate="1e300"),
        // which would thin such an emitter too little.
        const wx_emitter *em = &scene->emitters[e];
        double span = fmin(duration, em->end) - em->start;
        total += span > 0.0 && em->rate > 0.0 ? em->rate * span * (double)iterations : 0.0;
    }
    if (!(total > 0.0) || scene->input_count == 0) {
        return WX_OK;
    }
    // The pilot's scene: the same, with thinned emitters and small baked maps.
    wx_scene pilot = *scene;
    wx_scene_camera *cameras = malloc((size_t)scene->camera_count * sizeof *cameras);
    wx_emitter *emitters = malloc((size_t)scene->emitter_count * sizeof *emitters);
    wx_maps *maps = calloc((size_t)scene->input_count, sizeof *maps);
    wx_sim *sim = NULL;
    wx_result r = WX_OK;
    if (cameras == NULL || emitters == NULL || maps == NULL) {
        r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "info: out of memory (pilot)");
        goto done;
    }
    memcpy(cameras, scene->cameras, (size_t)scene->camera_count * sizeof *cameras);
    for (int c = 0; c < scene->camera_count; ++c) {
        wx_camera *cam = &cameras[c].camera;
        int side = cam->width > cam->height ? cam->width : cam->height;
        if (cameras[c].has_view && !wx_has_path(cameras[c].depth_path) && side > WX_PILOT_SIDE) {
            // Map space is [0, 1]: only the number of texels changes.
            double s = (double)WX_PILOT_SIDE / side;
            cam->width = (int)fmax(1.0, round(cam->width * s));
            cam->height = (int)fmax(1.0, round(cam->height * s));
        }
    }
    double thin = total > WX_PILOT_PARTICLES ? WX_PILOT_PARTICLES / total : 1.0;
    memcpy(emitters, scene->emitters, (size_t)scene->emitter_count * sizeof *emitters);
    for (int e = 0; e < scene->emitter_count; ++e) {
        emitters[e].rate *= thin;
    }
    pilot.cameras = cameras;
    pilot.emitters = emitters;

    wx_run_def quiet = *opts;
    quiet.quiet = true;
    pilot_maps pm = { &pilot, maps };
    if (wx_scene_needs_bake(&pilot)) {
        r = wx_bake_geometry_into(&pilot, &quiet, geometry, keep_maps, &pm, NULL, err);
    }
    int k = 0;
    for (int c = 0; c < pilot.camera_count && r == WX_OK; ++c) {
        const wx_scene_camera *sc = &pilot.cameras[c];
        if (sc->is_output) {
            continue;
        }
        if (maps[k].depth == NULL) { // maps the scene gives as files
            unsigned which = WX_MAPS_DEPTH | WX_MAPS_NORMAL | WX_MAPS_IMPACT |
                             (wx_has_path(sc->dirt_path) ? WX_MAPS_DIRT | WX_MAPS_INITIAL_DIRT : 0);
            r = wx_maps_load_scene(&maps[k], which, opts->threads, &pilot, sc->depth_path,
                                   sc->normal_path, sc->impact_path, sc->dirt_path, err);
        }
        k++;
    }
    if (r == WX_OK) {
        wx_sim_def def = wx_default_sim_def(&pilot);
        def.seed = opts->seed;
        def.threads = opts->threads;
        def.maps = maps;
        r = wx_sim_create(&pilot, &def, &sim, err);
    }
    for (int64_t s = 0; s < pilot.steps * iterations && r == WX_OK; ++s) {
        r = wx_sim_step(sim, err);
    }
    if (r == WX_OK) {
        wx_sim_stats st;
        wx_sim_get_stats(sim, &st);
        report->particles = st.particles_emitted;
        report->collisions = st.collisions;
        report->escaped_without_hit = st.escaped_without_hit;
        report->alive = st.alive;
    }
done:
    wx_sim_destroy(sim);
    for (int c = 0; maps != NULL && c < scene->input_count; ++c) {
        wx_maps_free(&maps[c]);
    }
    free(maps);
    free(emitters);
    free(cameras);
    report->seconds = wx_now_s() - start;
    return r;
}
