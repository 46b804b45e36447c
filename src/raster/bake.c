// bake.c: meshes and orthographic cameras to depth, normal, impact and dirt
// EXR maps, rendered offscreen with OSMesa (thesis 4.9.2, docs/design.md sections 1-3).
//
// One GL 4.5 core context renders into a float framebuffer with three colour
// targets in one pass (shaders/bake_*.glsl). Each mesh is imported, mapped onto
// the scene's <Surface>s, uploaded once (its CPU arrays freed on the way) and
// drawn for every camera. The projection is the camera's WTCMatrix itself: clip
// x, y = 2u-1, 2v-1, and clip z maps d over the depth range of the geometry,
// clipped at the eye plane (d = 0). The stored d is computed per fragment from
// the interpolated position, not from the depth buffer. glReadPixels returns
// rows bottom-up; bake_read_target() flips them, the only place that does. Initial
// dirt is given to the input camera that sees each patch most head-on
// (compute_initial_dirt). Each camera's maps go to def->on_maps (the pipeline
// writes them, its files compressed in parallel) before the next camera renders,
// so one set of images is alive. docs/cameras.md describes the choices.
//
// A layered input camera (docs/design.md section 14) is drawn by depth
// peeling: after each pass is read back, attachment 0 is copied into the
// `previous` texture, and the next pass keeps only the crossings behind it
// (bake_frag.glsl). The passes are merged into the camera's layers on the CPU
// (bake_peel.c): where the crossings outnumber the layers, a contact (a solid
// left and another entered at one depth: two solids lying on each other) gives
// way to the crossings behind it, so the layers hold what a particle reaches.
// Its normals are then the mesh's own, out of the solid, and every (camera,
// layer) is a view of the initial-dirt ownership.
//
// This file holds the bake's logic; bake_gl.c the GL side (context, shaders,
// framebuffer, drawing, readback) and bake_peel.c the merge of peeling passes
// into layers, through baker_internal.h.
#include "raster/bake.h"
#include "core/big_alloc.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "raster/baker_internal.h"
#include "model/maps.h"
#include "model/scene.h"
#include "model/geometry.h"
#include "model/ownership.h"
#include "model/mesh.h"
#include "core/matrix.h"
#include "core/progress.h"

// ---------------------------------------------------------------------------
// Messages.

#define warn(b, ...) wx_warn((b)->def->quiet, __VA_ARGS__)

// ---------------------------------------------------------------------------
// Meshes.

// The substance the renderer's dirt target carries (the one vertex colours may
// give): "dirt", or the first substance of a scene without it. The others are
// looked up from each texel's <Surface> (fill_substances).
static int rendered_substance(const wx_scene *scene)
{
    return scene->dirt_substance >= 0 ? scene->dirt_substance : 0;
}

// Fills 2 RGBA texels per material of a mesh from its matched <Surface>:
// (absorption, bounce, dirt, deposit), (erosion, colour use, surface index + 1, 0).
static void material_props(const wx_scene *scene, int mesh_index, const wx_geometry_mesh *g,
                           float *props)
{
    const wx_mesh *mesh = &scene->meshes[mesh_index];
    int base = wx_scene_surface_base(scene, mesh_index);
    int s = rendered_substance(scene);
    for (int m = 0; m < g->data.material_count; ++m) {
        const wx_surface *match = &mesh->surfaces[g->surface[m]];
        float *p = &props[8 * m];
        p[0] = match->absorption;
        p[1] = match->bounce;
        p[2] = match->initial[s];
        p[3] = match->deposit[s];
        p[4] = match->erosion[s];
        p[5] = (float)match->colors; // 0 none, 1 impact, 2 dirt (bake_frag.glsl)
        p[6] = (float)(base + g->surface[m] + 1);
        p[7] = 0.0f;
    }
}

// Projects every vertex into every camera to bake: depth range, and warnings for
// vertices outside the frame or behind the eye.
static void survey_vertices(baker *b, const wx_mesh *mesh, const wx_mesh_data *data)
{
    const wx_scene *scene = b->scene;
    for (int c = 0; c < scene->camera_count; ++c) {
        cam_state *cs = &b->cams[c];
        if (!cs->bake) {
            continue;
        }
        const wx_scene_camera *sc = &scene->cameras[c];
        double m[16];
        wx_matrix_fold_origin(sc->camera.wtc, data->origin, m);
        int64_t outside = 0, behind = 0;
        double d_min = cs->d_min, d_max = cs->d_max;
        const float *p = data->positions;
        for (int64_t v = 0; v < data->vertex_count; ++v, p += 3) {
            double u = p[0] * m[0] + p[1] * m[4] + p[2] * m[8] + m[12];
            double w = p[0] * m[1] + p[1] * m[5] + p[2] * m[9] + m[13];
            double d = p[0] * m[2] + p[1] * m[6] + p[2] * m[10] + m[14];
            outside += u < 0.0 || u > 1.0 || w < 0.0 || w > 1.0;
            behind += d < 0.0;
            d_min = d < d_min ? d : d_min;
            d_max = d > d_max ? d : d_max;
        }
        cs->d_min = d_min;
        cs->d_max = d_max;
        if (outside > 0) {
            warn(b, "%s: camera '%s': %lld of %lld vertices of mesh '%s' fall outside its frame",
                 scene->path, sc->name, (long long)outside, (long long)data->vertex_count,
                 wx_mesh_display_name(scene, mesh));
        }
        if (behind > 0) {
            warn(b,
                 "%s: camera '%s': %lld of %lld vertices of mesh '%s' lie behind its eye (d < 0) "
                 "and are not seen",
                 scene->path, sc->name, (long long)behind, (long long)data->vertex_count,
                 wx_mesh_display_name(scene, mesh));
        }
    }
}

// The smallest texel (world units) of the cameras this bake draws.
static double finest_texel(const baker *b)
{
    double finest = INFINITY;
    for (int c = 0; c < b->scene->camera_count; ++c) {
        const wx_camera *cam = &b->scene->cameras[c].camera;
        if (!b->cams[c].bake || cam->width <= 0 || cam->height <= 0) {
            continue;
        }
        float w, h;
        wx_camera_frame_size(cam, &w, &h);
        finest = fmin(finest, fmin((double)w / cam->width, (double)h / cam->height));
    }
    return finest;
}

// How finely the triangles of a smooth-shaded mesh are cut so that the maps
// record the smooth surface its normals describe (wx_mesh_smooth_subdivide,
// docs/cameras.md): pieces of about SMOOTH_PIECE_TEXELS of the finest camera's
// texels along the longest curved edges (the 90th percentile: a few long
// edges do not cut every triangle), at most SMOOTH_MAX_LEVEL, and at most
// WX_SMOOTH_MAX_TRIANGLES triangles in all (a dense scan stays as it is).
enum { SMOOTH_MAX_LEVEL = 8 };
#define SMOOTH_PIECE_TEXELS 4.0

static int smooth_level(const baker *b, const wx_mesh_data *data)
{
    double edge = wx_mesh_curved_edge_length(data, 0.9), texel = finest_texel(b);
    if (!(edge > 0.0) || !isfinite(texel) || !(texel > 0.0)) {
        return 1;
    }
    double level = fmin(ceil(edge / (SMOOTH_PIECE_TEXELS * texel)), SMOOTH_MAX_LEVEL);
    double curved = (double)wx_mesh_curved_triangles(data);
    while (level > 1.0 && curved * level * level > WX_SMOOTH_MAX_TRIANGLES) {
        level -= 1.0;
    }
    return level > 1.0 ? (int)level : 1;
}

// Uploads every mesh of the geometry (its arrays are released on the way).
static wx_result load_meshes(baker *b, wx_geometry *geometry, wx_error *err)
{
    const wx_scene *scene = b->scene;
    b->meshes = calloc(scene->mesh_count > 0 ? (size_t)scene->mesh_count : 1, sizeof *b->meshes);
    if (b->meshes == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
    }
    b->stats->import_s += geometry->import_s;
    for (int i = 0; i < geometry->count; ++i) {
        const wx_mesh *mesh = &scene->meshes[i];
        wx_geometry_mesh *g = &geometry->meshes[i];
        wx_mesh_data *data = &g->data;
        if (data->triangle_count == 0) {
            continue;
        }
        double t1 = wx_now_s();
        // The mesh as the file has it (the smooth surface may cut it finer).
        b->stats->triangles += data->triangle_count;
        b->stats->vertices += data->vertex_count;
        float *props = malloc((size_t)data->material_count * 8 * sizeof(float));
        wx_result r = WX_OK;
        if (props == NULL) {
            r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
        } else {
            material_props(scene, i, g, props);
            r = wx_mesh_smooth_subdivide(data, smooth_level(b, data), err);
            if (r == WX_OK) {
                survey_vertices(b, mesh, data);
                r = bake_upload_mesh(b, data, props, &b->meshes[b->mesh_count], err);
            }
            b->mesh_count++; // counted even when incomplete, so that it is deleted
            if (r != WX_OK) {
                wx_error_prefix(err, "%s:%d: mesh '%s'", scene->path, mesh->line,
                                wx_mesh_display_name(scene, mesh));
            }
        }
        free(props);
        wx_mesh_data_release_arrays(data);
        b->stats->setup_s += wx_now_s() - t1;
        if (r != WX_OK) {
            return r;
        }
    }
    if (b->stats->triangles == 0) {
        return wx_fail(err, WX_CAUSE_BAD_MESH,
                       "%s: the meshes of <Geometry> hold no triangles to bake the cameras "
                       "given by <View> from",
                       scene->path);
    }
    b->has_dirt = geometry->has_dirt;
    return WX_OK;
}

// ---------------------------------------------------------------------------
// Initial dirt (docs/design.md section 3): stored once, in the input camera that sees the
// patch most head-on. Every layer of a layered camera is a view of its own.

// The depth map of an input camera that the scene gives as files (read by the
// caller), for the visibility test: copied, "no surface" as +inf. Its layers
// count when the caller read their normals too, else its layer 0 alone.
static wx_result take_given_depth(baker *b, int c, wx_error *err)
{
    const wx_maps *given = b->def->given_depth != NULL ? &b->def->given_depth[c] : NULL;
    if (given == NULL || given->depth == NULL) {
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "bake: no depth map given for camera '%s'",
                       b->scene->cameras[c].name);
    }
    cam_state *cs = &b->cams[c];
    int layers = wx_maps_layers(given) > 1 && given->normal != NULL ? wx_maps_layers(given) : 1;
    size_t n = (size_t)given->width * (size_t)given->height * (size_t)layers;
    cs->depth = wx_big_malloc((n > 0 ? n : 1) * sizeof *cs->depth);
    if (cs->depth == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
    }
    if (layers > 1) {
        cs->normal = wx_big_malloc(3 * n * sizeof *cs->normal);
        if (cs->normal == NULL) {
            return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
        }
        memcpy(cs->normal, given->normal, 3 * n * sizeof *cs->normal);
    }
    cs->layers = layers;
    cs->depth_width = given->width;
    cs->depth_height = given->height;
    for (size_t k = 0; k < n; ++k) {
        cs->depth[k] = wx_depth_is_empty(given->depth[k]) ? INFINITY : given->depth[k];
    }
    return WX_OK;
}

// The views of the initial-dirt ownership while camera c bakes: one per layer
// of every input camera whose depth is known, in scene order, each camera's
// layers nearest first; a layered camera's views carry its outward normals.
// Camera c's are its planes just baked: depth[l] per layer and, layered,
// `normal` (3 interleaved floats per texel, one layer after the other).
// *self is the index of c's layer 0. NULL when out of memory.
static wx_owner_view *owner_views(const baker *b, int c, float *const *depth, const float *normal,
                                  int *count, int *self)
{
    const wx_scene *scene = b->scene;
    int total = 0;
    for (int k = 0; k < scene->camera_count; ++k) {
        if (scene->cameras[k].is_output || (k != c && b->cams[k].depth == NULL)) {
            continue;
        }
        total += k == c ? bake_cam_layers(&scene->cameras[k]) : b->cams[k].layers;
    }
    wx_owner_view *views = malloc((total > 0 ? (size_t)total : 1) * sizeof *views);
    if (views == NULL) {
        return NULL;
    }
    int n = 0;
    for (int k = 0; k < scene->camera_count; ++k) {
        const wx_scene_camera *sk = &scene->cameras[k];
        const cam_state *ks = &b->cams[k];
        if (sk->is_output || (k != c && ks->depth == NULL)) {
            continue;
        }
        int layers = k == c ? bake_cam_layers(sk) : ks->layers;
        int w = k == c ? sk->camera.width : ks->depth_width;
        int h = k == c ? sk->camera.height : ks->depth_height;
        size_t texels = (size_t)w * (size_t)h;
        const float *normals = k == c ? normal : ks->normal;
        if (k == c) {
            *self = n;
        }
        for (int l = 0; l < layers; ++l) {
            const float *d = k == c ? depth[l] : ks->depth + (size_t)l * texels;
            wx_owner_view_init(&views[n], &sk->camera, d, w, h);
            if (layers > 1) {
                views[n].normal = normals + 3 * (size_t)l * texels;
            }
            ++n;
        }
    }
    *count = n;
    return views;
}

// Turns the density planes of view `self` (a layer of camera c; one per
// substance) into amounts: density x texel area / |N.view| x the share of the
// texel's surface the view owns (model/ownership.h: the view that sees a point
// most head-on holds what lies there, so every amount is stored once and a
// border between two views' parts is shared as the gather reads it); `area`
// (may be NULL) receives texel area / |N.view| x that share (what Grow
// multiplies). `normal`: the layer's x, y, z planes.
static wx_result compute_initial_dirt(baker *b, int c, const wx_owner_view *views, int count,
                                      int self, float *const *normal, float *const *planes,
                                      int planes_count, float *area, wx_error *err)
{
    const wx_scene_camera *sc = &b->scene->cameras[c];
    int width = sc->camera.width, height = sc->camera.height;
    float view[3], frame_w, frame_h;
    wx_camera_view_dir(&sc->camera, view);
    wx_camera_frame_size(&sc->camera, &frame_w, &frame_h);
    float texel_area = (frame_w / (float)width) * (frame_h / (float)height);

    size_t texels = (size_t)width * (size_t)height;
    // No dirt to own and no area asked: every amount stays 0 (the surfaces
    // start clean, as most scenes' do), and the ownership is not needed.
    bool clean = area == NULL;
    for (int s = 0; s < planes_count && clean; ++s) {
        for (size_t t = 0; t < texels && clean; ++t) {
            clean = planes[s][t] == 0.0f;
        }
    }
    if (clean) {
        return WX_OK;
    }
    float *share = wx_big_malloc((texels > 0 ? texels : 1) * sizeof *share);
    if (share == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
    }
    wx_result r = wx_owned_fraction(views, count, self, normal[0], normal[1], normal[2], 1,
                                    b->def->threads > 0 ? b->def->threads : 1, share, err);
    if (r != WX_OK) {
        free(share);
        return r;
    }
    for (size_t t = 0; t < texels; ++t) {
        float cos_c = fabsf(normal[0][t] * view[0] + normal[1][t] * view[1] +
                            normal[2][t] * view[2]);
        float owned_area = share[t] * texel_area / fmaxf(cos_c, MIN_COSINE);
        for (int s = 0; s < planes_count; ++s) {
            planes[s][t] = owned_area > 0.0f ? planes[s][t] * owned_area : 0.0f;
        }
        if (area != NULL) {
            area[t] = owned_area;
        }
    }
    free(share);
    return WX_OK;
}

// ---------------------------------------------------------------------------
// The images handed to the caller.

// Makes the set's images W x H: depth (R), normal, impact (R, G, B), dirt (the
// scene's layout, model/maps.h: R, G, B for version 1's one substance), each
// channel once per layer: layer 0's as they are, then layer 1's named
// "layer1.R"... (wx_layer_channel), and so on.
static wx_result size_set(const wx_scene *scene, map_set *set, int width, int height, int count,
                          int layers, wx_error *err)
{
    static const char *const rgb[3] = { "R", "G", "B" };
    // The names (2 x 20 KiB): not on the stack.
    char (*dirt_names)[WX_NAME_MAX] = malloc(2 * WX_IMAGE_MAX_CHANNELS * sizeof *dirt_names);
    if (dirt_names == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
    }
    char (*names)[WX_NAME_MAX] = dirt_names + WX_IMAGE_MAX_CHANNELS;
    const char *base[WX_IMAGE_MAX_CHANNELS];
    const char *layered[WX_IMAGE_MAX_CHANNELS];
    int dirt_count = wx_dirt_channels(scene, false, dirt_names);
    wx_result r = WX_OK;
    set->count = count;
    for (int k = 0; k < count && r == WX_OK; ++k) {
        int per = k == 0 ? 1 : k < 3 ? 3 : dirt_count;
        for (int i = 0; i < per; ++i) {
            base[i] = k < 3 ? rgb[i] : dirt_names[i];
        }
        if (per * layers > WX_IMAGE_MAX_CHANNELS) {
            r = wx_fail(err, WX_CAUSE_BAD_SCENE,
                        "bake: %d layers of %d channels are more than an image holds (%d)",
                        layers, per, WX_IMAGE_MAX_CHANNELS);
            break;
        }
        for (int l = 0; l < layers && r == WX_OK; ++l) {
            for (int i = 0; i < per && r == WX_OK; ++i) {
                int at = l * per + i;
                if (!wx_layer_channel(names[at], l, base[i])) {
                    r = wx_fail(err, WX_CAUSE_BAD_SCENE,
                                "bake: channel '%s' of layer %d has too long a name", base[i], l);
                }
                layered[at] = names[at];
            }
        }
        if (r != WX_OK) {
            break;
        }
        wx_image *img = &set->maps[k];
        bool same = img->width == width && img->height == height &&
                    img->channel_count == per * layers;
        for (int i = 0; same && i < per * layers; ++i) {
            same = strcmp(img->channel_names[i], layered[i]) == 0;
        }
        if (same) {
            continue; // every plane read back or filled is overwritten; impact B stays 0
        }
        wx_image_free(img);
        r = wx_image_alloc(img, width, height, per * layers, layered, err);
    }
    free(dirt_names);
    return r;
}

// Index of the channel called `name` in `image`, or -1.
static int channel_index(const wx_image *image, const char *name)
{
    for (int c = 0; c < image->channel_count; ++c) {
        if (strcmp(image->channel_names[c], name) == 0) {
            return c;
        }
    }
    return -1;
}

// The substances the renderer does not carry, from each texel's <Surface>
// (surface index + 1 in `surface`): their initial density (turned into amounts
// with the rendered one), deposit and erosion, into one layer's dirt planes
// (substance s at 3s, 3s+1, 3s+2).
static wx_result fill_substances(const wx_scene *scene, const float *surface,
                                 float *const *dirt, size_t texels, wx_error *err)
{
    const wx_surface **by_index = wx_scene_surfaces_by_index(scene);
    if (by_index == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory (surfaces)");
    }
    const int known = wx_scene_surface_count(scene);
    int rendered = rendered_substance(scene);
    for (int s = 0; s < scene->substance_count; ++s) {
        if (s == rendered) {
            continue;
        }
        float *amount = dirt[3 * s], *deposit = dirt[3 * s + 1], *erosion = dirt[3 * s + 2];
        for (size_t t = 0; t < texels; ++t) {
            int id = (int)surface[t] - 1;
            const wx_surface *sf = id >= 0 && id < known ? by_index[id] : NULL;
            amount[t] = sf != NULL ? sf->initial[s] : 0.0f;
            deposit[t] = sf != NULL ? sf->deposit[s] : 0.0f;
            erosion[t] = sf != NULL ? sf->erosion[s] : 0.0f;
        }
    }
    free(by_index);
    return WX_OK;
}

// ---------------------------------------------------------------------------
// One camera.

// Whether a depth plane just read back holds some surface (a finite d): when
// layer k holds none, no layer after it does, and they are not drawn.
static bool any_surface(const float *depth, size_t texels)
{
    for (size_t t = 0; t < texels; ++t) {
        if (depth[t] < INFINITY) {
            return true;
        }
    }
    return false;
}

// Renders camera c and keeps only its depth planes and, layered, its outward
// normals (for the visibility test).
static wx_result render_depth_only(baker *b, int c, wx_error *err)
{
    const wx_scene_camera *sc = &b->scene->cameras[c];
    cam_state *cs = &b->cams[c];
    int layers = bake_cam_layers(sc);
    size_t n = (size_t)sc->camera.width * (size_t)sc->camera.height;
    cs->depth = wx_big_malloc(n * (size_t)layers * sizeof(float));
    if (cs->depth == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
    }
    if (layers > 1) {
        cs->normal = wx_big_malloc(3 * n * (size_t)layers * sizeof(float));
        if (cs->normal == NULL) {
            return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
        }
    }
    cs->layers = layers;
    cs->depth_width = sc->camera.width;
    cs->depth_height = sc->camera.height;
    double t0 = wx_now_s();
    wx_result r = WX_OK;
    if (layers > 1) {
        // Peeled as bake_camera peels it, contacts dropped (bake_peel_camera).
        plane_out dst[WX_MAX_LAYERS][PASS_PLANES];
        for (int l = 0; l < layers; ++l) {
            float *normal = cs->normal + 3 * (size_t)l * n;
            dst[l][PASS_D] = (plane_out){ cs->depth + (size_t)l * n, 1 };
            for (int q = 0; q < 3; ++q) {
                dst[l][PASS_NX + q] = (plane_out){ normal + q, 3 };
            }
        }
        int drawn = 0;
        r = bake_peel_camera(b, c, layers, PASS_DEPTH_PLANES, dst, &drawn, err);
    } else {
        r = bake_draw_camera(b, c, 1, 0, err);
        if (r == WX_OK) {
            plane_out out[4] = { { cs->depth, 1 }, { NULL, 3 }, { NULL, 3 }, { NULL, 3 } };
            r = bake_read_target(b, TARGET_DEPTH_NORMAL, 4, out, err);
        }
    }
    b->stats->render_s += wx_now_s() - t0;
    return r;
}

// Layer `layer` of the set as the background: depth +inf, every other plane 0.
static void clear_layer(map_set *set, int layers, int layer, size_t texels)
{
    for (int k = 0; k < set->count; ++k) {
        wx_image *img = &set->maps[k];
        int per = img->channel_count / layers;
        for (int i = 0; i < per; ++i) {
            float *plane = img->channels[layer * per + i];
            if (k == 0) {
                for (size_t t = 0; t < texels; ++t) {
                    plane[t] = INFINITY;
                }
            } else {
                memset(plane, 0, texels * sizeof *plane);
            }
        }
    }
}

// The outward normals of the set's layers, interleaved (3 floats a texel, one
// layer after the other), as the ownership views of a layered camera read them.
static float *interleaved_normals(const wx_image *normal, int layers, size_t texels)
{
    float *out = wx_big_malloc(3 * texels * (size_t)layers * sizeof *out);
    for (int l = 0; out != NULL && l < layers; ++l) {
        float *dst = out + 3 * texels * (size_t)l;
        for (size_t t = 0; t < texels; ++t) {
            for (int q = 0; q < 3; ++q) {
                dst[3 * t + (size_t)q] = normal->channels[3 * l + q][t];
            }
        }
    }
    return out;
}

static wx_result bake_camera(baker *b, int c, wx_error *err)
{
    const wx_scene *scene = b->scene;
    const wx_scene_camera *sc = &scene->cameras[c];
    bool input = !sc->is_output;
    int layers = bake_cam_layers(sc);
    char label[sizeof sc->name + 8];
    snprintf(label, sizeof label, "bake %s", sc->name);
    wx_progress progress;
    wx_progress_begin(&progress, label, 2 * layers + 2, b->def->quiet);

    map_set *set = &b->set;
    size_t texels = (size_t)sc->camera.width * (size_t)sc->camera.height;
    wx_result r = size_set(scene, set, sc->camera.width, sc->camera.height, input ? 4 : 2,
                           layers, err);
    wx_image *maps = set->maps;
    // The dirt image's planes, per layer (`per` of them, layer l's from l*per):
    // the rendered substance's at 3g (3g+1, 3g+2), the surface record and
    // Grow's area when the scene's layout has them.
    int g = scene->substances_declared ? rendered_substance(scene) : 0;
    int S = scene->substances_declared ? scene->substance_count : 1;
    int per = r == WX_OK && input ? maps[3].channel_count / layers : 0;
    int surface_channel = r == WX_OK && input ? channel_index(&maps[3], WX_SURFACE_CHANNEL) : -1;
    int area_channel = r == WX_OK && input ? channel_index(&maps[3], WX_AREA_CHANNEL) : -1;
    // Every layer's surface record: the dirt map's own planes, or a scratch.
    float *scratch = NULL;
    float *surface[WX_MAX_LAYERS] = { NULL };
    if (r == WX_OK && input && (S > 1 || surface_channel >= 0)) {
        if (surface_channel < 0) {
            scratch = wx_big_malloc(texels * (size_t)layers * sizeof *scratch);
            if (scratch == NULL) {
                r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
            }
        }
        for (int l = 0; l < layers && r == WX_OK; ++l) {
            surface[l] = scratch != NULL ? scratch + (size_t)l * texels
                                         : maps[3].channels[l * per + surface_channel];
        }
    }
    double t0 = wx_now_s();
    int drawn = 0; // layers drawn; those after them hold no crossing
    if (r == WX_OK && layers > 1) {
        // Peeled, contacts dropped (bake_peel_camera): each layer's planes.
        plane_out dst[WX_MAX_LAYERS][PASS_PLANES];
        for (int l = 0; l < layers; ++l) {
            float *const *dirt = input ? &maps[3].channels[l * per] : NULL;
            dst[l][PASS_D] = (plane_out){ maps[0].channels[l], 1 };
            for (int q = 0; q < 3; ++q) {
                dst[l][PASS_NX + q] = (plane_out){ maps[1].channels[3 * l + q], 1 };
            }
            if (input) {
                dst[l][PASS_ABSORPTION] = (plane_out){ maps[2].channels[3 * l], 1 };
                dst[l][PASS_BOUNCE] = (plane_out){ maps[2].channels[3 * l + 1], 1 };
                dst[l][PASS_DEPOSIT] = (plane_out){ dirt[3 * g + 1], 1 };
                dst[l][PASS_EROSION] = (plane_out){ dirt[3 * g + 2], 1 };
                dst[l][PASS_DENSITY] = (plane_out){ dirt[3 * g], 1 };
                dst[l][PASS_SURFACE] = (plane_out){ surface[l], 1 };
            }
        }
        r = bake_peel_camera(b, c, layers, input ? PASS_PLANES : PASS_DEPTH_PLANES, dst, &drawn,
                             err);
        wx_progress_update(&progress, 2 * layers);
    }
    for (int l = 0; l < layers && r == WX_OK; ++l) {
        if (layers > 1) {
            if (l >= drawn) {
                clear_layer(set, layers, l, texels);
                if (scratch != NULL) {
                    memset(surface[l], 0, texels * sizeof *surface[l]);
                }
            }
            continue;
        }
        if (l > 0 && !any_surface(maps[0].channels[l - 1], texels)) {
            clear_layer(set, layers, l, texels);
            if (scratch != NULL) {
                memset(surface[l], 0, texels * sizeof *surface[l]);
            }
            continue;
        }
        r = bake_draw_camera(b, c, input ? TARGET_COUNT : 1, l, err);
        wx_progress_update(&progress, 2 * l + 1);
        if (r == WX_OK) {
            plane_out out[4] = { { maps[0].channels[l], 1 },
                                 { maps[1].channels[3 * l], 1 },
                                 { maps[1].channels[3 * l + 1], 1 },
                                 { maps[1].channels[3 * l + 2], 1 } };
            r = bake_read_target(b, TARGET_DEPTH_NORMAL, 4, out, err);
        }
        if (r == WX_OK && input) {
            float *const *dirt = &maps[3].channels[l * per];
            plane_out out[4] = { { maps[2].channels[3 * l], 1 },
                                 { maps[2].channels[3 * l + 1], 1 },
                                 { dirt[3 * g + 1], 1 },
                                 { dirt[3 * g + 2], 1 } };
            r = bake_read_target(b, TARGET_IMPACT_DIRT, 4, out, err);
            if (r == WX_OK && surface[l] == NULL) {
                plane_out density[1] = { { dirt[3 * g], 1 } };
                r = bake_read_target(b, TARGET_DENSITY, 1, density, err);
            } else if (r == WX_OK) {
                plane_out density[2] = { { dirt[3 * g], 1 }, { surface[l], 1 } };
                r = bake_read_target(b, TARGET_DENSITY, 2, density, err);
            }
        }
        if (r == WX_OK && l + 1 < layers) {
            r = bake_keep_previous_layer(b, err);
        }
        drawn = l + 1;
        wx_progress_update(&progress, 2 * l + 2);
    }
    double t1 = wx_now_s();
    b->stats->render_s += t1 - t0;
    if (r == WX_OK && input) {
        // Every (camera, layer) is a view of the ownership; a layer with no
        // crossing holds no dirt (its planes are already the background's).
        float *normal = layers > 1 ? interleaved_normals(&maps[1], layers, texels) : NULL;
        int count = 0, self = 0;
        wx_owner_view *views = layers == 1 || normal != NULL
                                   ? owner_views(b, c, maps[0].channels, normal, &count, &self)
                                   : NULL;
        if (views == NULL) {
            r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
        }
        for (int l = 0; l < drawn && r == WX_OK; ++l) {
            float *const *dirt = &maps[3].channels[l * per];
            if (S > 1) {
                r = fill_substances(scene, surface[l], dirt, texels, err);
            }
            float *planes[WX_MAX_SUBSTANCES];
            for (int s = 0; s < S; ++s) {
                planes[s] = dirt[3 * s];
            }
            if (r == WX_OK) {
                r = compute_initial_dirt(b, c, views, count, self + l, &maps[1].channels[3 * l],
                                         planes, S, area_channel >= 0 ? dirt[area_channel] : NULL,
                                         err);
            }
        }
        free(views);
        free(normal);
    }
    free(scratch);
    b->stats->dirt_s += wx_now_s() - t1;
    wx_progress_update(&progress, 2 * layers + 1);
    if (r == WX_OK) {
        double t2 = wx_now_s();
        r = b->def->on_maps(c, set->maps, set->count, b->def->user, err);
        b->stats->write_s += wx_now_s() - t2;
        b->stats->cameras += r == WX_OK;
    }
    wx_progress_end(&progress);
    return r;
}

// ---------------------------------------------------------------------------
// The scene.

static void baker_free(baker *b)
{
    for (int f = 0; f < 4; ++f) {
        wx_image_free(&b->set.maps[f]);
    }
    bake_release_gl(b);
    free(b->meshes);
    if (b->cams != NULL) {
        for (int c = 0; c < b->scene->camera_count; ++c) {
            free(b->cams[c].depth);
            free(b->cams[c].normal);
        }
    }
    free(b->cams);
    free(b->strip);
    free(b);
}

static wx_result check_cameras(baker *b, int *bake_count, wx_error *err)
{
    const wx_scene *scene = b->scene;
    *bake_count = 0;
    for (int c = 0; c < scene->camera_count; ++c) {
        const wx_scene_camera *sc = &scene->cameras[c];
        cam_state *cs = &b->cams[c];
        cs->bake = sc->has_view && !wx_has_path(sc->depth_path);
        cs->d_min = INFINITY;
        cs->d_max = -INFINITY;
        if (!cs->bake) {
            continue;
        }
        ++*bake_count;
        int w = sc->camera.width, h = sc->camera.height;
        if (w < 1 || h < 1) {
            return wx_fail(err, WX_CAUSE_BAD_SCENE, "%s:%d: camera '%s' has no map size",
                                scene->path, sc->line, sc->name);
        }
    }
    return WX_OK;
}

static wx_result check_sizes(baker *b, wx_error *err)
{
    const wx_scene *scene = b->scene;
    for (int c = 0; c < scene->camera_count; ++c) {
        const wx_scene_camera *sc = &scene->cameras[c];
        if (!b->cams[c].bake) {
            continue;
        }
        if (sc->camera.width > b->max_side || sc->camera.height > b->max_side) {
            return wx_fail(err, WX_CAUSE_MAP_SIZE,
                           "%s:%d: camera '%s' asks for %d x %d maps; the renderer bakes at "
                           "most %d x %d",
                           scene->path, sc->line, sc->name, sc->camera.width, sc->camera.height,
                           (int)b->max_side, (int)b->max_side);
        }
    }
    return WX_OK;
}

wx_bake_def wx_default_bake_def(void)
{
    wx_bake_def def;
    memset(&def, 0, sizeof def);
    def.threads = 1;
    def.quiet = true;
    return def;
}

wx_result wx_bake_render(const wx_bake_def *def, wx_bake_stats *stats, wx_error *err)
{
    const wx_scene *scene = def->scene;
    wx_geometry *geometry = def->geometry;
    wx_bake_stats local;
    if (stats == NULL) {
        stats = &local;
    }
    memset(stats, 0, sizeof *stats);
    double start = wx_now_s();
    baker *b = calloc(1, sizeof *b); // large (image sets): not on the stack
    if (b == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
    }
    b->scene = scene;
    b->def = def;
    b->stats = stats;
    b->cams = calloc(scene->camera_count > 0 ? (size_t)scene->camera_count : 1, sizeof *b->cams);
    if (b->cams == NULL) {
        baker_free(b);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
    }
    int bake_count = 0;
    wx_result r = check_cameras(b, &bake_count, err);
    if (r != WX_OK || bake_count == 0) {
        baker_free(b);
        return r;
    }
    if (geometry == NULL || geometry->count != scene->mesh_count || scene->mesh_count == 0) {
        baker_free(b); // wx_geometry_load refuses a scene without meshes to bake from
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "bake: the scene's meshes were not imported");
    }
    double t0 = wx_now_s();
    r = bake_create_context(b, err);
    if (r == WX_OK) {
        r = check_sizes(b, err);
    }
    stats->setup_s += wx_now_s() - t0;
    if (r == WX_OK) {
        r = load_meshes(b, geometry, err);
    }

    // Initial dirt needs every input camera's depth before any dirt map is final.
    int input_cameras = 0;
    for (int c = 0; c < scene->camera_count; ++c) {
        input_cameras += !scene->cameras[c].is_output;
    }
    bool visibility = (b->has_dirt || wx_scene_has_grow(scene)) && input_cameras > 1;
    double cameras_start = wx_now_s();
    for (int c = 0; c < scene->camera_count && r == WX_OK && visibility; ++c) {
        if (scene->cameras[c].is_output) {
            continue;
        }
        r = b->cams[c].bake ? render_depth_only(b, c, err) : take_given_depth(b, c, err);
    }
    for (int c = 0; c < scene->camera_count && r == WX_OK; ++c) {
        if (b->cams[c].bake) {
            r = bake_camera(b, c, err);
        }
    }
    stats->cameras_s = wx_now_s() - cameras_start;
    baker_free(b);
    stats->total_s = wx_now_s() - start;
    return r;
}

