// test_bake.c: OSMesa bake of depth, normal, impact and dirt maps (src/raster/bake.c).
//
// Scenes are built by hand (wx_scene structs) so that every expected number can
// be worked out from the geometry: a unit sphere, a box, flat quads. One test
// goes through a scene file and the scene's own map reader.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "raster/bake.h"
#include "model/camera.h"
#include "ensure.h"
#include "io/exr.h"
#include "model/maps.h"
#include "model/scene.h"
#include "core/limits.h"
#include "io/maps_file.h"
#include "io/scene_xml.h"
#include "model/image.h"
#include "pipeline/bake_phase.h"
#include "pipeline/outputs.h"
#include "pipeline/pipeline.h"

// ---------------------------------------------------------------------------
// Scenes by hand.

static const char *data_path(const char *name)
{
    static char paths[4][4096];
    static int next;
    char *p = paths[next];
    next = (next + 1) % 4;
    snprintf(p, 4096, "%s/data/%s", ensure_tests_dir(), name);
    return p;
}

static void scene_begin(wx_scene *s)
{
    memset(s, 0, sizeof *s);
    wx_scene_set_path(&s->path, "scene.xml");
    wx_scene_set_path(&s->dir, ".");
    snprintf(s->name, sizeof s->name, "scene");
    s->output_index = -1;
    s->substance_count = 1; // version 1's one substance, as the scene loader sets it
    snprintf(s->substances[0], sizeof s->substances[0], "dirt");
    s->iterations = 1;
}

static wx_scene_camera *add_camera(wx_scene *s, const char *name, const float eye[3],
                                   const float target[3], const float up[3], float width_ws,
                                   float height_ws, int width_px, int height_px, bool output)
{
    s->cameras = realloc(s->cameras, (size_t)(s->camera_count + 1) * sizeof *s->cameras);
    wx_scene_camera *c = &s->cameras[s->camera_count++];
    memset(c, 0, sizeof *c);
    snprintf(c->name, sizeof c->name, "%s", name);
    c->is_output = output;
    c->has_view = true;
    for (int i = 0; i < 3; ++i) {
        c->view.eye[i] = eye[i];
        c->view.target[i] = target[i];
        c->view.up[i] = up[i];
    }
    c->view.width_ws = width_ws;
    c->view.height_ws = height_ws;
    c->view.width_px = width_px;
    c->view.height_px = height_px;
    wx_error err;
    if (wx_camera_from_view(&c->view, &c->camera, &err) != WX_OK) {
        fprintf(stderr, "bad test camera %s: %s\n", name, err.message);
        exit(1);
    }
    c->line = 10 + s->camera_count;
    if (output) {
        s->output_index = s->camera_count - 1;
        snprintf(c->output_file, sizeof c->output_file, "mask.exr");
        c->output_width = width_px;
        c->output_height = height_px;
    } else {
        s->input_count++;
    }
    return c;
}

static wx_mesh *add_mesh(wx_scene *s, const char *path, int line)
{
    s->meshes = realloc(s->meshes, (size_t)(s->mesh_count + 1) * sizeof *s->meshes);
    wx_mesh *m = &s->meshes[s->mesh_count++];
    memset(m, 0, sizeof *m);
    wx_scene_set_path(&m->path, path);
    m->line = line;
    return m;
}

static wx_surface *add_surface(wx_mesh *m, const char *material, float absorption, float bounce,
                               float dirt, float deposit, float erosion)
{
    m->surfaces = realloc(m->surfaces, (size_t)(m->surface_count + 1) * sizeof *m->surfaces);
    wx_surface *s = &m->surfaces[m->surface_count++];
    memset(s, 0, sizeof *s);
    snprintf(s->material, sizeof s->material, "%s", material);
    s->absorption = absorption;
    s->bounce = bounce;
    s->initial[0] = dirt;
    s->deposit[0] = deposit;
    s->erosion[0] = erosion;
    s->line = m->line + 1 + m->surface_count;
    return s;
}

static void scene_end(wx_scene *s)
{
    wx_scene_free(s);
}

static void options_for(wx_run_def *o, const char *test)
{
    memset(o, 0, sizeof *o);
    snprintf(o->out_dir, sizeof o->out_dir, "%s/%s", ensure_tmpdir(), test);
    o->threads = 2;
    o->quiet = true;
}

// ---------------------------------------------------------------------------
// Reading maps back.

typedef struct maps4 {
    wx_image depth, normal, impact, dirt;
} maps4;

static bool read_maps(const wx_scene_camera *c, maps4 *m)
{
    static const char *const r[1] = { "R" };
    static const char *const rgb[3] = { "R", "G", "B" };
    wx_error err;
    memset(m, 0, sizeof *m);
    if (wx_exr_read(c->depth_path, r, 1, &m->depth, &err) != WX_OK ||
        wx_exr_read(c->normal_path, rgb, 3, &m->normal, &err) != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
        return false;
    }
    if (!c->is_output && (wx_exr_read(c->impact_path, rgb, 3, &m->impact, &err) != WX_OK ||
                          wx_exr_read(c->dirt_path, rgb, 3, &m->dirt, &err) != WX_OK)) {
        fprintf(stderr, "%s\n", err.message);
        return false;
    }
    return true;
}

static void free_maps(maps4 *m)
{
    wx_image_free(&m->depth);
    wx_image_free(&m->normal);
    wx_image_free(&m->impact);
    wx_image_free(&m->dirt);
}

static float at(const wx_image *img, int channel, int i, int j)
{
    return img->channels[channel][(size_t)j * (size_t)img->width + (size_t)i];
}

static double plane_sum(const wx_image *img, int channel)
{
    double s = 0.0;
    for (size_t k = 0; k < (size_t)img->width * (size_t)img->height; ++k) {
        s += img->channels[channel][k];
    }
    return s;
}

// ---------------------------------------------------------------------------
// An icosphere of radius 1 at the origin, 20 * 4^5 = 20480 triangles, as OBJ
// without normals (the import generates them).

typedef struct ico {
    double (*v)[3];
    int nv, cap_v;
    int (*f)[3];
    int nf;
} ico;

static int ico_add(ico *s, double x, double y, double z)
{
    double l = sqrt(x * x + y * y + z * z);
    s->v[s->nv][0] = x / l;
    s->v[s->nv][1] = y / l;
    s->v[s->nv][2] = z / l;
    return s->nv++;
}

// Midpoint vertex of edge (a, b), shared through a small open-addressing table.
static int ico_mid(ico *s, int a, int b, int64_t *keys, int *vals, size_t cap)
{
    int64_t lo = a < b ? a : b, hi = a < b ? b : a;
    int64_t key = lo * 1000003 + hi;
    size_t h = (size_t)(key * 2654435761u) % cap;
    while (keys[h] != -1 && keys[h] != key) {
        h = (h + 1) % cap;
    }
    if (keys[h] == key) {
        return vals[h];
    }
    keys[h] = key;
    vals[h] = ico_add(s, s->v[a][0] + s->v[b][0], s->v[a][1] + s->v[b][1],
                      s->v[a][2] + s->v[b][2]);
    return vals[h];
}

static const char *write_icosphere(const char *dir, int levels)
{
    int faces = 20;
    for (int l = 0; l < levels; ++l) {
        faces *= 4;
    }
    ico s = { 0 };
    s.cap_v = faces / 2 + 2;
    s.v = malloc((size_t)s.cap_v * sizeof *s.v);
    s.f = malloc((size_t)faces * sizeof *s.f);
    const double t = (1.0 + sqrt(5.0)) / 2.0;
    const double base[12][3] = { { -1, t, 0 }, { 1, t, 0 },  { -1, -t, 0 }, { 1, -t, 0 },
                                 { 0, -1, t }, { 0, 1, t },  { 0, -1, -t }, { 0, 1, -t },
                                 { t, 0, -1 }, { t, 0, 1 },  { -t, 0, -1 }, { -t, 0, 1 } };
    const int tri[20][3] = { { 0, 11, 5 }, { 0, 5, 1 },  { 0, 1, 7 },   { 0, 7, 10 }, { 0, 10, 11 },
                             { 1, 5, 9 },  { 5, 11, 4 }, { 11, 10, 2 }, { 10, 7, 6 }, { 7, 1, 8 },
                             { 3, 9, 4 },  { 3, 4, 2 },  { 3, 2, 6 },   { 3, 6, 8 },  { 3, 8, 9 },
                             { 4, 9, 5 },  { 2, 4, 11 }, { 6, 2, 10 },  { 8, 6, 7 },  { 9, 8, 1 } };
    for (int k = 0; k < 12; ++k) {
        ico_add(&s, base[k][0], base[k][1], base[k][2]);
    }
    memcpy(s.f, tri, sizeof tri);
    s.nf = 20;
    for (int l = 0; l < levels; ++l) {
        size_t cap = (size_t)s.nf * 4;
        int64_t *keys = malloc(cap * sizeof *keys);
        int *vals = malloc(cap * sizeof *vals);
        for (size_t k = 0; k < cap; ++k) {
            keys[k] = -1;
        }
        int (*nf)[3] = malloc((size_t)s.nf * 4 * sizeof *nf);
        for (int k = 0; k < s.nf; ++k) {
            int a = s.f[k][0], b = s.f[k][1], c = s.f[k][2];
            int ab = ico_mid(&s, a, b, keys, vals, cap);
            int bc = ico_mid(&s, b, c, keys, vals, cap);
            int ca = ico_mid(&s, c, a, keys, vals, cap);
            int q[4][3] = { { a, ab, ca }, { b, bc, ab }, { c, ca, bc }, { ab, bc, ca } };
            memcpy(&nf[4 * k], q, sizeof q);
        }
        free(s.f);
        s.f = nf;
        s.nf *= 4;
        free(keys);
        free(vals);
    }
    static char path[4096];
    snprintf(path, sizeof path, "%s/sphere%d.obj", dir, levels);
    FILE *f = fopen(path, "w");
    for (int k = 0; k < s.nv; ++k) {
        fprintf(f, "v %.9f %.9f %.9f\n", s.v[k][0], s.v[k][1], s.v[k][2]);
    }
    for (int k = 0; k < s.nf; ++k) {
        fprintf(f, "f %d %d %d\n", s.f[k][0] + 1, s.f[k][1] + 1, s.f[k][2] + 1);
    }
    fclose(f);
    free(s.v);
    free(s.f);
    return path;
}

// ---------------------------------------------------------------------------
// Tests.

static const float ORIGIN[3] = { 0, 0, 0 };
static const float UP_Y[3] = { 0, 1, 0 };

// Expected depth and normal of the unit sphere at texel (i, j): with the image
// plane offsets a = (u-1/2) W, b = (v-1/2) H and eye distance D,
// d = D - sqrt(1 - a^2 - b^2), n = a right + b up - sqrt(1 - a^2 - b^2) forward.
static void check_sphere_camera(const wx_scene_camera *c, const maps4 *m, float eye_distance)
{
    const float right[3] = { c->camera.ctw[0] / c->view.width_ws,
                             c->camera.ctw[1] / c->view.width_ws,
                             c->camera.ctw[2] / c->view.width_ws };
    const float up[3] = { c->camera.ctw[4] / c->view.height_ws,
                          c->camera.ctw[5] / c->view.height_ws,
                          c->camera.ctw[6] / c->view.height_ws };
    float fwd[3];
    wx_camera_view_dir(&c->camera, fwd);
    const int texels[][2] = { { 64, 64 }, { 63, 63 }, { 80, 50 }, { 40, 80 }, { 90, 70 },
                              { 45, 45 }, { 64, 36 }, { 85, 85 }, { 64, 95 } };
    int W = c->camera.width, H = c->camera.height;
    for (size_t k = 0; k < sizeof texels / sizeof texels[0]; ++k) {
        int i = texels[k][0], j = texels[k][1];
        float u, v;
        wx_map_texel_center(W, H, i, j, &u, &v);
        double a = (u - 0.5) * c->view.width_ws, b = (v - 0.5) * c->view.height_ws;
        double r2 = a * a + b * b;
        ENSURE(r2 < 0.85 * 0.85); // the chosen texels lie well inside the disc
        double h = sqrt(1.0 - r2);
        ENSURE_NEAR(at(&m->depth, 0, i, j), eye_distance - h, 0.01);
        for (int q = 0; q < 3; ++q) {
            double n = a * right[q] + b * up[q] - h * fwd[q];
            ENSURE_NEAR(at(&m->normal, q, i, j), n, 0.03);
        }
    }
    // Outside the disc: no surface.
    ENSURE(isinf(at(&m->depth, 0, 0, 0)) && at(&m->depth, 0, 0, 0) > 0);
    ENSURE(isinf(at(&m->depth, 0, W - 1, H - 1)));
    ENSURE(isinf(at(&m->depth, 0, 5, H / 2)));
    ENSURE(at(&m->normal, 0, 0, 0) == 0.0f && at(&m->normal, 2, 0, 0) == 0.0f);
}

TEST(sphere_depth_and_normal)
{
    const char *sphere = write_icosphere(ensure_tmpdir(), 5);
    wx_scene s;
    scene_begin(&s);
    const float eye_front[3] = { 0, 0, 5 };
    add_camera(&s, "front", eye_front, ORIGIN, UP_Y, 3, 3, 128, 128, false);
    // An oblique camera at distance 5 along (1, 1, 1)/sqrt(3), frame 2.5 x 2.5.
    float k = 5.0f / sqrtf(3.0f);
    const float eye_diag[3] = { k, k, k };
    add_camera(&s, "diag", eye_diag, ORIGIN, UP_Y, 2.5f, 2.5f, 128, 128, false);
    wx_mesh *mesh = add_mesh(&s, sphere, 30);
    add_surface(mesh, "*", 0.2f, 0.3f, 0, 0.5f, 0.1f);
    wx_run_def o;
    options_for(&o, "sphere");
    wx_error err = { 0 };
    wx_bake_stats stats;
    wx_result r = wx_bake_scene_stats(&s, &o, &stats, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    ENSURE(stats.cameras == 2);
    ENSURE(stats.triangles == 20480);
    for (int c = 0; c < 2; ++c) {
        maps4 m;
        ENSURE(read_maps(&s.cameras[c], &m));
        ENSURE(m.depth.width == 128 && m.depth.height == 128);
        check_sphere_camera(&s.cameras[c], &m, 5.0f);
        // Impact and dirt properties are constant on the sphere.
        ENSURE_NEAR(at(&m.impact, 0, 64, 64), 0.2, 1e-6);
        ENSURE_NEAR(at(&m.impact, 1, 64, 64), 0.3, 1e-6);
        ENSURE(at(&m.impact, 2, 64, 64) == 0.0f);
        ENSURE(at(&m.dirt, 0, 64, 64) == 0.0f);
        ENSURE_NEAR(at(&m.dirt, 1, 64, 64), 0.5, 1e-6);
        ENSURE_NEAR(at(&m.dirt, 2, 64, 64), 0.1, 1e-6);
        ENSURE(at(&m.impact, 0, 0, 0) == 0.0f);
        int failed_before = ensure_failed_checks;
        free_maps(&m);
        ENSURE(failed_before == ensure_failed_checks);
    }
    scene_end(&s);
}

// Box [-1,1]^3: front face z = 1 seen from (0,0,5) at d = 4 with normal +z, top
// face y = 1 seen from (0,5,0) at d = 4 with normal +y, also next to the edges.
static void check_box(const char *file, const char *test, int threads)
{
    wx_scene s;
    scene_begin(&s);
    const float eye_front[3] = { 0, 0, 5 }, eye_top[3] = { 0, 5, 0 }, up_top[3] = { 0, 0, -1 };
    add_camera(&s, "front", eye_front, ORIGIN, UP_Y, 4, 4, 64, 64, false);
    add_camera(&s, "top", eye_top, ORIGIN, up_top, 4, 4, 64, 64, false);
    wx_mesh *mesh = add_mesh(&s, data_path(file), 30);
    add_surface(mesh, "*", 0.5f, 0.5f, 0, 0, 0);
    wx_run_def o;
    options_for(&o, test);
    o.threads = threads;
    wx_error err = { 0 };
    wx_result r = wx_bake_scene(&s, &o, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    const float axis[2][3] = { { 0, 0, 1 }, { 0, 1, 0 } };
    for (int c = 0; c < 2; ++c) {
        maps4 m;
        ENSURE(read_maps(&s.cameras[c], &m));
        // The face covers u, v in [0.25, 0.75]: texels 16..47. 16 and 47 are the
        // texels along its edges.
        const int texels[][2] = { { 32, 32 }, { 16, 16 }, { 47, 47 }, { 16, 40 }, { 47, 20 } };
        for (size_t k = 0; k < sizeof texels / sizeof texels[0]; ++k) {
            int i = texels[k][0], j = texels[k][1];
            ENSURE_NEAR(at(&m.depth, 0, i, j), 4.0, 1e-4);
            for (int q = 0; q < 3; ++q) {
                ENSURE_NEAR(at(&m.normal, q, i, j), axis[c][q], 1e-3);
            }
        }
        ENSURE(isinf(at(&m.depth, 0, 15, 32)));
        ENSURE(isinf(at(&m.depth, 0, 32, 48)));
        int failed_before = ensure_failed_checks;
        free_maps(&m);
        ENSURE(failed_before == ensure_failed_checks);
    }
    scene_end(&s);
}

TEST(box_faces)
{
    check_box("bake_box.obj", "box", 2);
}

TEST(flipped_winding_still_faces_the_camera)
{
    check_box("bake_box_flipped.obj", "box_flipped", 1); // files written in turn
}

TEST(top_scanline_is_highest_v)
{
    // The camera looks at y = -1.5: the box (y in [-1, 1]) fills v in
    // [7/12, 11/12], the upper half, so rows j < H/2 only.
    wx_scene s;
    scene_begin(&s);
    const float eye[3] = { 0, -1.5f, 5 }, target[3] = { 0, -1.5f, 0 };
    add_camera(&s, "low", eye, target, UP_Y, 6, 6, 48, 48, false);
    wx_mesh *mesh = add_mesh(&s, data_path("bake_box.obj"), 30);
    add_surface(mesh, "*", 0, 0, 0, 0, 0);
    wx_run_def o;
    options_for(&o, "rows");
    wx_error err = { 0 };
    ENSURE(wx_bake_scene(&s, &o, &err) == WX_OK);
    maps4 m;
    ENSURE(read_maps(&s.cameras[0], &m));
    int first = -1, last = -1;
    for (int j = 0; j < 48; ++j) {
        for (int i = 0; i < 48; ++i) {
            if (isfinite(at(&m.depth, 0, i, j))) {
                first = first < 0 ? j : first;
                last = j;
            }
        }
    }
    // v = 11/12 -> row (1 - 11/12) * 48 = 4; v = 7/12 -> row 20 (exclusive).
    ENSURE(first == 4);
    ENSURE(last == 19);
    ENSURE(last < 24);
    free_maps(&m);
    scene_end(&s);
}

TEST(two_materials_two_impacts)
{
    wx_scene s;
    scene_begin(&s);
    const float eye[3] = { 0, 0, 5 };
    add_camera(&s, "front", eye, ORIGIN, UP_Y, 2, 2, 32, 32, false);
    wx_mesh *mesh = add_mesh(&s, data_path("bake_two_materials.obj"), 30);
    add_surface(mesh, "Wood", 0.25f, 0.5f, 0, 0.1f, 0.2f);
    add_surface(mesh, "*", 0.75f, 0.125f, 0, 0.3f, 0.4f);
    wx_run_def o;
    options_for(&o, "materials");
    wx_error err = { 0 };
    ENSURE(wx_bake_scene(&s, &o, &err) == WX_OK);
    maps4 m;
    ENSURE(read_maps(&s.cameras[0], &m));
    for (int j = 0; j < 32; j += 5) {
        for (int i = 0; i < 32; i += 3) {
            bool wood = i < 16; // x < 0
            ENSURE_NEAR(at(&m.impact, 0, i, j), wood ? 0.25 : 0.75, 1e-6);
            ENSURE_NEAR(at(&m.impact, 1, i, j), wood ? 0.5 : 0.125, 1e-6);
            ENSURE_NEAR(at(&m.dirt, 1, i, j), wood ? 0.1 : 0.3, 1e-6);
            ENSURE_NEAR(at(&m.dirt, 2, i, j), wood ? 0.2 : 0.4, 1e-6);
            ENSURE_NEAR(at(&m.depth, 0, i, j), 5.0, 1e-5);
        }
    }
    free_maps(&m);
    scene_end(&s);
}

TEST(unmatched_material_lists_names)
{
    wx_scene s;
    scene_begin(&s);
    const float eye[3] = { 0, 0, 5 };
    add_camera(&s, "front", eye, ORIGIN, UP_Y, 2, 2, 16, 16, false);
    wx_mesh *mesh = add_mesh(&s, data_path("bake_two_materials.obj"), 42);
    add_surface(mesh, "Glass", 0.25f, 0.5f, 0, 0, 0);
    wx_run_def o;
    options_for(&o, "unmatched");
    wx_error err = { 0 };
    ENSURE(wx_bake_scene(&s, &o, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, UNMATCHED_MATERIAL);
    ENSURE(ensure_contains(err.message, "scene.xml:42: mesh '"));
    ENSURE(ensure_contains(err.message, "bake_two_materials.obj' has material 'Wood' that no "
                                        "<Surface> matches (materials in the file: Wood, Glass)"));
    ENSURE(!wx_has_path(s.cameras[0].depth_path));
    scene_end(&s);
}

TEST(vertex_colours_to_impact_and_dirt)
{
    // Colour (0.2, 0.8, 0) at y = -1 and (1, 0, 0) at y = 1, linear in y.
    wx_scene s;
    scene_begin(&s);
    const float eye[3] = { 0, 0, 5 };
    add_camera(&s, "front", eye, ORIGIN, UP_Y, 2, 2, 32, 32, false);
    wx_mesh *mesh = add_mesh(&s, data_path("bake_colors.ply"), 30);
    wx_surface *surf = add_surface(mesh, "*", 0.5f, 0.5f, 0, 0.7f, 0.7f);
    surf->colors = WX_COLOR_IMPACT;
    wx_run_def o;
    options_for(&o, "colors");
    wx_error err = { 0 };
    wx_result r = wx_bake_scene(&s, &o, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    maps4 m;
    ENSURE(read_maps(&s.cameras[0], &m));
    for (int j = 0; j < 32; j += 3) {
        float u, v;
        wx_map_texel_center(32, 32, 7, j, &u, &v);
        double t = v; // y = 2v - 1, t = (y + 1) / 2
        ENSURE_NEAR(at(&m.impact, 0, 7, j), 0.2 + 0.8 * t, 1e-4);
        ENSURE_NEAR(at(&m.impact, 1, 7, j), 0.8 - 0.8 * t, 1e-4);
        ENSURE_NEAR(at(&m.dirt, 1, 7, j), 0.7, 1e-6); // not from the colours
    }
    free_maps(&m);

    // The same colours as dirt density, deposit, erosion (one camera: it holds
    // all the dirt, density * texel area / |N.view| with |N.view| = 1).
    surf->colors = WX_COLOR_DIRT;
    wx_scene_camera *c = &s.cameras[0];
    c->depth_path[0] = c->normal_path[0] = c->impact_path[0] = c->dirt_path[0] = '\0';
    options_for(&o, "colors_dirt");
    ENSURE(wx_bake_scene(&s, &o, &err) == WX_OK);
    ENSURE(read_maps(&s.cameras[0], &m));
    double texel_area = (2.0 / 32) * (2.0 / 32);
    for (int j = 0; j < 32; j += 3) {
        float u, v;
        wx_map_texel_center(32, 32, 20, j, &u, &v);
        double t = v;
        ENSURE_NEAR(at(&m.dirt, 0, 20, j), (0.2 + 0.8 * t) * texel_area, 1e-6);
        ENSURE_NEAR(at(&m.dirt, 1, 20, j), 0.8 - 0.8 * t, 1e-4);
        ENSURE_NEAR(at(&m.dirt, 2, 20, j), 0.0, 1e-6);
        ENSURE_NEAR(at(&m.impact, 0, 20, j), 0.5, 1e-6);
    }
    free_maps(&m);
    scene_end(&s);
}

TEST(vertex_colours_missing_is_an_error)
{
    wx_scene s;
    scene_begin(&s);
    const float eye[3] = { 0, 0, 5 };
    add_camera(&s, "front", eye, ORIGIN, UP_Y, 2, 2, 16, 16, false);
    wx_mesh *mesh = add_mesh(&s, data_path("bake_box.obj"), 30);
    add_surface(mesh, "*", 0, 0, 0, 0, 0)->colors = WX_COLOR_IMPACT;
    wx_run_def o;
    options_for(&o, "nocolors");
    wx_error err = { 0 };
    ENSURE(wx_bake_scene(&s, &o, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, UNMATCHED_MATERIAL);
    ENSURE(ensure_contains(err.message, "vertex colours"));
    ENSURE(ensure_contains(err.message, "bake_box.obj"));
    scene_end(&s);
}

// A 2 x 2 quad in the plane z = 0 facing +z, as an OBJ in the test folder.
static const char *write_quad(void)
{
    return ensure_write_file(ensure_tmpdir(), "quad.obj",
                             "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n");
}

static void eye_at_angle(float degrees, float eye[3])
{
    float a = degrees * 3.14159265f / 180.0f;
    eye[0] = 5.0f * sinf(a);
    eye[1] = 0.0f;
    eye[2] = 5.0f * cosf(a);
}

TEST(initial_dirt_goes_to_the_most_head_on_camera)
{
    // Camera "slant" sees the quad at 60 degrees (|N.view| = 1/2) and is listed
    // first; "head" sees it head-on and holds all its dirt: density x texel area.
    const float density = 2.0f;
    wx_scene s;
    scene_begin(&s);
    float slant[3], head[3];
    eye_at_angle(60, slant);
    eye_at_angle(0, head);
    add_camera(&s, "slant", slant, ORIGIN, UP_Y, 4, 4, 64, 64, false);
    add_camera(&s, "head", head, ORIGIN, UP_Y, 4, 4, 64, 64, false);
    wx_mesh *mesh = add_mesh(&s, write_quad(), 30);
    add_surface(mesh, "*", 0, 0, density, 0.5f, 0.5f);
    wx_run_def o;
    options_for(&o, "dirt_head_on");
    wx_error err = { 0 };
    ENSURE(wx_bake_scene(&s, &o, &err) == WX_OK);
    maps4 a, b;
    ENSURE(read_maps(&s.cameras[0], &a));
    ENSURE(read_maps(&s.cameras[1], &b));
    double texel_area = (4.0 / 64) * (4.0 / 64);
    // The quad covers texels 16..47 of "head" exactly.
    for (int j = 16; j < 48; j += 3) {
        for (int i = 16; i < 48; i += 5) {
            ENSURE_NEAR(at(&b.dirt, 0, i, j), density * texel_area, 1e-7);
        }
    }
    ENSURE(at(&b.dirt, 0, 10, 32) == 0.0f); // background
    ENSURE(plane_sum(&a.dirt, 0) == 0.0);
    ENSURE(isfinite(at(&a.depth, 0, 32, 32))); // "slant" does see the quad
    ENSURE_NEAR(at(&a.dirt, 1, 32, 32), 0.5, 1e-6);
    // All the quad's dirt, stored once: density x area 4.
    ENSURE_NEAR(plane_sum(&b.dirt, 0), density * 4.0, 1e-4);
    free_maps(&a);
    free_maps(&b);
    scene_end(&s);
}

TEST(initial_dirt_one_camera_divides_by_cosine)
{
    // Alone, the 60 degree camera holds density x texel area / (1/2) per texel,
    // which still adds up to density x area.
    const float density = 2.0f;
    wx_scene s;
    scene_begin(&s);
    float slant[3];
    eye_at_angle(60, slant);
    add_camera(&s, "slant", slant, ORIGIN, UP_Y, 4, 4, 64, 64, false);
    wx_mesh *mesh = add_mesh(&s, write_quad(), 30);
    add_surface(mesh, "*", 0, 0, density, 0, 0);
    wx_run_def o;
    options_for(&o, "dirt_cosine");
    wx_error err = { 0 };
    ENSURE(wx_bake_scene(&s, &o, &err) == WX_OK);
    maps4 a;
    ENSURE(read_maps(&s.cameras[0], &a));
    double texel_area = (4.0 / 64) * (4.0 / 64);
    ENSURE_NEAR(at(&a.dirt, 0, 32, 32), density * texel_area / 0.5, 1e-6);
    ENSURE_NEAR(at(&a.dirt, 0, 26, 20), density * texel_area / 0.5, 1e-6);
    // The quad spans u in [0.375, 0.625]: 16 columns, edges on texel borders.
    ENSURE_NEAR(plane_sum(&a.dirt, 0), density * 4.0, 1e-4);
    free_maps(&a);
    scene_end(&s);
}

TEST(initial_dirt_tie_goes_to_the_first_camera)
{
    // Two cameras at +30 and -30 degrees: equal |N.view|; the first listed holds it.
    const float density = 1.0f;
    wx_scene s;
    scene_begin(&s);
    float left[3], right[3];
    eye_at_angle(-30, left);
    eye_at_angle(30, right);
    add_camera(&s, "left", left, ORIGIN, UP_Y, 4, 4, 64, 64, false);
    add_camera(&s, "right", right, ORIGIN, UP_Y, 4, 4, 64, 64, false);
    wx_mesh *mesh = add_mesh(&s, write_quad(), 30);
    add_surface(mesh, "*", 0, 0, density, 0, 0);
    wx_run_def o;
    options_for(&o, "dirt_tie");
    wx_error err = { 0 };
    ENSURE(wx_bake_scene(&s, &o, &err) == WX_OK);
    maps4 a, b;
    ENSURE(read_maps(&s.cameras[0], &a));
    ENSURE(read_maps(&s.cameras[1], &b));
    // The quad spans u in [0.2835, 0.7165]: columns 18..45 (28), 32 rows, each
    // texel density x texel area / cos 30.
    double texel_area = (4.0 / 64) * (4.0 / 64);
    ENSURE_NEAR(plane_sum(&a.dirt, 0), 28 * 32 * density * texel_area / (sqrt(3.0) / 2.0), 1e-4);
    ENSURE(plane_sum(&b.dirt, 0) == 0.0);
    free_maps(&a);
    free_maps(&b);
    scene_end(&s);
}

TEST(initial_dirt_hidden_from_head_on_camera)
{
    // A blocker (no dirt) at z = 1 over x in [-1, 0] hides the left half of the
    // quad from "head"; "slant" (60 degrees, towards +x) sees the whole quad, so
    // it holds the left half's dirt and "head" the right half's.
    const float density = 1.0f;
    wx_scene s;
    scene_begin(&s);
    float slant[3], head[3];
    eye_at_angle(60, slant);
    eye_at_angle(0, head);
    add_camera(&s, "head", head, ORIGIN, UP_Y, 4, 4, 64, 64, false);
    add_camera(&s, "slant", slant, ORIGIN, UP_Y, 4, 4, 64, 64, false);
    add_surface(add_mesh(&s, write_quad(), 30), "*", 0, 0, density, 0, 0);
    const char *blocker = ensure_write_file(ensure_tmpdir(), "blocker.obj",
                                            "v -1 -1 1\nv 0 -1 1\nv 0 1 1\nv -1 1 1\nf 1 2 3 4\n");
    add_surface(add_mesh(&s, blocker, 40), "*", 0, 0, 0, 0, 0);
    wx_run_def o;
    options_for(&o, "dirt_hidden");
    wx_error err = { 0 };
    ENSURE(wx_bake_scene(&s, &o, &err) == WX_OK);
    maps4 a, b;
    ENSURE(read_maps(&s.cameras[0], &a));
    ENSURE(read_maps(&s.cameras[1], &b));
    ENSURE_NEAR(at(&a.depth, 0, 20, 32), 4.0, 1e-4); // the blocker, no dirt
    ENSURE(at(&a.dirt, 0, 20, 32) == 0.0f);
    ENSURE_NEAR(at(&a.depth, 0, 40, 32), 5.0, 1e-4); // the quad's right half
    ENSURE(at(&a.dirt, 0, 40, 32) > 0.0f);
    double texel_area = (4.0 / 64) * (4.0 / 64);
    ENSURE_NEAR(plane_sum(&a.dirt, 0), density * 2.0, 2 * 32 * texel_area * density);
    ENSURE_NEAR(plane_sum(&b.dirt, 0), density * 2.0, 2 * 32 * texel_area * density);
    ENSURE_NEAR(plane_sum(&a.dirt, 0) + plane_sum(&b.dirt, 0), density * 4.0,
                32 * texel_area * density);
    free_maps(&a);
    free_maps(&b);
    scene_end(&s);
}

TEST(output_camera_gets_depth_and_normal_only)
{
    wx_scene s;
    scene_begin(&s);
    const float eye[3] = { 0, 0, 5 };
    add_camera(&s, "front", eye, ORIGIN, UP_Y, 4, 4, 32, 32, false);
    wx_scene_camera *out = add_camera(&s, "shot", eye, ORIGIN, UP_Y, 4, 2, 40, 20, true);
    (void)out;
    add_surface(add_mesh(&s, data_path("bake_box.obj"), 30), "*", 0, 0, 0, 0, 0);
    wx_run_def o;
    options_for(&o, "output");
    wx_error err = { 0 };
    ENSURE(wx_bake_scene(&s, &o, &err) == WX_OK);
    const wx_scene_camera *shot = &s.cameras[1];
    ENSURE(ensure_contains(shot->depth_path, "shot_depth.exr"));
    ENSURE(ensure_contains(shot->normal_path, "shot_normal.exr"));
    ENSURE(!wx_has_path(shot->impact_path) && !wx_has_path(shot->dirt_path));
    char path[4200];
    snprintf(path, sizeof path, "%s/shot_impact.exr", o.out_dir);
    struct stat st;
    ENSURE(stat(path, &st) != 0);
    maps4 m;
    ENSURE(read_maps(shot, &m));
    ENSURE(m.depth.width == 40 && m.depth.height == 20);
    ENSURE_NEAR(at(&m.depth, 0, 20, 10), 4.0, 1e-4);
    // Headers describe the camera.
    wx_image h;
    ENSURE(wx_exr_read_header(shot->depth_path, &h, &err) == WX_OK);
    const wx_attr *wtc = wx_image_find_attr(&h, "WTCMatrix");
    const wx_attr *ctw = wx_image_find_attr(&h, "CTWMatrix");
    const wx_attr *name = wx_image_find_attr(&h, "cameraName");
    ENSURE(wtc != NULL && wtc->type == WX_ATTR_M44F);
    ENSURE(ctw != NULL && ctw->type == WX_ATTR_M44F);
    ENSURE(name != NULL && strcmp(name->string, "shot") == 0);
    ENSURE(memcmp(wtc->m44f, shot->camera.wtc, sizeof wtc->m44f) == 0);
    ENSURE(memcmp(ctw->m44f, shot->camera.ctw, sizeof ctw->m44f) == 0);
    ENSURE(ensure_contains(s.cameras[0].dirt_path, "front_dirt.exr"));
    free_maps(&m);
    scene_end(&s);
}

TEST(missing_and_unsupported_mesh_files)
{
    const char *files[2] = { "bake_missing_mesh.obj", "bake_not_a_mesh.txt" };
    const wx_cause causes[2] = { WX_CAUSE_FILE_MISSING, WX_CAUSE_BAD_MESH };
    for (int k = 0; k < 2; ++k) {
        wx_scene s;
        scene_begin(&s);
        const float eye[3] = { 0, 0, 5 };
        add_camera(&s, "front", eye, ORIGIN, UP_Y, 4, 4, 16, 16, false);
        add_surface(add_mesh(&s, data_path(files[k]), 7), "*", 0, 0, 0, 0, 0);
        wx_run_def o;
        options_for(&o, "missing");
        wx_error err = { 0 };
        ENSURE(wx_bake_scene(&s, &o, &err) == WX_BAD_INPUT);
        ENSURE(err.cause == causes[k]);
        ENSURE(ensure_contains(err.message, "scene.xml:7"));
        ENSURE(ensure_contains(err.message, files[k]));
        ENSURE(!wx_has_path(s.cameras[0].depth_path));
        scene_end(&s);
    }
}

TEST(no_geometry_is_an_error)
{
    wx_scene s;
    scene_begin(&s);
    const float eye[3] = { 0, 0, 5 };
    add_camera(&s, "front", eye, ORIGIN, UP_Y, 4, 4, 16, 16, false);
    wx_run_def o;
    options_for(&o, "nogeometry");
    wx_error err = { 0 };
    ENSURE(wx_bake_scene(&s, &o, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, MISSING);
    ENSURE(ensure_contains(err.message, "camera 'front'"));
    ENSURE(ensure_contains(err.message, "no <Geometry>"));
    // Nothing to bake (maps given): no mesh needed, nothing written.
    wx_scene_set_path(&s.cameras[0].depth_path, "given.exr");
    ENSURE(wx_bake_scene(&s, &o, &err) == WX_OK);
    scene_end(&s);
}

TEST(maps_beyond_the_renderer_are_refused)
{
    wx_scene s;
    scene_begin(&s);
    const float eye[3] = { 0, 0, 5 };
    add_camera(&s, "huge", eye, ORIGIN, UP_Y, 4, 4, WX_MAP_MAX_SIDE + 1, 16, false);
    add_surface(add_mesh(&s, data_path("bake_box.obj"), 30), "*", 0, 0, 0, 0, 0);
    wx_run_def o;
    options_for(&o, "huge");
    wx_error err = { 0 };
    ENSURE(wx_bake_scene(&s, &o, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, MAP_SIZE);
    ENSURE(ensure_contains(err.message, "camera 'huge'"));
    ENSURE(ensure_contains(err.message, "at most"));
    scene_end(&s);
}

// A scene file with <View> cameras (two inputs, an output) and a box with
// initial dirt: bake, then load the maps back through the scene's map reader.
static const char *const SCENE_XML =
    "<?xml version=\"1.0\"?>\n"
    "<Weathering>\n"
    "  <Collider>\n"
    "    <ProjectedMaps>\n"
    "      <Ortho cameraName=\"front\">\n"
    "        <View eye=\"0 0 5\" target=\"0 0 0\" up=\"0 1 0\" width=\"4\" height=\"4\" "
    "resolution=\"64\"/>\n"
    "      </Ortho>\n"
    "      <Ortho cameraName=\"top\">\n"
    "        <View eye=\"0 5 0\" target=\"0 0 0\" up=\"0 0 -1\" width=\"4\" height=\"4\" "
    "resolution=\"64\"/>\n"
    "      </Ortho>\n"
    "      <Ortho cameraName=\"shot\" out=\"true\">\n"
    "        <View eye=\"3 3 5\" target=\"0 0 0\" up=\"0 1 0\" width=\"5\" height=\"5\" "
    "resolution=\"32\"/>\n"
    "        <OutputMap file=\"mask.exr\" width=\"32\" height=\"32\"/>\n"
    "      </Ortho>\n"
    "    </ProjectedMaps>\n"
    "  </Collider>\n"
    "  <Geometry>\n"
    "    <Mesh file=\"%s\">\n"
    "      <Surface material=\"*\" absorption=\"0.25\" bounce=\"0.5\" dirt=\"1\" "
    "deposit=\"0.75\" erosion=\"0.125\"/>\n"
    "    </Mesh>\n"
    "  </Geometry>\n"
    "</Weathering>\n";

static const char *write_scene(const char *name, const char *mesh_file)
{
    static char dir[4200];
    snprintf(dir, sizeof dir, "%s/%s", ensure_tmpdir(), name);
    mkdir(dir, 0777);
    char *box = ensure_read_file(data_path("bake_box.obj"));
    ensure_write_file(dir, "box.obj", box != NULL ? box : "");
    free(box);
    char *xml = malloc(strlen(SCENE_XML) + 256);
    sprintf(xml, SCENE_XML, mesh_file);
    const char *path = ensure_write_file(dir, "scene.xml", xml);
    free(xml);
    return path;
}

TEST(scene_file_bakes_maps_the_scene_reads_back)
{
    const char *path = write_scene("scene_file", "box.obj");
    wx_scene s;
    wx_error err = { 0 };
    wx_result r = wx_scene_load(path, &s, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    wx_run_def o;
    options_for(&o, "scene_file_out");
    ENSURE(wx_bake_scene(&s, &o, &err) == WX_OK);
    double texel_area = (4.0 / 64) * (4.0 / 64);
    for (int c = 0; c < 2; ++c) {
        const wx_scene_camera *sc = &s.cameras[c];
        wx_maps m;
        memset(&m, 0, sizeof m);
        r = wx_maps_load(&m, WX_MAPS_ALL, 1, sc->depth_path, sc->normal_path, sc->impact_path,
                         sc->dirt_path, &err);
        if (r != WX_OK) {
            fprintf(stderr, "%s\n", err.message);
        }
        ENSURE(r == WX_OK);
        ENSURE(m.width == 64 && m.height == 64);
        size_t t = 32 * 64 + 32;
        ENSURE_NEAR(m.depth[t], 4.0, 1e-4);
        ENSURE_NEAR(m.normal[3 * t + (c == 0 ? 2 : 1)], 1.0, 1e-4);
        ENSURE_NEAR(m.impact[2 * t], 0.25, 1e-6);
        ENSURE_NEAR(m.impact[2 * t + 1], 0.5, 1e-6);
        ENSURE_NEAR(m.deposit[t], 0.75, 1e-6);
        ENSURE_NEAR(m.erosion[t], 0.125, 1e-6);
        // Each camera holds the dirt of the face it sees head-on: 1 x area 4.
        ENSURE_NEAR(m.dirt[t], texel_area, 1e-7);
        double sum = 0.0;
        for (size_t k = 0; k < 64 * 64; ++k) {
            sum += m.dirt[k];
        }
        ENSURE_NEAR(sum, 4.0, 1e-4);
        ENSURE(wx_depth_is_empty(m.depth[0]));
        wx_maps_free(&m);
    }
    const wx_scene_camera *shot = &s.cameras[2];
    ENSURE(shot->is_output && !wx_has_path(shot->impact_path));
    wx_maps m;
    memset(&m, 0, sizeof m);
    ENSURE(wx_maps_load(&m, WX_MAPS_DEPTH | WX_MAPS_NORMAL, 1, shot->depth_path, shot->normal_path,
                        NULL, NULL, &err) == WX_OK);
    ENSURE(m.width == 32 && m.height == 32);
    // The corner (1,1,1) of the box is nearest to the shot camera: its eye
    // (3,3,5) is at distance sqrt(43) from the origin, and the corner lies
    // (1,1,1).(3,3,5)/sqrt(43) = 11/sqrt(43) closer.
    float uvd[3];
    const float corner[3] = { 1, 1, 1 };
    wx_camera_world_to_map(&shot->camera, corner, uvd);
    int i, j;
    ENSURE(wx_map_texel(32, 32, uvd[0], uvd[1], &i, &j));
    ENSURE_NEAR(uvd[2], (43.0 - 11.0) / sqrt(43.0), 1e-5);
    float best = INFINITY;
    for (size_t k = 0; k < 32 * 32; ++k) {
        best = m.depth[k] < best ? m.depth[k] : best;
    }
    ENSURE_NEAR(best, uvd[2], 0.2); // the nearest texel centre is close to the corner
    wx_maps_free(&m);
    wx_scene_free(&s);

    // A later phase in another process finds the baked maps in the same folder.
    ENSURE(wx_scene_load(path, &s, &err) == WX_OK);
    ENSURE(!wx_has_path(s.cameras[0].depth_path));
    r = wx_use_baked_maps(&s, &o, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    ENSURE(ensure_contains(s.cameras[1].dirt_path, "top_dirt.exr"));
    wx_scene_free(&s);
}

// Runs the bake with stderr captured into `out`.
static wx_result bake_capturing_stderr(wx_scene *s, const wx_run_def *o, char *out,
                                       size_t cap, wx_error *err)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/stderr.txt", ensure_tmpdir());
    fflush(stderr);
    int saved = dup(2);
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 2);
    close(fd);
    wx_result r = wx_bake_scene(s, o, err);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    char *text = ensure_read_file(path);
    snprintf(out, cap, "%s", text != NULL ? text : "");
    free(text);
    return r;
}

TEST(warns_about_geometry_outside_the_frame_or_behind_the_eye)
{
    // The eye at z = 0.5 inside the box: the front face (z = 1) is behind it,
    // and the 1 x 1 frame is smaller than the box.
    wx_scene s;
    scene_begin(&s);
    const float eye[3] = { 0, 0, 0.5f };
    add_camera(&s, "inside", eye, ORIGIN, UP_Y, 1, 1, 16, 16, false);
    add_surface(add_mesh(&s, data_path("bake_box.obj"), 30), "*", 0, 0, 0, 0, 0);
    wx_run_def o;
    options_for(&o, "warnings");
    o.quiet = false;
    wx_error err = { 0 };
    char text[4096];
    wx_result r = bake_capturing_stderr(&s, &o, text, sizeof text, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n%s\n", err.message, text);
    }
    ENSURE(r == WX_OK);
    ENSURE(ensure_contains(text, "warning: scene.xml: camera 'inside': 24 of 24 vertices of "
                                 "mesh '"));
    ENSURE(ensure_contains(text, "fall outside its frame"));
    ENSURE(ensure_contains(text, "12 of 24 vertices"));
    ENSURE(ensure_contains(text, "behind its eye"));
    // What is in front of the eye is still baked: the back face z = -1 at d = 1.5.
    maps4 m;
    ENSURE(read_maps(&s.cameras[0], &m));
    ENSURE_NEAR(at(&m.depth, 0, 8, 8), 1.5, 1e-4);
    free_maps(&m);
    // -q silences the warnings.
    o.quiet = true;
    wx_scene_camera *c = &s.cameras[0];
    c->depth_path[0] = c->normal_path[0] = c->impact_path[0] = c->dirt_path[0] = '\0';
    r = bake_capturing_stderr(&s, &o, text, sizeof text, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    ENSURE(text[0] == '\0');
    scene_end(&s);
}

TEST(cli_bake_writes_the_maps_and_refuses_a_bad_mesh)
{
    char out[8192];
    const char *build = ensure_build_dir();
    ENSURE(ensure_shell(out, sizeof out, "'%s/weathering' bake --help", build) == 0);
    const char *path = write_scene("cli", "box.obj");
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/cli_out", ensure_tmpdir());
    int status = ensure_shell(out, sizeof out, "'%s/weathering' bake '%s' --out '%s' -q", build,
                              path, dir);
    if (status != 0) {
        fprintf(stderr, "%s\n", out);
    }
    ENSURE(status == 0);
    char file[4400];
    struct stat st;
    const char *names[6] = { "front_depth.exr", "front_normal.exr", "front_impact.exr",
                             "front_dirt.exr",  "shot_depth.exr",   "shot_normal.exr" };
    for (int k = 0; k < 6; ++k) {
        snprintf(file, sizeof file, "%s/%s", dir, names[k]);
        ENSURE(stat(file, &st) == 0);
    }
    // An unsupported mesh file: exit status 2 and a message naming it.
    const char *bad = ensure_write_file(ensure_tmpdir(), "cli/notamesh.obj", "this is not\n");
    (void)bad;
    path = write_scene("cli", "notamesh.obj");
    status = ensure_shell(out, sizeof out, "'%s/weathering' bake '%s' --out '%s' -q", build, path,
                          dir);
    ENSURE(status == 2);
    ENSURE(ensure_contains(out, "notamesh.obj"));
}

// ---------------------------------------------------------------------------
// Layers: depth peeling (docs/design.md section 14).

// Reads layer `layer` of a camera's maps (layer 0's channel names, prefixed
// "layerK." from layer 1 on: wx_layer_channel), as read_maps does.
static bool read_layer_maps(const wx_scene_camera *c, int layer, maps4 *m)
{
    static const char *const rgb[3] = { "R", "G", "B" };
    char names[3][WX_NAME_MAX];
    const char *wanted[3];
    for (int k = 0; k < 3; ++k) {
        if (!wx_layer_channel(names[k], layer, rgb[k])) {
            return false;
        }
        wanted[k] = names[k];
    }
    wx_error err;
    memset(m, 0, sizeof *m);
    if (wx_exr_read(c->depth_path, wanted, 1, &m->depth, &err) != WX_OK ||
        wx_exr_read(c->normal_path, wanted, 3, &m->normal, &err) != WX_OK ||
        (!c->is_output && (wx_exr_read(c->impact_path, wanted, 3, &m->impact, &err) != WX_OK ||
                           wx_exr_read(c->dirt_path, wanted, 3, &m->dirt, &err) != WX_OK))) {
        fprintf(stderr, "layer %d: %s\n", layer, err.message);
        return false;
    }
    return true;
}

// Whether the layer holds no crossing at texel (i, j): the background's values.
static bool layer_empty_at(const maps4 *m, int i, int j)
{
    bool empty = isinf(at(&m->depth, 0, i, j)) && at(&m->depth, 0, i, j) > 0;
    for (int q = 0; q < 3; ++q) {
        empty = empty && at(&m->normal, q, i, j) == 0.0f && at(&m->impact, q, i, j) == 0.0f &&
                at(&m->dirt, q, i, j) == 0.0f;
    }
    return empty;
}

static void ensure_normal(const maps4 *m, int i, int j, float x, float y, float z)
{
    ENSURE_NEAR(at(&m->normal, 0, i, j), x, 1e-3);
    ENSURE_NEAR(at(&m->normal, 1, i, j), y, 1e-3);
    ENSURE_NEAR(at(&m->normal, 2, i, j), z, 1e-3);
}

// Box [-1,1]^3 seen from (0,0,5) with 4 layers: layer 0 the front face (d 4,
// normal +z, towards the camera), layer 1 the back face (d 6, normal -z: out
// of the box, away from the camera), layers 2 and 3 nothing. Each face's
// initial dirt is stored once, in the layer that holds it.
static void check_box_layers(const char *file, const char *test)
{
    const float density = 2.0f;
    wx_scene s;
    scene_begin(&s);
    const float eye[3] = { 0, 0, 5 };
    add_camera(&s, "front", eye, ORIGIN, UP_Y, 4, 4, 64, 64, false)->layers = 4;
    add_surface(add_mesh(&s, data_path(file), 30), "*", 0.5f, 0.25f, density, 0.75f, 0.125f);
    wx_run_def o;
    options_for(&o, test);
    wx_error err = { 0 };
    wx_result r = wx_bake_scene(&s, &o, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    maps4 m[4];
    for (int l = 0; l < 4; ++l) {
        ENSURE(read_layer_maps(&s.cameras[0], l, &m[l]));
    }
    const double texel_area = (4.0 / 64) * (4.0 / 64);
    const int texels[][2] = { { 32, 32 }, { 16, 16 }, { 47, 47 }, { 16, 40 }, { 47, 20 } };
    for (size_t k = 0; k < sizeof texels / sizeof texels[0]; ++k) {
        int i = texels[k][0], j = texels[k][1];
        ENSURE_NEAR(at(&m[0].depth, 0, i, j), 4.0, 1e-4);
        ensure_normal(&m[0], i, j, 0, 0, 1);
        ENSURE_NEAR(at(&m[1].depth, 0, i, j), 6.0, 1e-4);
        ensure_normal(&m[1], i, j, 0, 0, -1);
        for (int l = 0; l < 2; ++l) {
            ENSURE_NEAR(at(&m[l].impact, 0, i, j), 0.5, 1e-6);
            ENSURE_NEAR(at(&m[l].impact, 1, i, j), 0.25, 1e-6);
            ENSURE_NEAR(at(&m[l].dirt, 0, i, j), density * texel_area, 1e-7);
            ENSURE_NEAR(at(&m[l].dirt, 1, i, j), 0.75, 1e-6);
            ENSURE_NEAR(at(&m[l].dirt, 2, i, j), 0.125, 1e-6);
        }
        ENSURE(layer_empty_at(&m[2], i, j));
        ENSURE(layer_empty_at(&m[3], i, j));
    }
    for (int l = 0; l < 4; ++l) {
        ENSURE(layer_empty_at(&m[l], 15, 32));
        ENSURE(layer_empty_at(&m[l], 32, 48));
    }
    // Each face's dirt, stored once: density x area 4 (the side faces are seen edge-on).
    ENSURE_NEAR(plane_sum(&m[0].dirt, 0), density * 4.0, 1e-4);
    ENSURE_NEAR(plane_sum(&m[1].dirt, 0), density * 4.0, 1e-4);
    for (int l = 0; l < 4; ++l) {
        free_maps(&m[l]);
    }
    scene_end(&s);
}

TEST(layers_box_back_face_points_out)
{
    check_box_layers("bake_box.obj", "layers_box");
}

TEST(layers_box_wound_inwards_points_out)
{
    // The import turns a closed mesh wound inwards outwards: the same layers.
    check_box_layers("bake_box_flipped.obj", "layers_box_flipped");
}

// The box [x0,x1] x [y0,y1] x [z0,z1] as an OBJ in the test folder, faces
// counter-clockwise seen from outside.
static const char *write_box(const char *name, float x0, float x1, float y0, float y1, float z0,
                             float z1)
{
    char text[1024];
    snprintf(text, sizeof text,
             "v %g %g %g\nv %g %g %g\nv %g %g %g\nv %g %g %g\n"
             "v %g %g %g\nv %g %g %g\nv %g %g %g\nv %g %g %g\n"
             "f 5 6 7 8\nf 2 1 4 3\nf 6 2 3 7\nf 1 5 8 4\nf 8 7 3 4\nf 1 2 6 5\n",
             x0, y0, z0, x1, y0, z0, x1, y1, z0, x0, y1, z0, x0, y0, z1, x1, y0, z1, x1, y1, z1,
             x0, y1, z1);
    return ensure_write_file(ensure_tmpdir(), name, text);
}

TEST(layers_pane_one_millimetre_before_a_wall)
{
    // A pane (one quad, absorption 0.9) at z = 0.001 over x, y in [-0.5, 0.5],
    // before a wall box (absorption 0.1) x, y in [-1, 1], z in [-0.2, 0], seen
    // from 30 m: behind the pane, layer 0 is the pane, layer 1 the wall 1 mm
    // farther, layer 2 the wall's back face (normal -z). Both start with dirt 1
    // per square metre, stored once: 1 on the pane, 1 on the wall behind it
    // (the layer whose surface the point is on owns it, though the pane's
    // layer sees it within its depth tolerance), 3 on the rest of the wall's
    // front, 4 on its back.
    wx_scene s;
    scene_begin(&s);
    const float eye[3] = { 0, 0, 30 };
    add_camera(&s, "front", eye, ORIGIN, UP_Y, 4, 4, 64, 64, false)->layers = 4;
    const char *pane = ensure_write_file(
        ensure_tmpdir(), "pane.obj",
        "v -0.5 -0.5 0.001\nv 0.5 -0.5 0.001\nv 0.5 0.5 0.001\nv -0.5 0.5 0.001\nf 1 2 3 4\n");
    add_surface(add_mesh(&s, pane, 30), "*", 0.9f, 0, 1, 0, 0);
    add_surface(add_mesh(&s, write_box("wall.obj", -1, 1, -1, 1, -0.2f, 0), 40), "*", 0.1f, 0, 1,
                0, 0);
    wx_run_def o;
    options_for(&o, "layers_pane");
    wx_error err = { 0 };
    ENSURE(wx_bake_scene(&s, &o, &err) == WX_OK);
    maps4 m[4];
    for (int l = 0; l < 4; ++l) {
        ENSURE(read_layer_maps(&s.cameras[0], l, &m[l]));
    }
    // The pane covers texels 24..39, the wall 16..47.
    const int behind_pane[][2] = { { 32, 32 }, { 24, 24 }, { 39, 39 }, { 25, 38 } };
    for (size_t k = 0; k < sizeof behind_pane / sizeof behind_pane[0]; ++k) {
        int i = behind_pane[k][0], j = behind_pane[k][1];
        ENSURE_NEAR(at(&m[0].depth, 0, i, j), 29.999, 1e-4);
        ENSURE_NEAR(at(&m[0].impact, 0, i, j), 0.9, 1e-6);
        ensure_normal(&m[0], i, j, 0, 0, 1);
        ENSURE_NEAR(at(&m[1].depth, 0, i, j), 30.0, 1e-4);
        ENSURE_NEAR(at(&m[1].depth, 0, i, j) - at(&m[0].depth, 0, i, j), 0.001, 1e-4);
        ENSURE_NEAR(at(&m[1].impact, 0, i, j), 0.1, 1e-6);
        ensure_normal(&m[1], i, j, 0, 0, 1);
        ENSURE_NEAR(at(&m[2].depth, 0, i, j), 30.2, 1e-4);
        ensure_normal(&m[2], i, j, 0, 0, -1);
        ENSURE(layer_empty_at(&m[3], i, j));
    }
    // Beside the pane: the wall's two faces.
    ENSURE_NEAR(at(&m[0].depth, 0, 20, 32), 30.0, 1e-4);
    ENSURE_NEAR(at(&m[0].impact, 0, 20, 32), 0.1, 1e-6);
    ENSURE_NEAR(at(&m[1].depth, 0, 20, 32), 30.2, 1e-4);
    ensure_normal(&m[1], 20, 32, 0, 0, -1);
    ENSURE(layer_empty_at(&m[2], 20, 32));
    double pane_dirt = 0.0, behind_dirt = 0.0;
    for (int j = 24; j <= 39; ++j) {
        for (int i = 24; i <= 39; ++i) {
            pane_dirt += at(&m[0].dirt, 0, i, j);
            behind_dirt += at(&m[1].dirt, 0, i, j);
        }
    }
    ENSURE_NEAR(pane_dirt, 1.0, 1e-3);
    ENSURE_NEAR(behind_dirt, 1.0, 1e-3);
    ENSURE_NEAR(plane_sum(&m[0].dirt, 0), 4.0, 1e-3);
    ENSURE_NEAR(plane_sum(&m[1].dirt, 0), 1.0 + 4.0 - 1.0, 1e-3);
    ENSURE_NEAR(plane_sum(&m[1].dirt, 0) + plane_sum(&m[2].dirt, 0), 5.0, 1e-3);
    for (int l = 0; l < 4; ++l) {
        free_maps(&m[l]);
    }
    scene_end(&s);
}

TEST(layers_sill_underside_points_down)
{
    // A sill-like slab x in [-1, 1], y in [0.9, 1], z in [-0.25, 0.25] seen from
    // above: layer 0 its top (d 4, normal +y), layer 1 its underside (d 4.1,
    // normal -y), which holds the underside's initial dirt.
    const float density = 1.0f;
    wx_scene s;
    scene_begin(&s);
    const float eye[3] = { 0, 5, 0 }, up[3] = { 0, 0, -1 };
    add_camera(&s, "top", eye, ORIGIN, up, 4, 4, 64, 64, false)->layers = 2;
    add_surface(add_mesh(&s, write_box("sill.obj", -1, 1, 0.9f, 1, -0.25f, 0.25f), 30), "*", 0, 0,
                density, 0, 0);
    wx_run_def o;
    options_for(&o, "layers_sill");
    wx_error err = { 0 };
    ENSURE(wx_bake_scene(&s, &o, &err) == WX_OK);
    maps4 top, under;
    ENSURE(read_layer_maps(&s.cameras[0], 0, &top));
    ENSURE(read_layer_maps(&s.cameras[0], 1, &under));
    const double texel_area = (4.0 / 64) * (4.0 / 64);
    ENSURE_NEAR(at(&top.depth, 0, 32, 32), 4.0, 1e-4);
    ensure_normal(&top, 32, 32, 0, 1, 0);
    ENSURE_NEAR(at(&under.depth, 0, 32, 32), 4.1, 1e-4);
    ensure_normal(&under, 32, 32, 0, -1, 0);
    ENSURE_NEAR(at(&under.dirt, 0, 32, 32), density * texel_area, 1e-7);
    // Top and underside each 2 x 0.5 (edges on texel borders).
    ENSURE_NEAR(plane_sum(&top.dirt, 0), density * 1.0, 1e-4);
    ENSURE_NEAR(plane_sum(&under.dirt, 0), density * 1.0, 1e-4);
    free_maps(&top);
    free_maps(&under);
    scene_end(&s);
}

TEST(layers_drop_the_contact_of_two_slabs_lying_on_each_other)
{
    // Two slabs x, z in [-1, 1] lying on each other (y 1..1.2 and 1.2..1.4)
    // over a floor (y -0.2..0), seen from above with 3 layers: the upper
    // slab's underside and the lower one's top meet at y 1.2 with no free
    // space between (a contact: dropped), so layer 0 is the pair's top (d 3.6,
    // normal +y), layer 1 its underside (d 4, normal -y) and layer 2 the floor
    // (d 5, normal +y), which the contact's two crossings would hide. Beside
    // them a pair 1 cm apart (x in [1.25, 1.75]) keeps its gap: its upper
    // slab's underside (d 3.79) and lower slab's top (d 3.8). A contact gives
    // way only where the crossings outnumber the layers.
    const float density = 1.0f;
    wx_scene s;
    scene_begin(&s);
    const float eye[3] = { 0, 5, 0 }, up[3] = { 0, 0, -1 };
    add_camera(&s, "top", eye, ORIGIN, up, 4, 4, 64, 64, false)->layers = 3;
    add_camera(&s, "top6", eye, ORIGIN, up, 4, 4, 64, 64, false)->layers = 6;
    add_surface(add_mesh(&s, write_box("floor.obj", -3, 3, -0.2f, 0, -3, 3), 30), "*", 0, 0,
                density, 0, 0);
    add_surface(add_mesh(&s, write_box("lower.obj", -1, 1, 1, 1.2f, -1, 1), 31), "*", 0, 0,
                density, 0, 0);
    add_surface(add_mesh(&s, write_box("upper.obj", -1, 1, 1.2f, 1.4f, -1, 1), 32), "*", 0, 0,
                density, 0, 0);
    add_surface(add_mesh(&s, write_box("gap_lower.obj", 1.25f, 1.75f, 1, 1.2f, -1, 1), 33), "*",
                0, 0, density, 0, 0);
    add_surface(add_mesh(&s, write_box("gap_upper.obj", 1.25f, 1.75f, 1.21f, 1.4f, -1, 1), 34),
                "*", 0, 0, density, 0, 0);
    wx_run_def o;
    options_for(&o, "layers_contact");
    wx_error err = { 0 };
    ENSURE(wx_bake_scene(&s, &o, &err) == WX_OK);
    maps4 m[3];
    for (int l = 0; l < 3; ++l) {
        ENSURE(read_layer_maps(&s.cameras[0], l, &m[l]));
    }
    const double texel_area = (4.0 / 64) * (4.0 / 64);
    // Texels 16..47 lie over the touching pair, 52..59 over the pair with a gap.
    const int over_pair[][2] = { { 32, 32 }, { 16, 16 }, { 47, 47 }, { 20, 40 } };
    for (size_t k = 0; k < sizeof over_pair / sizeof over_pair[0]; ++k) {
        int i = over_pair[k][0], j = over_pair[k][1];
        ENSURE_NEAR(at(&m[0].depth, 0, i, j), 3.6, 1e-4);
        ensure_normal(&m[0], i, j, 0, 1, 0);
        ENSURE_NEAR(at(&m[1].depth, 0, i, j), 4.0, 1e-4);
        ensure_normal(&m[1], i, j, 0, -1, 0);
        ENSURE_NEAR(at(&m[1].dirt, 0, i, j), density * texel_area, 1e-7);
        ENSURE_NEAR(at(&m[2].depth, 0, i, j), 5.0, 1e-4);
        ensure_normal(&m[2], i, j, 0, 1, 0);
        ENSURE_NEAR(at(&m[2].dirt, 0, i, j), density * texel_area, 1e-7);
    }
    const int over_gap[][2] = { { 56, 32 }, { 52, 16 }, { 59, 47 } };
    for (size_t k = 0; k < sizeof over_gap / sizeof over_gap[0]; ++k) {
        int i = over_gap[k][0], j = over_gap[k][1];
        ENSURE_NEAR(at(&m[0].depth, 0, i, j), 3.6, 1e-4);
        ENSURE_NEAR(at(&m[1].depth, 0, i, j), 3.79, 1e-4);
        ensure_normal(&m[1], i, j, 0, -1, 0);
        ENSURE_NEAR(at(&m[2].depth, 0, i, j), 3.8, 1e-4);
        ensure_normal(&m[2], i, j, 0, 1, 0);
    }
    // Beside both: the floor's top and underside, nothing after them.
    ENSURE_NEAR(at(&m[0].depth, 0, 8, 32), 5.0, 1e-4);
    ENSURE_NEAR(at(&m[1].depth, 0, 8, 32), 5.2, 1e-4);
    ensure_normal(&m[1], 8, 32, 0, -1, 0);
    ENSURE(layer_empty_at(&m[2], 8, 32));
    for (int l = 0; l < 3; ++l) {
        free_maps(&m[l]);
    }
    // With room for every crossing (6 layers) the contact stays, sealing the
    // two faces: 3.6, 3.8 (leaving), 3.8 (entering), 4, 5, 5.2.
    maps4 all[6];
    const double depths[6] = { 3.6, 3.8, 3.8, 4.0, 5.0, 5.2 };
    const float ys[6] = { 1, -1, 1, -1, 1, -1 };
    for (int l = 0; l < 6; ++l) {
        ENSURE(read_layer_maps(&s.cameras[1], l, &all[l]));
        ENSURE_NEAR(at(&all[l].depth, 0, 32, 32), depths[l], 1e-4);
        ensure_normal(&all[l], 32, 32, 0, ys[l], 0);
        free_maps(&all[l]);
    }
    scene_end(&s);
}

// Whether two files hold the same bytes.
static bool same_file(const char *a, const char *b)
{
    FILE *fa = fopen(a, "rb"), *fb = fopen(b, "rb");
    bool same = fa != NULL && fb != NULL;
    while (same) {
        int ca = getc(fa), cb = getc(fb);
        same = ca == cb;
        if (ca == EOF) {
            break;
        }
    }
    if (fa != NULL) {
        fclose(fa);
    }
    if (fb != NULL) {
        fclose(fb);
    }
    return same;
}

// The box seen from (0,0,5), and a quad at z = 2 facing away from the camera
// (-z) before its left part: where the quad is, the first crossing is
// back-facing. An output camera asks for layers too. Baked with `layers` on
// the input camera into out/TEST.
static void bake_mixed(wx_scene *s, wx_run_def *o, const char *test, int layers)
{
    scene_begin(s);
    const float eye[3] = { 0, 0, 5 };
    add_camera(s, "front", eye, ORIGIN, UP_Y, 4, 4, 64, 64, false)->layers = layers;
    add_camera(s, "shot", eye, ORIGIN, UP_Y, 4, 4, 32, 32, true)->layers = layers;
    add_surface(add_mesh(s, data_path("bake_box.obj"), 30), "*", 0.5f, 0.25f, 2.0f, 0.75f, 0.5f);
    const char *away = ensure_write_file(ensure_tmpdir(), "away.obj",
                                         "v -1.8 -0.5 2\nv -0.6 -0.5 2\nv -0.6 0.5 2\n"
                                         "v -1.8 0.5 2\nf 4 3 2 1\n");
    add_surface(add_mesh(s, away, 40), "*", 0.125f, 0.5f, 3.0f, 0.25f, 0.25f);
    options_for(o, test);
    wx_error err = { 0 };
    wx_result r = wx_bake_scene(s, o, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
}

TEST(layers_one_is_today_and_layer_zero_of_four_matches_it)
{
    wx_scene zero, one, four;
    wx_run_def o0, o1, o4;
    bake_mixed(&zero, &o0, "layers_0", 0);
    bake_mixed(&one, &o1, "layers_1", 1);
    bake_mixed(&four, &o4, "layers_4", 4);
    // layers="1" is the default's bytes, file by file.
    for (int c = 0; c < 2; ++c) {
        const wx_scene_camera *a = &zero.cameras[c], *b = &one.cameras[c];
        ENSURE(same_file(a->depth_path, b->depth_path));
        ENSURE(same_file(a->normal_path, b->normal_path));
        if (c == 0) {
            ENSURE(same_file(a->impact_path, b->impact_path));
            ENSURE(same_file(a->dirt_path, b->dirt_path));
        }
    }
    // The files name every layer's channels; the output camera has one layer.
    wx_image h;
    wx_error err;
    ENSURE(wx_exr_read_header(four.cameras[0].depth_path, &h, &err) == WX_OK);
    ENSURE(h.channel_count == 4);
    ENSURE(wx_exr_read_header(four.cameras[0].dirt_path, &h, &err) == WX_OK);
    ENSURE(h.channel_count == 12);
    int found = 0;
    for (int k = 0; k < h.channel_count; ++k) {
        found += strcmp(h.channel_names[k], "layer1.R") == 0 ||
                 strcmp(h.channel_names[k], "layer3.B") == 0;
    }
    ENSURE(found == 2);
    ENSURE(wx_exr_read_header(four.cameras[0].normal_path, &h, &err) == WX_OK);
    ENSURE(h.channel_count == 12);
    ENSURE(wx_exr_read_header(four.cameras[1].depth_path, &h, &err) == WX_OK);
    ENSURE(h.channel_count == 1);
    ENSURE(same_file(four.cameras[1].depth_path, one.cameras[1].depth_path));
    ENSURE(same_file(four.cameras[1].normal_path, one.cameras[1].normal_path));
    // Layer 0 of four layers is the one-layer bake but for the sign of the
    // normals where the first crossing faces away from the camera (the quad).
    maps4 a, b;
    ENSURE(read_maps(&one.cameras[0], &a));
    ENSURE(read_layer_maps(&four.cameras[0], 0, &b));
    size_t texels = (size_t)a.depth.width * (size_t)a.depth.height, away = 0, mismatch = 0;
    for (size_t t = 0; t < texels; ++t) {
        mismatch += memcmp(&a.depth.channels[0][t], &b.depth.channels[0][t], sizeof(float)) != 0;
        for (int q = 0; q < 3; ++q) {
            mismatch += a.impact.channels[q][t] != b.impact.channels[q][t];
            mismatch += a.dirt.channels[q][t] != b.dirt.channels[q][t];
        }
        bool flipped = b.normal.channels[2][t] < 0.0f; // faces away from the eye
        away += flipped;
        for (int q = 0; q < 3; ++q) {
            float want = flipped ? -b.normal.channels[q][t] : b.normal.channels[q][t];
            mismatch += a.normal.channels[q][t] != want;
        }
    }
    ENSURE(mismatch == 0);
    // The quad covers x in [-1.8, -0.6] at z = 2, y in [-0.5, 0.5]: 19 x 16 texels.
    ENSURE(away == 19 * 16);
    ENSURE_NEAR(at(&b.normal, 2, 8, 32), -1.0, 1e-3);
    ENSURE_NEAR(at(&b.impact, 0, 8, 32), 0.125, 1e-6);
    free_maps(&a);
    free_maps(&b);
    scene_end(&zero);
    scene_end(&one);
    scene_end(&four);
}

TEST(layers_share_initial_dirt_with_other_cameras)
{
    // The box with density 1 seen from the front with 2 layers and from the top
    // with one: the front camera's layers hold the front and back faces, the
    // top camera the top face (which it sees head-on), each once; nobody sees
    // the bottom and the sides.
    const float density = 1.0f;
    wx_scene s;
    scene_begin(&s);
    const float eye_front[3] = { 0, 0, 5 }, eye_top[3] = { 0, 5, 0 }, up_top[3] = { 0, 0, -1 };
    add_camera(&s, "front", eye_front, ORIGIN, UP_Y, 4, 4, 64, 64, false)->layers = 2;
    add_camera(&s, "top", eye_top, ORIGIN, up_top, 4, 4, 64, 64, false);
    add_surface(add_mesh(&s, data_path("bake_box.obj"), 30), "*", 0, 0, density, 0, 0);
    wx_run_def o;
    options_for(&o, "layers_dirt_shared");
    wx_error err = { 0 };
    ENSURE(wx_bake_scene(&s, &o, &err) == WX_OK);
    maps4 front0, front1, top;
    ENSURE(read_layer_maps(&s.cameras[0], 0, &front0));
    ENSURE(read_layer_maps(&s.cameras[0], 1, &front1));
    ENSURE(read_maps(&s.cameras[1], &top));
    ENSURE_NEAR(plane_sum(&front0.dirt, 0), density * 4.0, 1e-4);
    ENSURE_NEAR(plane_sum(&front1.dirt, 0), density * 4.0, 1e-4);
    ENSURE_NEAR(plane_sum(&top.dirt, 0), density * 4.0, 1e-4);
    free_maps(&front0);
    free_maps(&front1);
    free_maps(&top);
    scene_end(&s);
}

TEST(layers_hold_every_substance_the_surface_and_the_area)
{
    // Two substances, a <Surface> with rules of its own (so the surface record)
    // and a Grow (so Grow's area): each layer of the box carries them all,
    // named "layer1.water.amount"... .
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/layers_substances", ensure_tmpdir());
    mkdir(dir, 0777);
    char *box = ensure_read_file(data_path("bake_box.obj"));
    ensure_write_file(dir, "box.obj", box != NULL ? box : "");
    free(box);
    const char *path = ensure_write_file(
        dir, "scene.xml",
        "<?xml version=\"1.0\"?>\n<Weathering>\n"
        "  <Substances><Substance name=\"water\"/><Substance name=\"dirt\"/></Substances>\n"
        "  <Collider><ProjectedMaps>\n"
        "    <Ortho cameraName=\"front\" layers=\"2\"><View eye=\"0 0 5\" target=\"0 0 0\" "
        "up=\"0 1 0\" width=\"4\" height=\"4\" resolution=\"64\"/></Ortho>\n"
        "    <Ortho cameraName=\"shot\" out=\"true\"><View eye=\"0 0 5\" target=\"0 0 0\" "
        "up=\"0 1 0\" width=\"4\" height=\"4\" resolution=\"32\"/>\n"
        "      <OutputMap file=\"mask.exr\" width=\"32\" height=\"32\"/></Ortho>\n"
        "  </ProjectedMaps></Collider>\n"
        "  <Geometry><Mesh file=\"box.obj\">\n"
        "    <Surface material=\"*\" absorption=\"0.25\" bounce=\"0.5\" dirt=\"2\" deposit=\"0.75\" "
        "erosion=\"0.125\">\n"
        "      <Exchange substance=\"water\" initial=\"3\" deposit=\"0.5\" erosion=\"0.25\"/>\n"
        "      <Grow substance=\"water\" amount=\"0.1\"/>\n"
        "    </Surface>\n"
        "  </Mesh></Geometry>\n</Weathering>\n");
    wx_scene s;
    wx_error err = { 0 };
    wx_result r = wx_scene_load(path, &s, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    ENSURE(s.cameras[0].layers == 2);
    wx_run_def o;
    options_for(&o, "layers_substances");
    r = wx_bake_scene(&s, &o, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    static const char *const names[] = { "water.amount", "water.deposit", "water.erosion",
                                         "dirt.amount",  "dirt.deposit",  "dirt.erosion",
                                         "surface",      "area" };
    const double texel_area = (4.0 / 64) * (4.0 / 64);
    const double want[] = { 3 * texel_area, 0.5, 0.25, 2 * texel_area, 0.75, 0.125, 1,
                            texel_area };
    for (int l = 0; l < 2; ++l) {
        char layered[8][WX_NAME_MAX];
        const char *wanted[8];
        for (int k = 0; k < 8; ++k) {
            ENSURE(wx_layer_channel(layered[k], l, names[k]));
            wanted[k] = layered[k];
        }
        wx_image dirt;
        r = wx_exr_read(s.cameras[0].dirt_path, wanted, 8, &dirt, &err);
        if (r != WX_OK) {
            fprintf(stderr, "%s\n", err.message);
        }
        ENSURE(r == WX_OK);
        for (int k = 0; k < 8; ++k) {
            ENSURE_NEAR(at(&dirt, k, 32, 32), want[k], 1e-6);
            ENSURE(at(&dirt, k, 5, 32) == 0.0f); // background
        }
        ENSURE_NEAR(plane_sum(&dirt, 0), 3 * 4.0, 1e-4);
        wx_image_free(&dirt);
    }
    scene_end(&s);
}

int main(void)
{
    RUN(sphere_depth_and_normal);
    RUN(box_faces);
    RUN(flipped_winding_still_faces_the_camera);
    RUN(top_scanline_is_highest_v);
    RUN(two_materials_two_impacts);
    RUN(unmatched_material_lists_names);
    RUN(vertex_colours_to_impact_and_dirt);
    RUN(vertex_colours_missing_is_an_error);
    RUN(initial_dirt_goes_to_the_most_head_on_camera);
    RUN(initial_dirt_one_camera_divides_by_cosine);
    RUN(initial_dirt_tie_goes_to_the_first_camera);
    RUN(initial_dirt_hidden_from_head_on_camera);
    RUN(output_camera_gets_depth_and_normal_only);
    RUN(missing_and_unsupported_mesh_files);
    RUN(no_geometry_is_an_error);
    RUN(maps_beyond_the_renderer_are_refused);
    RUN(scene_file_bakes_maps_the_scene_reads_back);
    RUN(warns_about_geometry_outside_the_frame_or_behind_the_eye);
    RUN(cli_bake_writes_the_maps_and_refuses_a_bad_mesh);
    RUN(layers_box_back_face_points_out);
    RUN(layers_box_wound_inwards_points_out);
    RUN(layers_pane_one_millimetre_before_a_wall);
    RUN(layers_sill_underside_points_down);
    RUN(layers_drop_the_contact_of_two_slabs_lying_on_each_other);
    RUN(layers_one_is_today_and_layer_zero_of_four_matches_it);
    RUN(layers_share_initial_dirt_with_other_cameras);
    RUN(layers_hold_every_substance_the_surface_and_the_area);
    return ensure_summary();
}
