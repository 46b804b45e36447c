// sim_fixture.h: hand-built scenes for the simulation tests. Solids are convex
// polyhedra (intersections of half-spaces n.p <= c); fx_render ray-casts them
// from an orthographic camera into in-memory maps (exact depth and normals at
// every texel centre), so every expected answer can be worked out by hand.
#ifndef WX_SIM_FIXTURE_H
#define WX_SIM_FIXTURE_H

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "model/camera.h"
#include "model/maps.h"
#include "model/scene.h"

#define FX_MAX_PLANES 8
#define FX_MAX_SOLIDS  64
#define FX_MAX_CAMERAS 4

typedef struct fx_solid {
    int plane_count;
    float n[FX_MAX_PLANES][3];
    float c[FX_MAX_PLANES];
} fx_solid;

typedef struct fx_world {
    int solid_count;
    fx_solid solids[FX_MAX_SOLIDS];
    float absorption, bounce; ///< impact map
    float dirt, deposit, erosion; ///< dirt map (dirt per texel)
} fx_world;

static inline void fx_plane(fx_solid *s, float nx, float ny, float nz, float c)
{
    float len = sqrtf(nx * nx + ny * ny + nz * nz);
    int k = s->plane_count++;
    s->n[k][0] = nx / len;
    s->n[k][1] = ny / len;
    s->n[k][2] = nz / len;
    s->c[k] = c / len;
}

static inline fx_solid *fx_box(fx_world *w, float x0, float y0, float z0, float x1, float y1,
                               float z1)
{
    fx_solid *s = &w->solids[w->solid_count++];
    memset(s, 0, sizeof *s);
    fx_plane(s, 1, 0, 0, x1);
    fx_plane(s, -1, 0, 0, -x0);
    fx_plane(s, 0, 1, 0, y1);
    fx_plane(s, 0, -1, 0, -y0);
    fx_plane(s, 0, 0, 1, z1);
    fx_plane(s, 0, 0, -1, -z0);
    return s;
}

// Ray o + t*d through a convex solid: the entry distance t0 and plane p0, the
// exit distance t1 and plane p1 (-1: none). False when the ray misses it or
// enters it behind o.
static inline bool fx_cross_solid(const fx_solid *s, const double o[3], const double d[3],
                                  double *t0, int *p0, double *t1, int *p1)
{
    *t0 = -1e30;
    *t1 = 1e30;
    *p0 = *p1 = -1;
    for (int k = 0; k < s->plane_count; ++k) {
        double nd = s->n[k][0] * d[0] + s->n[k][1] * d[1] + s->n[k][2] * d[2];
        double no = s->n[k][0] * o[0] + s->n[k][1] * o[1] + s->n[k][2] * o[2];
        if (fabs(nd) < 1e-12) {
            if (no > s->c[k]) {
                return false;
            }
            continue;
        }
        double t = (s->c[k] - no) / nd;
        if (nd < 0) {
            if (t > *t0) {
                *t0 = t;
                *p0 = k;
            }
        } else if (t < *t1) {
            *t1 = t;
            *p1 = k;
        }
    }
    return *p0 >= 0 && *t0 <= *t1 && *t0 >= 0;
}

// Ray o + t*d against a convex solid: entry distance and the entry plane's normal.
static inline bool fx_hit_solid(const fx_solid *s, const double o[3], const double d[3],
                                double *t_out, float n[3])
{
    double t1;
    int plane, exit;
    if (!fx_cross_solid(s, o, d, t_out, &plane, &t1, &exit)) {
        return false;
    }
    memcpy(n, s->n[plane], sizeof(float) * 3);
    return true;
}

// Renders depth, normal, impact and dirt maps of `world` seen by `cam`.
static inline void fx_render(const wx_camera *cam, const fx_world *world, wx_maps *maps)
{
    int W = cam->width, H = cam->height;
    size_t n = (size_t)W * (size_t)H;
    memset(maps, 0, sizeof *maps);
    maps->width = W;
    maps->height = H;
    maps->depth = malloc(n * sizeof(float));
    maps->normal = calloc(3 * n, sizeof(float));
    maps->impact = malloc(2 * n * sizeof(float));
    maps->dirt = calloc(n, sizeof(float));
    maps->deposit = malloc(n * sizeof(float));
    maps->erosion = malloc(n * sizeof(float));
    float dir[3];
    wx_camera_view_dir(cam, dir);
    double d[3] = { dir[0], dir[1], dir[2] };
    for (int j = 0; j < H; ++j) {
        for (int i = 0; i < W; ++i) {
            size_t t = (size_t)j * (size_t)W + (size_t)i;
            float uvd[3];
            wx_map_texel_center(W, H, i, j, &uvd[0], &uvd[1]);
            uvd[2] = 0.0f;
            float eye[3];
            wx_camera_map_to_world(cam, uvd, eye);
            double o[3] = { eye[0], eye[1], eye[2] };
            double best = INFINITY;
            float normal[3] = { 0, 0, 0 };
            for (int s = 0; s < world->solid_count; ++s) {
                double th;
                float nh[3];
                if (fx_hit_solid(&world->solids[s], o, d, &th, nh) && th < best) {
                    best = th;
                    memcpy(normal, nh, sizeof normal);
                }
            }
            maps->depth[t] = (float)best;
            memcpy(&maps->normal[3 * t], normal, sizeof normal);
            maps->impact[2 * t] = world->absorption;
            maps->impact[2 * t + 1] = world->bounce;
            maps->dirt[t] = isfinite(best) ? world->dirt : 0.0f;
            maps->deposit[t] = world->deposit;
            maps->erosion[t] = world->erosion;
        }
    }
}

/// An orthographic camera looking from `eye` to `target`, `size` metres wide and
/// high, `px` texels a side.
static inline wx_camera fx_camera(float ex, float ey, float ez, float tx, float ty, float tz,
                                  float ux, float uy, float uz, float size, int px)
{
    wx_view view;
    memset(&view, 0, sizeof view);
    view.eye[0] = ex;
    view.eye[1] = ey;
    view.eye[2] = ez;
    view.target[0] = tx;
    view.target[1] = ty;
    view.target[2] = tz;
    view.up[0] = ux;
    view.up[1] = uy;
    view.up[2] = uz;
    view.width_ws = size;
    view.height_ws = size;
    view.width_px = px;
    view.height_px = px;
    wx_camera cam;
    wx_error err;
    if (wx_camera_from_view(&view, &cam, &err) != WX_OK) {
        abort();
    }
    return cam;
}

/// A scene built in memory: the arrays it points to live in the fixture.
typedef struct fx_scene {
    wx_scene scene;
    wx_scene_camera cameras[FX_MAX_CAMERAS];
    wx_maps maps[FX_MAX_CAMERAS];
    wx_field fields[4];
    wx_emitter emitters[4];
} fx_scene;

/// Defaults of docs/design.md section 3, no fields, no emitters, no cameras.
static inline void fx_scene_init(fx_scene *f)
{
    memset(f, 0, sizeof *f);
    wx_scene *s = &f->scene;
    s->bbox_size = 100.0f;
    s->time_step = 0.01;
    s->steps = 1000;
    s->seed = 1;
    s->collider.resilience = 0.5f;
    s->collider.friction = 0.8f;
    s->collider.adherence = 1.0f;
    s->collider.deposit = 1.0f;
    s->collider.erosion = 1.0f;
    s->cameras = f->cameras;
    s->fields = f->fields;
    s->emitters = f->emitters;
    s->output_index = -1;
}

/// Adds an input camera rendering `world`.
static inline void fx_add_camera(fx_scene *f, const char *name, wx_camera cam,
                                 const fx_world *world)
{
    int c = f->scene.camera_count++;
    wx_scene_camera *sc = &f->cameras[c];
    memset(sc, 0, sizeof *sc);
    strncpy(sc->name, name, sizeof sc->name - 1);
    sc->camera = cam;
    f->scene.input_count++;
    fx_render(&cam, world, &f->maps[c]);
}

static inline void fx_gravity(fx_scene *f, float g)
{
    wx_field *field = &f->fields[f->scene.field_count++];
    memset(field, 0, sizeof *field);
    field->kind = WX_FIELD_GRAVITY;
    field->strength = g;
}

static inline void fx_wind(fx_scene *f, float strength, float x, float y, float z)
{
    wx_field *field = &f->fields[f->scene.field_count++];
    memset(field, 0, sizeof *field);
    field->kind = WX_FIELD_WIND;
    field->strength = strength;
    field->dir[0] = x;
    field->dir[1] = y;
    field->dir[2] = z;
}

static inline void fx_turbulence(fx_scene *f, float strength, float frequency, int octaves)
{
    wx_field *field = &f->fields[f->scene.field_count++];
    memset(field, 0, sizeof *field);
    field->kind = WX_FIELD_TURBULENCE;
    field->strength = strength;
    field->frequency = frequency;
    field->octaves = octaves;
}

static inline wx_emitter *fx_emitter(fx_scene *f, wx_emitter_kind kind, float x, float y, float z)
{
    wx_emitter *e = &f->emitters[f->scene.emitter_count++];
    memset(e, 0, sizeof *e);
    e->kind = kind;
    e->center[0] = x;
    e->center[1] = y;
    e->center[2] = z;
    e->radius = kind == WX_EMITTER_HEMISPHERE ? 1.0f : 0.0f;
    e->rate = 1000;
    e->start = 0;
    e->end = 1e30;
    e->speed = 1;
    e->mass = 1;
    e->load[0] = 1;
    e->max_collisions = 100;
    return e;
}

static inline void fx_scene_free(fx_scene *f)
{
    for (int c = 0; c < f->scene.camera_count; ++c) {
        wx_maps_free(&f->maps[c]);
    }
}

#endif
