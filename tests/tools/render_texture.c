// render_texture.c: renders a TextureMap (docs/design.md section 11) back onto
// its mesh through an orthographic camera, on the CPU, so that a texture can be
// looked at from any angle and compared with the mask the program writes
// through the same camera.
//
// Each triangle is projected with wx_camera_world_to_map and rasterised into
// the camera's pixel grid (pixel (i, j) centred at wx_map_texel_center, as the
// masks are): a pixel is covered when its centre lies inside the projected
// triangle (edge functions in double; an edge shared by two triangles belongs
// to exactly one), the smallest depth d > 0 wins (d grows away from the eye).
// At a covered pixel the UV is interpolated (affine is exact for an
// orthographic projection) and the texture's channel and its `seen` are
// sampled bilinearly in texel space (x = u*W - 0.5, y = (1-v)*H - 0.5, clamped
// at the borders; a UV outside [0,1] first taken modulo 1, as the default
// tiles="repeat" writes it). A TEXTURE path with the token <UDIM>
// (city_texture.<UDIM>.exr, as Blender names UDIM sets) reads every tile
// 1001 ... 1999 that exists: a UV in [k, k+1) x [m, m+1) samples tile
// 1001 + k + 10 m (all tiles of one size; a UV in a missing tile is unseen).
// The mesh is taken as the file gives it (scenes place meshes as they are).
//
//   make build/tools/render_texture
//   build/tools/render_texture MESH TEXTURE.exr [--channel NAME] [--uv N]
//       --view "ex ey ez tx ty tz ux uy uz width height resolution"
//       [--png OUT.png] [--white X] [--exr OUT.exr] [--seen-exr OUT.exr]
//
// `resolution` is N (square) or WxH. --channel reads NAME, else NAME.Y (default
// Y). Outputs:
//   --exr       float EXR of the view's size: `Y` the sampled value, `seen` the
//               sampled seen, `surface` 1 where the pixel shows the mesh (all 0
//               elsewhere), with the camera's WTCMatrix and CTWMatrix; one
//               sample per pixel, at its centre.
//   --seen-exr  the same with `Y` holding the sampled seen (to view or compare
//               the known part as a mask).
//   --png       a picture for people, supersampled 2 x 2: the mesh lit by a
//               headlight (0.25 + 0.75 |N.view|), clay (0.80 0.78 0.72) blending
//               to dirt (0.25 0.20 0.15) by t = min(1, value / white), grey-blue
//               (0.55 0.60 0.70) where seen < 0.5, on a dark grey background.
//               white is --white, else the larger of 1 and the 99th percentile
//               of the channel's positive values over the texels with seen > 0
//               (as the previews: wx_preview_white); it prints `white X`.
// Exit status 2 on bad arguments or unreadable files, 1 on other failures.
#define _XOPEN_SOURCE 700 // access
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/error.h"
#include "io/exr.h"
#include "io/mesh_import.h"
#include "io/png_preview.h"
#include "model/camera.h"
#include "model/image.h"
#include "model/mesh.h"

/// Pixels per side of the PNG's supersampling.
#define SUPERSAMPLE 2

static const float CLAY[3] = { 0.80f, 0.78f, 0.72f };
static const float DIRT[3] = { 0.25f, 0.20f, 0.15f };
static const float UNKNOWN[3] = { 0.55f, 0.60f, 0.70f };
static const float BACKGROUND[3] = { 0.15f, 0.15f, 0.15f };
static const float AMBIENT = 0.25f;

typedef struct options {
    const char *mesh_path;
    const char *texture_path;
    const char *channel;
    int uv;
    wx_view view;
    bool has_view;
    const char *png_path;
    const char *exr_path;
    const char *seen_exr_path;
    float white; ///< 0: the 99th percentile
} options;

// ---------------------------------------------------------------------------
// The command line.

static int usage(const char *fmt, const char *detail)
{
    fprintf(stderr, "render_texture: ");
    fprintf(stderr, fmt, detail);
    fprintf(stderr, "\nusage: render_texture MESH TEXTURE.exr [--channel NAME] [--uv N]\n"
                    "         --view \"ex ey ez tx ty tz ux uy uz width height resolution\"\n"
                    "         [--png OUT.png] [--white X] [--exr OUT.exr] [--seen-exr OUT.exr]\n");
    return WX_BAD_INPUT;
}

// "N" or "WxH".
static bool parse_resolution(const char *text, int *width, int *height)
{
    char *end;
    long w = strtol(text, &end, 10), h = w;
    if (end != text && (*end == 'x' || *end == 'X')) {
        const char *rest = end + 1;
        h = strtol(rest, &end, 10);
        if (end == rest) {
            return false;
        }
    }
    if (end == text || *end != '\0' || w < 1 || h < 1 || w > INT32_MAX || h > INT32_MAX) {
        return false;
    }
    *width = (int)w;
    *height = (int)h;
    return true;
}

// Eleven numbers and a resolution: eye, target, up, width, height, pixels.
static bool parse_view(const char *text, wx_view *view)
{
    float v[11];
    const char *s = text;
    for (int k = 0; k < 11; ++k) {
        char *end;
        v[k] = strtof(s, &end);
        if (end == s || !isfinite(v[k])) {
            return false;
        }
        s = end;
    }
    while (*s == ' ' || *s == '\t') {
        s++;
    }
    char resolution[64];
    size_t len = strcspn(s, " \t");
    if (len == 0 || len >= sizeof resolution || s[len + strspn(s + len, " \t")] != '\0') {
        return false;
    }
    memcpy(resolution, s, len);
    resolution[len] = '\0';
    memset(view, 0, sizeof *view);
    memcpy(view->eye, &v[0], sizeof view->eye);
    memcpy(view->target, &v[3], sizeof view->target);
    memcpy(view->up, &v[6], sizeof view->up);
    view->width_ws = v[9];
    view->height_ws = v[10];
    return parse_resolution(resolution, &view->width_px, &view->height_px);
}

// Returns -1 when the options are good, else the exit status.
static int parse_args(int argc, char **argv, options *o)
{
    memset(o, 0, sizeof *o);
    o->channel = "Y";
    int positional = 0;
    for (int i = 1; i < argc; ++i) {
        const char *arg = argv[i];
        if (arg[0] != '-' || arg[1] == '\0') {
            if (positional == 2) {
                return usage("unexpected argument '%s'", arg);
            }
            *(positional++ == 0 ? &o->mesh_path : &o->texture_path) = arg;
            continue;
        }
        if (i + 1 >= argc) {
            return usage("%s needs a value", arg);
        }
        const char *value = argv[++i];
        char *end;
        if (strcmp(arg, "--channel") == 0) {
            o->channel = value;
        } else if (strcmp(arg, "--uv") == 0) {
            long uv = strtol(value, &end, 10);
            if (end == value || *end != '\0' || uv < 0 || uv >= WX_MESH_MAX_UV_CHANNELS) {
                return usage("--uv '%s' is not a UV channel (0 to 7)", value);
            }
            o->uv = (int)uv;
        } else if (strcmp(arg, "--view") == 0) {
            if (!parse_view(value, &o->view)) {
                return usage("--view '%s' is not \"ex ey ez tx ty tz ux uy uz width height "
                             "resolution\" (resolution N or WxH)", value);
            }
            o->has_view = true;
        } else if (strcmp(arg, "--white") == 0) {
            o->white = strtof(value, &end);
            if (end == value || *end != '\0' || !(o->white > 0.0f) || !isfinite(o->white)) {
                return usage("--white '%s' is not a positive number", value);
            }
        } else if (strcmp(arg, "--png") == 0) {
            o->png_path = value;
        } else if (strcmp(arg, "--exr") == 0) {
            o->exr_path = value;
        } else if (strcmp(arg, "--seen-exr") == 0) {
            o->seen_exr_path = value;
        } else {
            return usage("unknown option '%s'", arg);
        }
    }
    if (positional < 2) {
        return usage("%s", "needs a mesh and a texture");
    }
    if (!o->has_view) {
        return usage("%s", "needs --view");
    }
    if (o->png_path == NULL && o->exr_path == NULL && o->seen_exr_path == NULL) {
        return usage("%s", "nothing to write: give --png, --exr or --seen-exr");
    }
    return -1;
}

// ---------------------------------------------------------------------------
// The texture.

enum { UDIM_TILES = 999 };

typedef struct texture {
    int width, height;
    const float *value;
    const float *seen;
    int tiles; ///< 0, or UDIM_TILES: tile[k] is UDIM tile 1001 + k (NULL: missing)
    const float *tile_value[UDIM_TILES], *tile_seen[UDIM_TILES];
} texture;

// Bilinear in texel space, centres at integers, clamped at the borders; UVs
// outside [0,1] wrap (REPEAT, docs/texture.md), those inside are read as they are.
static float sample(const texture *tex, bool seen, double u, double v)
{
    const float *plane = seen ? tex->seen : tex->value;
    if (tex->tiles > 0) {
        double k = floor(u), m = floor(v);
        int tile = k >= 0.0 && k < 10.0 && m >= 0.0 && m < 100.0 ? (int)k + 10 * (int)m : -1;
        if (tile < 0 || tile >= tex->tiles || tex->tile_value[tile] == NULL) {
            return 0.0f;
        }
        plane = seen ? tex->tile_seen[tile] : tex->tile_value[tile];
        u -= k;
        v -= m;
    }
    u = u < 0.0 || u > 1.0 ? u - floor(u) : u;
    v = v < 0.0 || v > 1.0 ? v - floor(v) : v;
    double x = u * tex->width - 0.5, y = (1.0 - v) * tex->height - 0.5;
    x = fmin(fmax(x, 0.0), tex->width - 1.0);
    y = fmin(fmax(y, 0.0), tex->height - 1.0);
    int i0 = (int)x, j0 = (int)y;
    int i1 = i0 + 1 < tex->width ? i0 + 1 : i0, j1 = j0 + 1 < tex->height ? j0 + 1 : j0;
    double fx = x - i0, fy = y - j0;
    size_t w = (size_t)tex->width;
    double top = (1.0 - fx) * plane[(size_t)j0 * w + i0] + fx * plane[(size_t)j0 * w + i1];
    double bottom = (1.0 - fx) * plane[(size_t)j1 * w + i0] + fx * plane[(size_t)j1 * w + i1];
    return (float)((1.0 - fy) * top + fy * bottom);
}

// The PNG's white point, as the previews': the larger of 1 and the 99th
// percentile of the positive values seen.
static wx_result white_point(const texture *tex, float *white, wx_error *err)
{
    size_t texels = (size_t)tex->width * (size_t)tex->height, n = 0;
    int planes = tex->tiles > 0 ? tex->tiles : 1;
    float *values = malloc((texels > 0 ? texels : 1) * (size_t)planes * sizeof *values);
    if (values == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (white point)");
    }
    for (int k = 0; k < planes; ++k) {
        const float *value = tex->tiles > 0 ? tex->tile_value[k] : tex->value;
        const float *seen = tex->tiles > 0 ? tex->tile_seen[k] : tex->seen;
        for (size_t t = 0; value != NULL && t < texels; ++t) {
            if (seen[t] > 0.0f) {
                values[n++] = value[t];
            }
        }
    }
    wx_result r = wx_preview_scale(values, n, white, err);
    free(values);
    *white = wx_preview_white(*white); // 1 when nothing is positive: all clay
    return r;
}

// ---------------------------------------------------------------------------
// The raster: per pixel the nearest triangle and its barycentric weights.

typedef struct point2 {
    double x, y;
} point2;

typedef struct raster {
    int width, height;
    float *depth;      ///< per pixel: the nearest d, +inf where none
    int32_t *triangle; ///< per pixel: the triangle shown, -1 where none
    float *weight;     ///< 2 per pixel: weights of the triangle's 2nd and 3rd vertices
} raster;

static void raster_free(raster *r)
{
    free(r->depth);
    free(r->triangle);
    free(r->weight);
    memset(r, 0, sizeof *r);
}

// Twice the signed area of (a, b, p), computed from the lexicographically
// smaller end of the edge so that edge(a, b, p) == -edge(b, a, p) exactly (as
// gather/texture.c): a centre on a shared edge is inside exactly one triangle.
static double edge(point2 a, point2 b, point2 p)
{
    bool swap = b.x < a.x || (b.x == a.x && b.y < a.y);
    if (swap) {
        point2 t = a;
        a = b;
        b = t;
    }
    double e = (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
    return swap ? -e : e;
}

// Of the two directions of an edge of positively oriented triangles, exactly
// one owns the centres on it.
static bool inside(double e, point2 a, point2 b)
{
    double dx = b.x - a.x, dy = b.y - a.y;
    return e > 0.0 || (e == 0.0 && (dy > 0.0 || (dy == 0.0 && dx < 0.0)));
}

// Map coordinates (u, v, d) of every vertex.
static float *project_vertices(const wx_mesh_data *mesh, const wx_camera *cam)
{
    float *uvd = malloc((size_t)(mesh->vertex_count > 0 ? mesh->vertex_count : 1) * 3 *
                        sizeof *uvd);
    for (int64_t k = 0; uvd != NULL && k < mesh->vertex_count; ++k) {
        float p[3];
        for (int c = 0; c < 3; ++c) {
            p[c] = (float)((double)mesh->positions[3 * k + c] + mesh->origin[c]);
        }
        wx_camera_world_to_map(cam, p, &uvd[3 * k]);
    }
    return uvd;
}

// A pixel column or row clamped to [0, n - 1].
static int pixel_index(double x, int n)
{
    return (int)fmin(fmax(x, 0.0), n - 1.0);
}

static void raster_triangle(const wx_mesh_data *mesh, const float *uvd, int32_t tri,
                            const wx_camera *cam, raster *r)
{
    const uint32_t *idx = &mesh->indices[3 * (size_t)tri];
    point2 p[3];
    double d[3];
    int order[3] = { 0, 1, 2 };
    for (int k = 0; k < 3; ++k) {
        const float *m = &uvd[3 * (size_t)idx[k]];
        p[k] = (point2){ m[0], m[1] };
        d[k] = m[2];
    }
    double area = edge(p[0], p[1], p[2]);
    if (!(area != 0.0) || !isfinite(area) || !isfinite(d[0] + d[1] + d[2])) {
        return;
    }
    if (area < 0.0) { // orient positively, remembering which vertex went where
        point2 t = p[1];
        p[1] = p[2];
        p[2] = t;
        double dt = d[1]; // the depths go with their vertices
        d[1] = d[2];
        d[2] = dt;
        order[1] = 2;
        order[2] = 1;
        area = -area;
    }
    const int W = cam->width, H = cam->height;
    double u0 = fmin(p[0].x, fmin(p[1].x, p[2].x)), u1 = fmax(p[0].x, fmax(p[1].x, p[2].x));
    double v0 = fmin(p[0].y, fmin(p[1].y, p[2].y)), v1 = fmax(p[0].y, fmax(p[1].y, p[2].y));
    // A pixel of margin: the edge test against wx_map_texel_center decides.
    int i0 = pixel_index(floor(u0 * W - 0.5), W), i1 = pixel_index(ceil(u1 * W - 0.5), W);
    int j0 = pixel_index(floor((1.0 - v1) * H - 0.5), H);
    int j1 = pixel_index(ceil((1.0 - v0) * H - 0.5), H);
    for (int j = j0; j <= j1; ++j) {
        for (int i = i0; i <= i1; ++i) {
            float cu, cv;
            wx_map_texel_center(W, H, i, j, &cu, &cv);
            point2 c = { cu, cv };
            double e[3] = { edge(p[1], p[2], c), edge(p[2], p[0], c), edge(p[0], p[1], c) };
            if (!inside(e[0], p[1], p[2]) || !inside(e[1], p[2], p[0]) ||
                !inside(e[2], p[0], p[1])) {
                continue;
            }
            double b[3] = { e[0] / area, e[1] / area, e[2] / area }; // weights of p[k]
            float depth = (float)(b[0] * d[0] + b[1] * d[1] + b[2] * d[2]);
            size_t t = (size_t)j * (size_t)W + (size_t)i;
            if (!(depth > 0.0f) || !(depth < r->depth[t])) {
                continue; // behind the eye, or behind what the pixel shows
            }
            double w[3];
            for (int k = 0; k < 3; ++k) {
                w[order[k]] = b[k];
            }
            r->depth[t] = depth;
            r->triangle[t] = tri;
            r->weight[2 * t] = (float)w[1];
            r->weight[2 * t + 1] = (float)w[2];
        }
    }
}

static wx_result raster_build(const wx_mesh_data *mesh, const wx_camera *cam, raster *r,
                              wx_error *err)
{
    memset(r, 0, sizeof *r);
    size_t pixels = (size_t)cam->width * (size_t)cam->height;
    r->width = cam->width;
    r->height = cam->height;
    r->depth = malloc(pixels * sizeof *r->depth);
    r->triangle = malloc(pixels * sizeof *r->triangle);
    r->weight = malloc(2 * pixels * sizeof *r->weight);
    float *uvd = project_vertices(mesh, cam);
    if (r->depth == NULL || r->triangle == NULL || r->weight == NULL || uvd == NULL) {
        free(uvd);
        raster_free(r);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (%d x %d raster)",
                       cam->width, cam->height);
    }
    for (size_t t = 0; t < pixels; ++t) {
        r->depth[t] = INFINITY;
        r->triangle[t] = -1;
    }
    for (int64_t tri = 0; tri < mesh->triangle_count && tri <= INT32_MAX; ++tri) {
        raster_triangle(mesh, uvd, (int32_t)tri, cam, r);
    }
    free(uvd);
    return WX_OK;
}

// ---------------------------------------------------------------------------
// What a covered pixel shows.

typedef struct surface_sample {
    float value, seen;
    float normal[3]; ///< unit (the triangle's own normal where the vertices' cancel)
} surface_sample;

static void face_normal(const wx_mesh_data *mesh, const uint32_t *idx, float n[3])
{
    const float *a = &mesh->positions[3 * (size_t)idx[0]];
    const float *b = &mesh->positions[3 * (size_t)idx[1]];
    const float *c = &mesh->positions[3 * (size_t)idx[2]];
    float e1[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
    float e2[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
}

static surface_sample sample_pixel(const wx_mesh_data *mesh, int uv, const texture *tex,
                                   const raster *r, size_t t)
{
    const uint32_t *idx = &mesh->indices[3 * (size_t)r->triangle[t]];
    double w[3] = { 0.0, r->weight[2 * t], r->weight[2 * t + 1] };
    w[0] = 1.0 - w[1] - w[2];
    double tu = 0.0, tv = 0.0, n[3] = { 0.0, 0.0, 0.0 };
    for (int k = 0; k < 3; ++k) {
        const float *st = &mesh->uvs[uv][2 * (size_t)idx[k]];
        tu += w[k] * st[0];
        tv += w[k] * st[1];
        for (int c = 0; c < 3; ++c) {
            n[c] += w[k] * mesh->normals[3 * (size_t)idx[k] + c];
        }
    }
    surface_sample s = { sample(tex, false, tu, tv),
                         sample(tex, true, tu, tv),
                         { 0.0f, 0.0f, 0.0f } };
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 1e-12)) {
        float f[3];
        face_normal(mesh, idx, f);
        for (int c = 0; c < 3; ++c) {
            n[c] = f[c];
        }
        len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
    for (int c = 0; c < 3 && len > 0.0; ++c) {
        s.normal[c] = (float)(n[c] / len);
    }
    return s;
}

// ---------------------------------------------------------------------------
// The outputs.

// `first` is the sampled value (or seen, for --seen-exr) in channel Y.
static wx_result write_exr(const char *path, const wx_mesh_data *mesh, int uv,
                           const texture *tex, const raster *r, const wx_camera *cam,
                           bool seen_as_y, wx_error *err)
{
    static const char *const names[3] = { "Y", "seen", "surface" };
    wx_image image;
    wx_result res = wx_image_alloc(&image, r->width, r->height, 3, names, err);
    if (res != WX_OK) {
        wx_error_prefix(err, "%s", path);
        return res;
    }
    size_t pixels = (size_t)r->width * (size_t)r->height;
    for (size_t t = 0; t < pixels; ++t) {
        if (r->triangle[t] >= 0) {
            surface_sample s = sample_pixel(mesh, uv, tex, r, t);
            image.channels[0][t] = seen_as_y ? s.seen : s.value;
            image.channels[1][t] = s.seen;
            image.channels[2][t] = 1.0f;
        }
    }
    wx_image_set_m44f(&image, "WTCMatrix", cam->wtc);
    wx_image_set_m44f(&image, "CTWMatrix", cam->ctw);
    res = wx_exr_write(path, &image, err);
    wx_image_free(&image);
    return res;
}

static void shade(const surface_sample *s, const float view_dir[3], float white, float rgb[3])
{
    float lambert = fabsf(s->normal[0] * view_dir[0] + s->normal[1] * view_dir[1] +
                          s->normal[2] * view_dir[2]);
    float light = AMBIENT + (1.0f - AMBIENT) * lambert;
    float t = isfinite(s->value) ? fminf(1.0f, fmaxf(0.0f, s->value / white)) : 0.0f;
    for (int c = 0; c < 3; ++c) {
        float albedo = s->seen < 0.5f ? UNKNOWN[c] : CLAY[c] + t * (DIRT[c] - CLAY[c]);
        rgb[c] = albedo * light;
    }
}

// The picture: rasterised at SUPERSAMPLE times the view's resolution, each
// pixel the mean of its sub-pixels (whose centres are those of the finer grid).
static wx_result write_png(const char *path, const wx_mesh_data *mesh, int uv,
                           const texture *tex, const wx_view *view, float white, wx_error *err)
{
    wx_view fine_view = *view;
    fine_view.width_px *= SUPERSAMPLE;
    fine_view.height_px *= SUPERSAMPLE;
    wx_camera fine;
    raster r;
    wx_result res = wx_camera_from_view(&fine_view, &fine, err);
    if (res != WX_OK || (res = raster_build(mesh, &fine, &r, err)) != WX_OK) {
        return res;
    }
    const int W = view->width_px, H = view->height_px;
    uint8_t *pixels = malloc((size_t)W * (size_t)H * 3);
    if (pixels == NULL) {
        raster_free(&r);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (%d x %d picture)", W, H);
    }
    float view_dir[3];
    wx_camera_view_dir(&fine, view_dir);
    for (int j = 0; j < H; ++j) {
        for (int i = 0; i < W; ++i) {
            float sum[3] = { 0.0f, 0.0f, 0.0f };
            for (int sj = 0; sj < SUPERSAMPLE; ++sj) {
                for (int si = 0; si < SUPERSAMPLE; ++si) {
                    size_t t = (size_t)(j * SUPERSAMPLE + sj) * (size_t)r.width +
                               (size_t)(i * SUPERSAMPLE + si);
                    float rgb[3] = { BACKGROUND[0], BACKGROUND[1], BACKGROUND[2] };
                    if (r.triangle[t] >= 0) {
                        surface_sample s = sample_pixel(mesh, uv, tex, &r, t);
                        shade(&s, view_dir, white, rgb);
                    }
                    for (int c = 0; c < 3; ++c) {
                        sum[c] += rgb[c] / (SUPERSAMPLE * SUPERSAMPLE);
                    }
                }
            }
            for (int c = 0; c < 3; ++c) {
                float byte = fminf(255.0f, fmaxf(0.0f, sum[c] * 255.0f + 0.5f));
                pixels[((size_t)j * (size_t)W + (size_t)i) * 3 + (size_t)c] = (uint8_t)byte;
            }
        }
    }
    raster_free(&r);
    res = wx_png_write(path, pixels, W, H, 3, err);
    free(pixels);
    return res;
}

// ---------------------------------------------------------------------------

// image: one image, or UDIM_TILES for a <UDIM> path (tile k in image[k]).
static wx_result load(const options *o, wx_mesh_data *mesh, wx_image *image, texture *tex,
                      wx_error *err)
{
    wx_result r = wx_mesh_import_uvs(o->mesh_path, 1u << o->uv, mesh, err);
    if (r != WX_OK) {
        return r;
    }
    char wanted_value[2 * WX_NAME_MAX + 4];
    snprintf(wanted_value, sizeof wanted_value, "%s|%s.Y", o->channel, o->channel);
    const char *const wanted[2] = { wanted_value, "seen" };
    memset(tex, 0, sizeof *tex);
    const char *token = strstr(o->texture_path, "<UDIM>");
    if (token == NULL) {
        r = wx_exr_read(o->texture_path, wanted, 2, image, err);
        if (r == WX_OK) {
            tex->width = image->width;
            tex->height = image->height;
            tex->value = image->channels[0];
            tex->seen = image->channels[1];
        }
        return r;
    }
    int found = 0;
    for (int k = 0; k < UDIM_TILES && r == WX_OK; ++k) {
        char path[4096];
        snprintf(path, sizeof path, "%.*s%d%s", (int)(token - o->texture_path), o->texture_path,
                 1001 + k, token + 6);
        if (access(path, R_OK) != 0) {
            continue;
        }
        r = wx_exr_read(path, wanted, 2, &image[k], err);
        if (r == WX_OK && found > 0 &&
            (image[k].width != tex->width || image[k].height != tex->height)) {
            r = wx_fail(err, WX_CAUSE_MAP_SIZE, "%s: %d x %d, the other tiles %d x %d", path,
                        image[k].width, image[k].height, tex->width, tex->height);
        }
        if (r == WX_OK) {
            tex->width = image[k].width;
            tex->height = image[k].height;
            tex->tile_value[k] = image[k].channels[0];
            tex->tile_seen[k] = image[k].channels[1];
            ++found;
        }
    }
    tex->tiles = UDIM_TILES;
    if (r == WX_OK && found == 0) {
        r = wx_fail(err, WX_CAUSE_FILE_MISSING, "%s: no UDIM tile 1001 ... 1999 exists",
                    o->texture_path);
    }
    return r;
}

static wx_result render(const options *o, const wx_mesh_data *mesh, const texture *tex,
                        wx_error *err)
{
    wx_camera cam;
    raster r;
    wx_result res = wx_camera_from_view(&o->view, &cam, err);
    if (res != WX_OK || (res = raster_build(mesh, &cam, &r, err)) != WX_OK) {
        return res;
    }
    if (o->exr_path != NULL) {
        res = write_exr(o->exr_path, mesh, o->uv, tex, &r, &cam, false, err);
    }
    if (res == WX_OK && o->seen_exr_path != NULL) {
        res = write_exr(o->seen_exr_path, mesh, o->uv, tex, &r, &cam, true, err);
    }
    raster_free(&r);
    if (res == WX_OK && o->png_path != NULL) {
        float white = o->white;
        if (!(white > 0.0f)) {
            res = white_point(tex, &white, err);
        }
        if (res == WX_OK) {
            res = write_png(o->png_path, mesh, o->uv, tex, &o->view, white, err);
        }
        if (res == WX_OK) {
            printf("white %g\n", white); // for pictures drawn to the same scale
        }
    }
    return res;
}

int main(int argc, char **argv)
{
    options o;
    int status = parse_args(argc, argv, &o);
    if (status >= 0) {
        return status;
    }
    wx_error err = { 0 };
    wx_mesh_data mesh = { 0 };
    wx_image *images = calloc(UDIM_TILES, sizeof *images);
    texture *tex = malloc(sizeof *tex);
    wx_result r = images != NULL && tex != NULL
                      ? load(&o, &mesh, images, tex, &err)
                      : wx_fail(&err, WX_CAUSE_OUT_OF_MEMORY, "out of memory");
    if (r == WX_OK) {
        r = render(&o, &mesh, tex, &err);
    }
    if (r != WX_OK) {
        fprintf(stderr, "render_texture: %s\n", err.message);
    }
    for (int k = 0; images != NULL && k < UDIM_TILES; ++k) {
        wx_image_free(&images[k]);
    }
    free(images);
    free(tex);
    wx_mesh_data_free(&mesh);
    return (int)r;
}
