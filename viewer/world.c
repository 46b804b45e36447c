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
            ca->has_view != cb->has_view || (ca->has_view && !same_view(&ca->view, &cb->view))) {
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

// Depth samples: every stride-th texel of every camera with a surface.
static void add_camera_points(vw_world *world, vertex_list *points, int c, int stride)
{
    const wx_maps *m = &world->maps[world->camera_maps[c]];
    const wx_camera *cam = &world->scene.cameras[c].camera;
    if (m->depth == NULL) {
        return;
    }
    float color[3];
    camera_color(world, c, color);
    int input = world->scene.cameras[c].is_output ? -1 : world->camera_maps[c];
    const float light[3] = { 0.40f, 0.80f, 0.45f }; // roughly unit
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
            for (int a = 0; a < 3; ++a) {
                shaded[a] = color[a] * shade;
            }
            if (!wx_array_reserve((void **)&points->samples, &points->sample_capacity,
                                  (int64_t)points->count + 1, sizeof *points->samples, 256)) {
                points->failed = true;
                return;
            }
            points->samples[points->count] = (vw_sample){
                .input = input, .texel = (int)t, .shade = shade
            };
            push_vertex(points, p, shaded);
        }
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
            n += cols * rows;
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

static wx_result build_geometry(vw_world *world, wx_error *err)
{
    const wx_scene *scene = &world->scene;
    int n = scene->camera_count;
    world->camera_lines = calloc((size_t)n, sizeof *world->camera_lines);
    world->camera_points = calloc((size_t)n, sizeof *world->camera_points);
    if (world->camera_lines == NULL || world->camera_points == NULL) {
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
    while (sample_count(world, stride) > VW_MAX_DEPTH_SAMPLES) {
        stride++;
    }
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

// --- maps and simulation ------------------------------------------------------------

static wx_result load_maps(vw_world *world, wx_error *err)
{
    const wx_scene *scene = &world->scene;
    int n = scene->camera_count;
    world->maps = calloc((size_t)n, sizeof *world->maps);
    world->camera_maps = calloc((size_t)n, sizeof *world->camera_maps);
    world->input_camera = calloc((size_t)n, sizeof *world->input_camera);
    if (world->maps == NULL || world->camera_maps == NULL || world->input_camera == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (maps)");
    }
    int inputs = 0;
    for (int c = 0; c < n; ++c) {
        if (!scene->cameras[c].is_output) {
            world->input_camera[inputs] = c;
            world->camera_maps[c] = inputs++;
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
        wx_result r = wx_maps_load_scene(&world->maps[world->camera_maps[c]], which, 1,
                                         &world->scene, cam->depth_path, cam->normal_path,
                                         cam->impact_path, cam->dirt_path, err);
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
    return wx_sim_create(&world->scene, &config, &world->sim, err);
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
    free(world->lines);
    free(world->points);
    free(world->samples);
    free(world->camera_lines);
    free(world->camera_points);
    wx_scene_free(&world->scene);
    memset(world, 0, sizeof *world);
}
