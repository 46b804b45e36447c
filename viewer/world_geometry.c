// world_geometry.c: a world's static geometry (world.h): the vertex lists of
// the camera frames, the depth samples of every layer, the emitters and the
// bounding box.
#include "world_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/array.h"
#include "model/camera.h"
#include "palette.h"

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

static void camera_color(const vw_world *world, int c, float out[3])
{
    const wx_scene_camera *cam = &world->scene.cameras[c];
    if (cam->is_output) {
        vw_to_float_color(VW_OUTPUT_COLOR, out);
        return;
    }
    int input = world->camera_maps[c]; // inputs come first in maps
    vw_to_float_color(VW_CAMERA_COLORS[input % VW_CAMERA_COLOR_COUNT], out);
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

wx_result vw_world_build_geometry_within(vw_world *world, int64_t max_samples, wx_error *err)
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
    vw_to_float_color(VW_EMITTER_COLOR, color);
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
    vw_to_float_color(VW_BBOX_COLOR, color);
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

wx_result vw_world_build_geometry(vw_world *world, wx_error *err)
{
    return vw_world_build_geometry_within(world, VW_MAX_DEPTH_SAMPLES, err);
}
