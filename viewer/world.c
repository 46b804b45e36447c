// world.c: scene, maps, simulation and static geometry of the viewer (world.h).
#include "world.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "core/array.h"
#include "gather/gather.h"
#include "io/maps_file.h"
#include "io/scene_xml.h"
#include "model/camera.h"
#include "palette.h"
#include "pipeline/gather_phase.h"
#include "pipeline/outputs.h"
#include "pipeline/simulate_phase.h"
#include "core/limits.h"
#include "pipeline/pipeline.h"
#include "sim/simulate.h"

static const char *const MAP_KINDS[4] = { "depth", "normal", "impact", "dirt" };

// --- parsing and baking ------------------------------------------------------------

wx_result vw_world_parse(vw_world *world, const vw_settings *settings, wx_error *err)
{
    memset(world, 0, sizeof *world);
    wx_result r = wx_scene_load(settings->scene_path, &world->scene, err);
    if (r != WX_OK) {
        return r;
    }
    world->opts = wx_default_run_def(&world->scene);
    if (settings->out_dir != NULL) {
        int n = snprintf(world->opts.out_dir, sizeof world->opts.out_dir, "%s",
                         settings->out_dir);
        if (n < 0 || n >= (int)sizeof world->opts.out_dir) {
            wx_scene_free(&world->scene);
            return wx_fail(err, WX_CAUSE_PATH_TOO_LONG, "--out %s: path too long",
                           settings->out_dir);
        }
    }
    if (settings->threads > 0) {
        world->opts.threads = settings->threads;
    }
    world->opts.quiet = true; // the viewer reports in its own words
    world->mask = -1;
    return WX_OK;
}

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
        int count = cam->is_output ? 2 : 4;
        for (int k = 0; k < count; ++k) {
            char path[WX_PATH_MAX + 128];
            snprintf(path, sizeof path, "%s/%s_%s.exr", world->opts.out_dir, cam->name,
                     MAP_KINDS[k]);
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

// --- geometry --------------------------------------------------------------------

typedef struct vertex_list {
    vw_vertex *data;
    int count;
    int64_t capacity;
    bool failed;
    vw_sample *samples; ///< depth samples only: one per vertex
    int64_t sample_capacity;
} vertex_list;

static void push_vertex(vertex_list *list, const float p[3], const float color[3])
{
    if (!wx_array_reserve((void **)&list->data, &list->capacity, (int64_t)list->count + 1,
                          sizeof *list->data, 256)) {
        list->failed = true;
        return;
    }
    vw_vertex *v = &list->data[list->count++];
    memcpy(v->position, p, sizeof v->position);
    memcpy(v->color, color, sizeof v->color);
}

static void push_line(vertex_list *list, const float a[3], const float b[3], const float color[3])
{
    push_vertex(list, a, color);
    push_vertex(list, b, color);
}

static void to_float_color(const uint8_t rgb[3], float out[3])
{
    for (int k = 0; k < 3; ++k) {
        out[k] = (float)rgb[k] / 255.0f;
    }
}

static void camera_color(const vw_world *world, int c, float out[3])
{
    const wx_scene_camera *cam = &world->scene.cameras[c];
    if (cam->is_output) {
        to_float_color(VW_OUTPUT_COLOR, out);
        return;
    }
    int input = world->camera_maps[c]; // inputs come first in maps
    to_float_color(VW_CAMERA_COLORS[input % VW_CAMERA_COLOR_COUNT], out);
}

// The frame rectangle at d = 0, a line along the viewing direction and a tick
// at the top edge.
static void add_camera_lines(vw_world *world, vertex_list *lines, int c)
{
    const wx_camera *cam = &world->scene.cameras[c].camera;
    float color[3], corner[4][3];
    camera_color(world, c, color);
    static const float uv[4][2] = { { 0, 0 }, { 1, 0 }, { 1, 1 }, { 0, 1 } };
    // The output camera often shares an input camera's frame: drawn a little
    // inside it, both stay visible.
    float inset = world->scene.cameras[c].is_output ? 0.01f : 0.0f;
    for (int k = 0; k < 4; ++k) {
        const float uvd[3] = { inset + (1.0f - 2.0f * inset) * uv[k][0],
                               inset + (1.0f - 2.0f * inset) * uv[k][1], 0.0f };
        wx_camera_map_to_world(cam, uvd, corner[k]);
        for (int a = 0; a < 3; ++a) {
            world->frame_lo[a] = fminf(world->frame_lo[a], corner[k][a]);
            world->frame_hi[a] = fmaxf(world->frame_hi[a], corner[k][a]);
        }
    }
    for (int k = 0; k < 4; ++k) {
        push_line(lines, corner[k], corner[(k + 1) % 4], color);
    }
    float w_ws, h_ws, dir[3], center[3], tip[3];
    wx_camera_frame_size(cam, &w_ws, &h_ws);
    wx_camera_view_dir(cam, dir);
    const float mid[3] = { 0.5f, 0.5f, 0.0f };
    wx_camera_map_to_world(cam, mid, center);
    float len = 0.25f * fminf(w_ws, h_ws);
    for (int a = 0; a < 3; ++a) {
        tip[a] = center[a] + len * dir[a];
    }
    push_line(lines, center, tip, color);
    // A tick on the top edge (v = 1) says which way is up in the map.
    const float top[3] = { 0.5f, 1.0f, 0.0f }, below[3] = { 0.5f, 0.92f, 0.0f };
    float t0[3], t1[3];
    wx_camera_map_to_world(cam, top, t0);
    wx_camera_map_to_world(cam, below, t1);
    push_line(lines, t0, t1, color);
}

// Depth samples of layer `layer` of camera c: every stride-th texel with a
// surface, in the camera's colour darkened for deeper layers.
static void add_layer_points(vw_world *world, vertex_list *points, int c, int layer, int stride)
{
    wx_maps view;
    wx_maps_layer_view(&world->maps[world->camera_maps[c]], layer, &view);
    const wx_maps *m = &view;
    const wx_camera *cam = &world->scene.cameras[c].camera;
    if (m->depth == NULL) {
        return;
    }
    float color[3];
    camera_color(world, c, color);
    int input = world->first_view[c] >= 0 ? world->first_view[c] + layer : -1;
    const float light[3] = { 0.40f, 0.80f, 0.45f }; // roughly unit
    const float darken = vw_layer_shade(layer);
    for (int j = stride / 2; j < m->height; j += stride) {
        for (int i = stride / 2; i < m->width; i += stride) {
            size_t t = (size_t)j * (size_t)m->width + (size_t)i;
            float d = m->depth[t];
            if (wx_depth_is_empty(d)) {
                continue;
            }
            float uvd[3], p[3], shaded[3];
            wx_map_texel_center(m->width, m->height, i, j, &uvd[0], &uvd[1]);
            uvd[2] = d;
            wx_camera_map_to_world(cam, uvd, p);
            float shade = 1.0f;
            if (m->normal != NULL) {
                const float *n = &m->normal[3 * t];
                float ndotl = n[0] * light[0] + n[1] * light[1] + n[2] * light[2];
                shade = 0.45f + 0.55f * fminf(1.0f, fabsf(ndotl));
            }
            shade *= darken;
            for (int a = 0; a < 3; ++a) {
                shaded[a] = color[a] * shade;
            }
            if (!wx_array_reserve((void **)&points->samples, &points->sample_capacity,
                                  (int64_t)points->count + 1, sizeof *points->samples, 256)) {
                points->failed = true;
                return;
            }
            points->samples[points->count] = (vw_sample){
                .input = input, .texel = (int)t, .layer = layer, .shade = shade
            };
            push_vertex(points, p, shaded);
        }
    }
}

// Depth samples of camera c, layer after layer.
static void add_camera_points(vw_world *world, vertex_list *points, int c, int stride)
{
    for (int k = 0; k < vw_world_camera_layers(world, c); ++k) {
        vw_range *r = &world->layer_points[(size_t)c * WX_MAX_LAYERS + (size_t)k];
        r->first = points->count;
        add_layer_points(world, points, c, k, stride);
        r->count = points->count - r->first;
    }
}

static int64_t sample_count(const vw_world *world, int stride)
{
    int64_t n = 0;
    for (int c = 0; c < world->scene.camera_count; ++c) {
        const wx_maps *m = &world->maps[world->camera_maps[c]];
        if (m->depth != NULL) {
            int64_t first = stride / 2;
            int64_t cols = m->width > first ? (m->width - first + stride - 1) / stride : 0;
            int64_t rows = m->height > first ? (m->height - first + stride - 1) / stride : 0;
            n += cols * rows * wx_maps_layers(m);
        }
    }
    return n;
}

static void add_box(vertex_list *lines, const float lo[3], const float hi[3], const float color[3])
{
    for (int e = 0; e < 12; ++e) {
        // Edge e runs along axis e / 4; the other two axes take the corners' bits.
        int axis = e / 4, a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
        float p[3], q[3];
        p[axis] = lo[axis];
        q[axis] = hi[axis];
        p[a1] = q[a1] = (e & 1) ? hi[a1] : lo[a1];
        p[a2] = q[a2] = (e & 2) ? hi[a2] : lo[a2];
        push_line(lines, p, q, color);
    }
}

// Point emitter: a small wire box with a cross inside (the thesis' "box with a
// large point inside"); hemisphere: its base circle and two arcs over the top;
// box: the box (a rectangle when flat) and arrows along its direction from its
// centre and its corners on the min side.
static void add_emitter(vertex_list *lines, const wx_emitter *e, float size, const float color[3])
{
    if (e->kind == WX_EMITTER_BOX) {
        add_box(lines, e->box_min, e->box_max, color);
        // Arrows along the direction from the centre and from four points
        // halfway to the corners of the box's two widest axes.
        float ext[3], mid[3];
        int thin = 0;
        for (int a = 0; a < 3; ++a) {
            ext[a] = e->box_max[a] - e->box_min[a];
            mid[a] = 0.5f * (e->box_min[a] + e->box_max[a]);
            thin = ext[a] < ext[thin] ? a : thin;
        }
        int a1 = (thin + 1) % 3, a2 = (thin + 2) % 3;
        float len = fmaxf(4.0f * size, 0.25f * fmaxf(ext[a1], ext[a2]));
        for (int k = 0; k < 5; ++k) {
            float p[3] = { mid[0], mid[1], mid[2] }, q[3];
            if (k > 0) {
                p[a1] += ((k - 1) & 1 ? 0.25f : -0.25f) * ext[a1];
                p[a2] += ((k - 1) & 2 ? 0.25f : -0.25f) * ext[a2];
            }
            for (int a = 0; a < 3; ++a) {
                q[a] = p[a] + len * e->dir[a];
            }
            push_line(lines, p, q, color);
        }
        return;
    }
    const float *c = e->center;
    if (e->kind == WX_EMITTER_POINT) {
        float lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            lo[a] = c[a] - size;
            hi[a] = c[a] + size;
        }
        add_box(lines, lo, hi, color);
        for (int a = 0; a < 3; ++a) {
            float p[3] = { c[0], c[1], c[2] }, q[3] = { c[0], c[1], c[2] };
            p[a] -= 0.5f * size;
            q[a] += 0.5f * size;
            push_line(lines, p, q, color);
        }
        return;
    }
    enum { SEGMENTS = 48 };
    const float pi = 3.14159265358979f;
    float r = e->radius;
    for (int s = 0; s < SEGMENTS; ++s) {
        float a0 = 2.0f * pi * (float)s / SEGMENTS, a1 = 2.0f * pi * (float)(s + 1) / SEGMENTS;
        float p[3] = { c[0] + r * cosf(a0), c[1], c[2] + r * sinf(a0) };
        float q[3] = { c[0] + r * cosf(a1), c[1], c[2] + r * sinf(a1) };
        push_line(lines, p, q, color);
        // Half circles over the top in the XY and ZY planes.
        float h0 = pi * (float)s / SEGMENTS, h1 = pi * (float)(s + 1) / SEGMENTS;
        float x0[3] = { c[0] + r * cosf(h0), c[1] + r * sinf(h0), c[2] };
        float x1[3] = { c[0] + r * cosf(h1), c[1] + r * sinf(h1), c[2] };
        push_line(lines, x0, x1, color);
        float z0[3] = { c[0], c[1] + r * sinf(h0), c[2] + r * cosf(h0) };
        float z1[3] = { c[0], c[1] + r * sinf(h1), c[2] + r * cosf(h1) };
        push_line(lines, z0, z1, color);
    }
}

// The geometry with at most `max_samples` depth samples (VW_MAX_DEPTH_SAMPLES;
// tests take fewer to see a stride).
static wx_result build_geometry_within(vw_world *world, int64_t max_samples, wx_error *err)
{
    const wx_scene *scene = &world->scene;
    int n = scene->camera_count;
    world->camera_lines = calloc((size_t)n, sizeof *world->camera_lines);
    world->camera_points = calloc((size_t)n, sizeof *world->camera_points);
    world->layer_points = calloc((size_t)n * WX_MAX_LAYERS, sizeof *world->layer_points);
    if (world->camera_lines == NULL || world->camera_points == NULL ||
        world->layer_points == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (viewer geometry)");
    }
    vertex_list lines = { 0 }, points = { 0 };
    for (int a = 0; a < 3; ++a) {
        world->frame_lo[a] = INFINITY;
        world->frame_hi[a] = -INFINITY;
    }
    for (int c = 0; c < n; ++c) {
        world->camera_lines[c].first = lines.count;
        add_camera_lines(world, &lines, c);
        world->camera_lines[c].count = lines.count - world->camera_lines[c].first;
    }
    int stride = 1;
    while (sample_count(world, stride) > max_samples) {
        stride++;
    }
    world->sample_stride = stride;
    // Input cameras first: where the output camera sees the same points, the
    // input colour wins the depth test.
    for (int pass = 0; pass < 2; ++pass) {
        for (int c = 0; c < n; ++c) {
            if (scene->cameras[c].is_output != (pass == 1)) {
                continue;
            }
            world->camera_points[c].first = points.count;
            add_camera_points(world, &points, c, stride);
            world->camera_points[c].count = points.count - world->camera_points[c].first;
        }
    }
    float diag = 0.0f;
    for (int a = 0; a < 3; ++a) {
        float e = world->frame_hi[a] - world->frame_lo[a];
        diag += e * e;
    }
    float size = fmaxf(0.02f * sqrtf(diag), 1e-3f);
    float color[3];
    to_float_color(VW_EMITTER_COLOR, color);
    world->emitter_lines.first = lines.count;
    for (int e = 0; e < scene->emitter_count; ++e) {
        add_emitter(&lines, &scene->emitters[e], size, color);
    }
    world->emitter_lines.count = lines.count - world->emitter_lines.first;
    float lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
        lo[a] = scene->bbox_center[a] - 0.5f * scene->bbox_size;
        hi[a] = scene->bbox_center[a] + 0.5f * scene->bbox_size;
    }
    to_float_color(VW_BBOX_COLOR, color);
    world->bbox_lines.first = lines.count;
    add_box(&lines, lo, hi, color);
    world->bbox_lines.count = lines.count - world->bbox_lines.first;

    world->lines = lines.data;
    world->line_count = lines.count;
    world->points = points.data;
    world->samples = points.samples;
    world->point_count = points.count;
    if (lines.failed || points.failed) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (viewer geometry)");
    }
    return WX_OK;
}

static wx_result build_geometry(vw_world *world, wx_error *err)
{
    return build_geometry_within(world, VW_MAX_DEPTH_SAMPLES, err);
}

// --- maps and simulation ------------------------------------------------------------

static wx_result load_maps(vw_world *world, wx_error *err)
{
    const wx_scene *scene = &world->scene;
    int n = scene->camera_count;
    world->maps = calloc((size_t)n, sizeof *world->maps);
    world->camera_maps = calloc((size_t)n, sizeof *world->camera_maps);
    world->input_camera = calloc((size_t)n, sizeof *world->input_camera);
    world->first_view = calloc((size_t)n, sizeof *world->first_view);
    if (world->maps == NULL || world->camera_maps == NULL || world->input_camera == NULL ||
        world->first_view == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (maps)");
    }
    // The simulation's views: each input camera's layers, camera by camera.
    int inputs = 0, views = 0;
    world->max_layers = 1;
    for (int c = 0; c < n; ++c) {
        const wx_scene_camera *cam = &scene->cameras[c];
        world->first_view[c] = -1;
        if (!cam->is_output) {
            int layers = cam->layers > 1 ? cam->layers : 1;
            world->input_camera[inputs] = c;
            world->camera_maps[c] = inputs++;
            world->first_view[c] = views;
            views += layers;
            world->max_layers = layers > world->max_layers ? layers : world->max_layers;
        }
    }
    for (int c = 0, outputs = 0; c < n; ++c) {
        if (scene->cameras[c].is_output) {
            world->camera_maps[c] = inputs + outputs++;
        }
    }
    for (int c = 0; c < n; ++c) {
        const wx_scene_camera *cam = &scene->cameras[c];
        if (!wx_has_path(cam->depth_path)) {
            return wx_fail(err, WX_CAUSE_MISSING_PHASE,
                           "%s: camera '%s' has no maps; run `weathering bake %s` first",
                           scene->path, cam->name, scene->path);
        }
        unsigned which = WX_MAPS_DEPTH | WX_MAPS_NORMAL;
        if (!cam->is_output) {
            which |= WX_MAPS_IMPACT;
            if (wx_has_path(cam->dirt_path)) {
                // After G the file holds simulated dirt; start from its initialDirt.
                which |= WX_MAPS_DIRT | WX_MAPS_INITIAL_DIRT;
            }
        }
        // Every layer of an input camera (docs/design.md section 14); the
        // output camera has one.
        int layers = !cam->is_output && cam->layers > 1 ? cam->layers : 1;
        wx_result r = wx_maps_load_layers(&world->maps[world->camera_maps[c]], which, 1,
                                          &world->scene, layers, cam->depth_path,
                                          cam->normal_path, cam->impact_path, cam->dirt_path,
                                          err);
        if (r != WX_OK) {
            wx_error_prefix(err, "camera '%s'", cam->name);
            return r;
        }
    }
    return WX_OK;
}

static wx_result create_sim(vw_world *world, const vw_settings *settings, wx_error *err)
{
    wx_sim_def config = wx_default_sim_def(&world->scene);
    config.seed = world->opts.seed;
    config.threads = settings->threads;
    config.hit_capacity = settings->hit_capacity;
    config.maps = world->maps;
    wx_result r = wx_sim_create(&world->scene, &config, &world->sim, err);
    // The depth samples name their views as load_maps counted them: the
    // simulation must count the same.
    for (int c = 0; r == WX_OK && c < world->scene.camera_count; ++c) {
        int first = -1;
        if (world->first_view[c] >= 0 &&
            (wx_sim_camera_views(world->sim, world->camera_maps[c], &first) !=
                 vw_world_camera_layers(world, c) ||
             first != world->first_view[c])) {
            wx_sim_destroy(world->sim);
            world->sim = NULL;
            r = wx_fail(err, WX_CAUSE_BAD_ARGUMENT,
                        "camera '%s': the simulation's views of its layers are not the viewer's",
                        world->scene.cameras[c].name);
        }
    }
    return r;
}

wx_result vw_world_finish(vw_world *world, const vw_settings *settings, wx_error *err)
{
    wx_result r = wx_use_baked_maps(&world->scene, &world->opts, err);
    if (r == WX_OK) {
        r = load_maps(world, err);
    }
    if (r == WX_OK) {
        r = build_geometry(world, err);
    }
    if (r == WX_OK) {
        r = create_sim(world, settings, err);
    }
    if (r == WX_OK) {
        vw_world_show_substance(world, 0);
    }
    return r;
}

// --- layers --------------------------------------------------------------------------

int vw_world_camera_layers(const vw_world *world, int c)
{
    return wx_maps_layers(&world->maps[world->camera_maps[c]]);
}

vw_range vw_world_layer_points(const vw_world *world, int c, int layer)
{
    if (layer < 0) {
        return world->camera_points[c];
    }
    if (layer >= vw_world_camera_layers(world, c)) {
        return (vw_range){ world->camera_points[c].first, 0 };
    }
    return world->layer_points[(size_t)c * WX_MAX_LAYERS + (size_t)layer];
}

int vw_world_next_layer(const vw_world *world, int layer)
{
    return world->max_layers > 1 && layer + 1 < world->max_layers ? layer + 1 : -1;
}

int vw_world_view_camera(const vw_world *world, int view, int *layer)
{
    if (layer != NULL) {
        *layer = 0;
    }
    if (world->sim == NULL || view < 0 || view >= wx_sim_input_count(world->sim)) {
        return -1;
    }
    return world->input_camera[wx_sim_view_camera(world->sim, view, layer)];
}

// --- substances ----------------------------------------------------------------------

int vw_world_substance_count(const vw_world *world)
{
    return world->scene.substance_count > 1 ? world->scene.substance_count : 1;
}

void vw_world_show_substance(vw_world *world, int s)
{
    int S = vw_world_substance_count(world);
    s %= S;
    world->substance = s < 0 ? s + S : s;
    float own = 0.0f, any = 0.0f;
    for (int e = 0; e < world->scene.emitter_count; ++e) {
        const float *load = world->scene.emitters[e].load;
        own = fmaxf(own, load[world->substance]);
        for (int k = 0; k < S; ++k) {
            any = fmaxf(any, load[k]);
        }
    }
    world->load_scale = own > 0.0f ? own : any > 0.0f ? any : 1.0f;
}

int vw_world_next_substance(vw_world *world)
{
    vw_world_show_substance(world, world->substance + 1);
    return world->substance;
}

int vw_world_find_substance(const vw_world *world, const char *name)
{
    for (int s = 0; s < world->scene.substance_count; ++s) {
        if (strcmp(world->scene.substances[s], name) == 0) {
            return s;
        }
    }
    return -1;
}

void vw_world_keep_substance(vw_world *world, const char *name)
{
    int s = name != NULL ? vw_world_find_substance(world, name) : -1;
    vw_world_show_substance(world, s >= 0 ? s : 0);
}

const char *vw_world_substance_name(const vw_world *world)
{
    return world->scene.substances[world->substance];
}

void vw_world_substance_color(const vw_world *world, int s, float out[3])
{
    to_float_color(s == world->scene.dirt_substance ? VW_PARTICLE_DIRTY_COLOR
                                                    : VW_SUBSTANCE_COLORS[s % 8],
                   out);
}

bool vw_world_shows_deposits(const vw_world *world)
{
    return world->scene.substances_declared;
}

double vw_world_deposit(const vw_world *world, int point)
{
    const vw_sample *sample = &world->samples[point];
    const wx_dirt_map *map =
        sample->input >= 0 && world->sim != NULL ? wx_sim_dirt_map(world->sim, sample->input)
                                                 : NULL;
    if (map == NULL) {
        return -1.0;
    }
    int S = map->substances > 1 ? map->substances : 1;
    int s = world->substance < S ? world->substance : 0;
    return map->texels[(size_t)sample->texel * (size_t)S + (size_t)s].dirt;
}

// The k-th smallest of a[0..n) (0-based, n > 0; a is reordered): Hoare's
// selection.
static float select_kth(float *a, size_t n, size_t k)
{
    ptrdiff_t lo = 0, hi = (ptrdiff_t)n - 1, want = (ptrdiff_t)k;
    while (lo < hi) {
        float pivot = a[lo + (hi - lo) / 2];
        ptrdiff_t i = lo, j = hi;
        while (i <= j) {
            while (a[i] < pivot) {
                i++;
            }
            while (a[j] > pivot) {
                j--;
            }
            if (i <= j) {
                float t = a[i];
                a[i++] = a[j];
                a[j--] = t;
            }
        }
        if (want <= j) {
            hi = j;
        } else if (want >= i) {
            lo = i;
        } else {
            break;
        }
    }
    return a[want];
}

float vw_world_deposit_scale(const vw_world *world, const uint32_t *picked, size_t n,
                             float *scratch)
{
    size_t m = 0;
    for (size_t k = 0; k < n; ++k) {
        double a = vw_world_deposit(world, (int)picked[k]);
        if (a > 0.0) {
            scratch[m++] = (float)a;
        }
    }
    if (m == 0) {
        return 0.0f;
    }
    return select_kth(scratch, m, (size_t)((double)(m - 1) * VW_DEPOSIT_QUANTILE));
}

void vw_world_deposit_colors(const vw_world *world, const uint32_t *picked, size_t n,
                             float *scratch, vw_vertex *out)
{
    float scale = vw_world_deposit_scale(world, picked, n, scratch);
    float color[3];
    vw_world_substance_color(world, world->substance, color);
    for (size_t k = 0; k < n; ++k) {
        const int i = (int)picked[k];
        out[k] = world->points[i];
        double a = scale > 0.0f ? vw_world_deposit(world, i) : 0.0;
        if (!(a > 0.0)) {
            continue;
        }
        float t = sqrtf(a < scale ? (float)a / scale : 1.0f);
        float shade = world->samples[i].shade;
        for (int c = 0; c < 3; ++c) {
            out[k].color[c] += t * (color[c] * shade - out[k].color[c]);
        }
    }
}

// --- derived masks -------------------------------------------------------------------

int vw_world_mask_count(const vw_world *world)
{
    return world->scene.mask_count;
}

int vw_world_find_mask(const vw_world *world, const char *name)
{
    for (int m = 0; m < world->scene.mask_count; ++m) {
        if (strcmp(world->scene.masks[m].name, name) == 0) {
            return m;
        }
    }
    return -1;
}

int vw_world_next_mask(const vw_world *world)
{
    int n = world->scene.mask_count;
    return world->mask + 1 < n ? world->mask + 1 : -1;
}

const char *vw_world_mask_kind_name(const vw_world *world, int m)
{
    switch (world->scene.masks[m].kind) {
    case WX_MASK_ACCESSIBILITY: return "accessibility";
    case WX_MASK_EXPOSURE: return "exposure";
    case WX_MASK_CURVATURE: return "curvature";
    case WX_MASK_HEIGHT: return "height";
    case WX_MASK_COMBINE: return "combine";
    }
    return "mask";
}

bool vw_world_mask_ready(const vw_world *world, int m)
{
    return m < 0 || (m < world->scene.mask_count && world->mask_values[m] != NULL);
}

// The grid of the sampled texels of one layer of a camera (`m`: that layer's
// view of its maps): texel (first + gi * stride, first + gj * stride) at
// gj * cols + gi, as add_layer_points walks them, made into surface points as
// wx_masks_at_camera makes a map's texels.
typedef struct sample_grid {
    int cols, rows, first, stride;
    double *position;
    float *normal;
    unsigned char *valid;
    float texel; ///< the map's texel in world units
} sample_grid;

static void free_grid(sample_grid *g)
{
    free(g->position);
    free(g->normal);
    free(g->valid);
    memset(g, 0, sizeof *g);
}

static bool make_grid(const vw_world *world, int c, const wx_maps *m, sample_grid *g)
{
    const wx_camera *cam = &world->scene.cameras[c].camera;
    memset(g, 0, sizeof *g);
    g->stride = world->sample_stride > 0 ? world->sample_stride : 1;
    g->first = g->stride / 2;
    g->cols = m->width > g->first ? (m->width - g->first + g->stride - 1) / g->stride : 0;
    g->rows = m->height > g->first ? (m->height - g->first + g->stride - 1) / g->stride : 0;
    size_t cells = (size_t)g->cols * (size_t)g->rows;
    g->position = malloc((3 * cells + 1) * sizeof *g->position);
    g->normal = malloc((3 * cells + 1) * sizeof *g->normal);
    g->valid = malloc(cells + 1);
    if (g->position == NULL || g->normal == NULL || g->valid == NULL) {
        free_grid(g);
        return false;
    }
    float frame_w, frame_h;
    wx_camera_frame_size(cam, &frame_w, &frame_h);
    g->texel = frame_w / (float)(m->width > 0 ? m->width : 1);
    for (int gj = 0; gj < g->rows; ++gj) {
        for (int gi = 0; gi < g->cols; ++gi) {
            int i = g->first + gi * g->stride, j = g->first + gj * g->stride;
            size_t t = (size_t)j * (size_t)m->width + (size_t)i;
            size_t q = (size_t)gj * (size_t)g->cols + (size_t)gi;
            float d = m->depth[t];
            const float *n = &m->normal[3 * t];
            g->valid[q] = !wx_depth_is_empty(d) && (n[0] != 0.0f || n[1] != 0.0f || n[2] != 0.0f);
            float uvd[3] = { 0.0f, 0.0f, g->valid[q] ? d : 0.0f }, p[3];
            wx_map_texel_center(m->width, m->height, i, j, &uvd[0], &uvd[1]);
            wx_camera_map_to_world(cam, uvd, p);
            for (int k = 0; k < 3; ++k) {
                g->position[3 * q + k] = p[k];
                g->normal[3 * q + k] = n[k];
            }
        }
    }
    return true;
}

// The grid cell of depth sample `point` of a layer's grid (maps `m`), or -1.
static ptrdiff_t grid_cell(const vw_world *world, const wx_maps *m, const sample_grid *g,
                           int point)
{
    int texel = world->samples[point].texel;
    int i = texel % m->width, j = texel / m->width;
    int gi = (i - g->first) / g->stride, gj = (j - g->first) / g->stride;
    if (i < g->first || j < g->first || gi >= g->cols || gj >= g->rows) {
        return -1;
    }
    return (ptrdiff_t)gj * g->cols + gi;
}

// What each mask up to m is in one evaluation of the grids.
typedef enum mask_role {
    ROLE_SKIP,    ///< not read by m: made a cheap Height (its plane is thrown away)
    ROLE_COMPUTE, ///< m or a mask m reads, not known yet: computed and kept
    ROLE_REUSE,   ///< known and read by m: its plane is the known values
} mask_role;

// The scene as one camera's grid evaluates it: masks up to m in their places
// (an accessibility's directions hash its index), those m does not read made
// cheap, those known turned into a Combine of one term reading their values
// from the extra plane substances[substance_count + k] (exact: their values
// lie in [0, 1], which the Combine's clamp keeps), Curvature's default radius
// wide enough for the samples' spacing.
static void masks_for_grid(const wx_scene *scene, int m, const mask_role role[],
                           const sample_grid *g, wx_scene *copy)
{
    *copy = *scene;
    copy->mask_count = m + 1;
    for (int k = 0; k <= m; ++k) {
        wx_mask_def *md = &copy->masks[k];
        if (role[k] == ROLE_SKIP) {
            md->kind = WX_MASK_HEIGHT;
            md->has_min = md->has_max = true;
            md->min = 0.0f;
            md->max = 1.0f;
        } else if (role[k] == ROLE_REUSE) {
            md->kind = WX_MASK_COMBINE;
            md->scale = 1.0f;
            md->term_count = 1;
            md->terms[0] = (wx_term){ .kind = WX_TERM_SUBSTANCE,
                                      .index = scene->substance_count + k,
                                      .weight = 1.0f };
        } else if (md->kind == WX_MASK_CURVATURE && !(md->radius > 0.0f) && g->stride > 2) {
            md->radius = 2.0f * (float)g->stride * g->texel;
        }
    }
}

// The scale of a mask's ramp: 1, or for Curvature the 99th percentile of
// |value| over the samples (their largest when that is 0; 1 when all are flat).
static float mask_scale(const vw_world *world, int m, const float *values)
{
    if (world->scene.masks[m].kind != WX_MASK_CURVATURE) {
        return 1.0f;
    }
    size_t n = 0;
    float *a = malloc(((size_t)world->point_count + 1) * sizeof *a);
    float largest = 0.0f;
    for (int i = 0; a != NULL && i < world->point_count; ++i) {
        if (!isnan(values[i])) {
            a[n++] = fabsf(values[i]);
            largest = fmaxf(largest, fabsf(values[i]));
        }
    }
    float scale = n > 0 ? select_kth(a, n, (size_t)((double)(n - 1) * 0.99)) : 0.0f;
    free(a);
    scale = scale > 0.0f ? scale : largest;
    return scale > 0.0f ? scale : 1.0f;
}

wx_result vw_world_compute_mask(vw_world *world, int m, wx_error *err)
{
    const wx_scene *scene = &world->scene;
    if (m < 0 || m >= scene->mask_count) {
        return m < 0 ? WX_OK : wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "no mask %d", m + 1);
    }
    if (world->mask_values[m] != NULL) {
        return WX_OK;
    }
    // The masks m reads (a Combine reads masks before it): those not known
    // yet are computed and kept too; known ones are read back, but for
    // Curvature's, which are not in [0, 1] (and cheap to compute again).
    mask_role role[WX_MAX_MASKS] = { ROLE_SKIP };
    role[m] = ROLE_COMPUTE;
    int reused = 0;
    for (int k = m; k >= 0; --k) {
        const wx_mask_def *md = &scene->masks[k];
        if (role[k] == ROLE_SKIP) {
            continue;
        }
        if (k < m && world->mask_values[k] != NULL && md->kind != WX_MASK_CURVATURE) {
            role[k] = ROLE_REUSE; // what it reads is not needed then
            reused++;
            continue;
        }
        role[k] = ROLE_COMPUTE;
        for (int t = 0; md->kind == WX_MASK_COMBINE && t < md->term_count; ++t) {
            const wx_term *term = &md->terms[t];
            if (term->kind == WX_TERM_MASK && term->index >= 0 && term->index < k) {
                role[term->index] = ROLE_COMPUTE;
            }
        }
    }
    wx_result r = WX_OK;
    if (world->mask_context == NULL) {
        wx_mask_context *ctx = calloc(1, sizeof *ctx);
        if (ctx == NULL) {
            return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "masks: out of memory");
        }
        r = wx_mask_context_init(scene, world->maps, false, ctx, err);
        if (r != WX_OK) {
            free(ctx);
            return r;
        }
        world->mask_context = ctx;
    }
    float *values[WX_MAX_MASKS] = { NULL };
    wx_scene *copy = malloc(sizeof *copy);
    bool oom = copy == NULL;
    for (int k = 0; k <= m && !oom; ++k) {
        if (role[k] == ROLE_COMPUTE && world->mask_values[k] == NULL) {
            values[k] = malloc(((size_t)world->point_count + 1) * sizeof *values[k]);
            oom = values[k] == NULL;
            for (int i = 0; !oom && i < world->point_count; ++i) {
                values[k][i] = NAN;
            }
        }
    }
    // Each layer of each camera is a grid of its own (docs/design.md section 14).
    for (int view = 0; view < scene->camera_count * WX_MAX_LAYERS && r == WX_OK && !oom; ++view) {
        int c = view / WX_MAX_LAYERS, layer = view % WX_MAX_LAYERS;
        if (layer >= vw_world_camera_layers(world, c)) {
            continue;
        }
        vw_range range = vw_world_layer_points(world, c, layer);
        wx_maps layer_maps;
        wx_maps_layer_view(&world->maps[world->camera_maps[c]], layer, &layer_maps);
        const wx_maps *maps = &layer_maps;
        if (range.count == 0 || maps->depth == NULL || maps->normal == NULL) {
            continue;
        }
        sample_grid g;
        if (!make_grid(world, c, maps, &g)) {
            oom = true;
            break;
        }
        // One zero plane (what Combine terms on substances read), the planes
        // of masks 0..m, then the known values of the masks reused.
        size_t cells = (size_t)g.cols * (size_t)g.rows;
        float *block = calloc((size_t)(m + 2 + reused) * cells + 1, sizeof *block);
        if (block == NULL) {
            free_grid(&g);
            oom = true;
            break;
        }
        float *planes[WX_MAX_MASKS];
        const float *substances[WX_MAX_SUBSTANCES + WX_MAX_MASKS];
        for (int s = 0; s < WX_MAX_SUBSTANCES + WX_MAX_MASKS; ++s) {
            substances[s] = block;
        }
        float *extra = block + (size_t)(m + 2) * cells;
        for (int k = 0; k <= m; ++k) {
            planes[k] = block + (size_t)(k + 1) * cells;
            if (role[k] != ROLE_REUSE) {
                continue;
            }
            for (int i = range.first; i < range.first + range.count; ++i) {
                ptrdiff_t q = grid_cell(world, maps, &g, i);
                float v = world->mask_values[k][i];
                if (q >= 0 && !isnan(v)) {
                    extra[q] = v;
                }
            }
            substances[scene->substance_count + k] = extra;
            extra += cells;
        }
        masks_for_grid(scene, m, role, &g, copy);
        wx_mask_points points = { .width = g.cols,
                                  .height = g.rows,
                                  .position = g.position,
                                  .normal = g.normal,
                                  .valid = g.valid,
                                  .texel = g.texel };
        r = wx_masks_at_points(copy, &world->opts, world->mask_context, -1, &points,
                               substances, planes, err);
        for (int i = range.first; r == WX_OK && i < range.first + range.count; ++i) {
            ptrdiff_t q = grid_cell(world, maps, &g, i);
            for (int k = 0; q >= 0 && g.valid[q] && k <= m; ++k) {
                if (values[k] != NULL) {
                    values[k][i] = planes[k][q];
                }
            }
        }
        free(block);
        free_grid(&g);
    }
    free(copy);
    if (r == WX_OK && oom) {
        r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "mask %s: out of memory", scene->masks[m].name);
    }
    for (int k = 0; k <= m; ++k) {
        if (r == WX_OK && values[k] != NULL) {
            world->mask_scale[k] = mask_scale(world, k, values[k]);
            world->mask_values[k] = values[k];
        } else {
            free(values[k]);
        }
    }
    return r;
}

wx_result vw_world_show_mask(vw_world *world, int m, wx_error *err)
{
    wx_result r = vw_world_compute_mask(world, m, err);
    if (r == WX_OK) {
        world->mask = m < 0 ? -1 : m;
    }
    return r;
}

wx_result vw_world_keep_mask(vw_world *world, const char *name, wx_error *err)
{
    int m = name != NULL ? vw_world_find_mask(world, name) : -1;
    world->mask = -1;
    return vw_world_show_mask(world, m, err);
}

float vw_world_mask_value(const vw_world *world, int point)
{
    if (world->mask < 0 || world->mask_values[world->mask] == NULL) {
        return NAN;
    }
    return world->mask_values[world->mask][point];
}

// Piecewise linear through `count` evenly spaced stops, t in [0, 1].
static void ramp(const uint8_t (*stops)[3], int count, float t, float out[3])
{
    t = t > 0.0f ? (t < 1.0f ? t : 1.0f) : 0.0f;
    float x = t * (float)(count - 1);
    int k = (int)x;
    k = k < count - 1 ? k : count - 2;
    float f = x - (float)k;
    for (int c = 0; c < 3; ++c) {
        float a = (float)stops[k][c] / 255.0f, b = (float)stops[k + 1][c] / 255.0f;
        out[c] = (1.0f - f) * a + f * b; // the stops exactly at f = 0 and 1
    }
}

void vw_world_mask_color(const vw_world *world, float value, float out[3])
{
    int m = world->mask;
    if (m >= 0 && world->scene.masks[m].kind == WX_MASK_CURVATURE) {
        float scale = world->mask_scale[m] > 0.0f ? world->mask_scale[m] : 1.0f;
        ramp(VW_CURVATURE_RAMP, VW_CURVATURE_RAMP_COUNT, 0.5f + 0.5f * value / scale, out);
    } else {
        ramp(VW_MASK_RAMP, VW_MASK_RAMP_COUNT, value, out);
    }
}

void vw_world_mask_colors(const vw_world *world, const uint32_t *picked, size_t n,
                          vw_vertex *out)
{
    for (size_t k = 0; k < n; ++k) {
        const int i = (int)picked[k];
        out[k] = world->points[i];
        float v = vw_world_mask_value(world, i);
        if (!isnan(v)) {
            vw_world_mask_color(world, v, out[k].color);
        }
    }
}

wx_result vw_world_restart(vw_world *world, const vw_settings *settings, wx_error *err)
{
    wx_sim *old = world->sim; // kept running should the new one fail
    wx_result r = create_sim(world, settings, err);
    if (r != WX_OK) {
        world->sim = old;
        return r;
    }
    wx_sim_destroy(old);
    return WX_OK;
}

int64_t vw_world_total_steps(const vw_world *world)
{
    return world->scene.steps * (int64_t)(world->scene.iterations > 1 ? world->scene.iterations : 1);
}

bool vw_world_finished(const vw_world *world)
{
    return world->sim != NULL && wx_sim_step_count(world->sim) >= vw_world_total_steps(world);
}

wx_result vw_world_gather(vw_world *world, char saved[WX_PATH_MAX], wx_error *err)
{
    snprintf(saved, WX_PATH_MAX, "%s", world->opts.out_dir);
    wx_result r = wx_output_prepare(&world->scene, &world->opts, NULL, err);
    if (r == WX_OK) {
        r = wx_write_dirt_maps(&world->scene, &world->opts, world->sim, world->maps, err);
    }
    if (r != WX_OK || world->scene.output_index < 0) {
        return r;
    }
    const wx_scene_camera *out = &world->scene.cameras[world->scene.output_index];
    r = wx_gather_scene(&world->scene, &world->opts, err);
    if (r == WX_OK) {
        r = wx_output_path(&world->scene, &world->opts, out->output_file, saved, err);
    }
    return r;
}

void vw_world_free(vw_world *world)
{
    wx_sim_destroy(world->sim);
    if (world->maps != NULL) {
        for (int c = 0; c < world->scene.camera_count; ++c) {
            wx_maps_free(&world->maps[c]);
        }
    }
    free(world->maps);
    free(world->camera_maps);
    free(world->input_camera);
    free(world->first_view);
    free(world->lines);
    free(world->points);
    free(world->samples);
    free(world->camera_lines);
    free(world->camera_points);
    free(world->layer_points);
    for (int m = 0; m < WX_MAX_MASKS; ++m) {
        free(world->mask_values[m]);
    }
    if (world->mask_context != NULL) {
        wx_mask_context_free(world->mask_context);
        free(world->mask_context);
    }
    wx_scene_free(&world->scene);
    memset(world, 0, sizeof *world);
}
