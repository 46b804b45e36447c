// surface_probe.c: where the collider puts a model's surface, against the
// smooth surface the bake draws (issue 25, docs/performance.md, "The collision
// surface measured against the model").
//
//   make build/tools/surface_probe
//   build/tools/surface_probe SCENE.xml RUN_DIR OUT.txt [SAMPLES]
//
// Reads the scene, the input cameras' maps a run or a bake left in RUN_DIR,
// and builds the collider as the simulation does. Then it draws SAMPLES points
// per square input texel (default 0.5) on every mesh's smooth surface (the
// Phong surface of wx_mesh_phong_point, which the bake draws in pieces of
// about four texels), and for each one sweeps a segment along the surface's
// normal, from four texels outside it to four texels inside, as a particle
// would. Each line of OUT.txt is one point:
//
//   x y z  nx ny nz  distance  camera  vetoes
//
// `distance` is where the collider met the segment, along the normal from the
// point, in texels of the first input camera (> 0: outside the surface; nan:
// no hit); `camera` the input camera that recorded the hit (-1: none); for a
// point met more than a quarter of a texel inside, `vetoes` the input cameras
// (bit c for camera c) that call a point a fifth of a texel inside the surface
// free, which is how the collider lets a particle in there (0 otherwise).
// Points are drawn from a fixed sequence, triangle by triangle, so the same
// mesh turned gives the same points in the same order: two runs' files
// compare line by line (tests/tools/diagnosis/surface_probe.py).
//
// It prints a summary: the points, the distance's mean and RMS, and how many
// lie more than a quarter of a texel inside (notches) or outside (bumps).
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/maps_file.h"
#include "io/mesh_import.h"
#include "io/scene_xml.h"
#include "model/maps.h"
#include "model/mesh.h"
#include "model/scene.h"
#include "pipeline/outputs.h"
#include "pipeline/pipeline.h"
#include "sim/collider.h"
#include "sim/particles.h"

typedef struct probe_totals {
    long long points, hits, notches, bumps;
    double sum, sum2;
} probe_totals;

// The tests' generator (tests/bench/bench_embree.c): the particles' mixer on
// a Weyl sequence, 53 bits of it.
static double next_uniform(uint64_t *state)
{
    *state = wx_mix64(*state + UINT64_C(0x9e3779b97f4a7c15));
    return (double)(*state >> 11) * (1.0 / 9007199254740992.0);
}

// The cameras that call world point q free (inside their frame and not
// behind any of their surfaces there).
static unsigned free_for(const wx_collider *collider, const float q[3])
{
    unsigned mask = 0;
    for (int c = 0; c < collider->camera_count; ++c) {
        const wx_collider_camera *cam = &collider->cameras[c];
        double X = q[0] * cam->mx[0] + q[1] * cam->mx[1] + q[2] * cam->mx[2] + cam->mx[3];
        double Y = q[0] * cam->my[0] + q[1] * cam->my[1] + q[2] * cam->my[2] + cam->my[3];
        double D = q[0] * cam->md[0] + q[1] * cam->md[1] + q[2] * cam->md[2] + cam->md[3];
        if (X >= 0.0 && Y >= 0.0 && X < cam->width && Y < cam->height &&
            !wx_collider_camera_may_collide(collider, c, X, Y, D)) {
            mask |= 1u << c;
        }
    }
    return mask;
}

// Probes one mesh's smooth surface into `out`.
static void probe_mesh(const wx_collider *collider, const wx_mesh_data *mesh, double samples,
                       uint64_t *state, FILE *out, probe_totals *totals)
{
    double texel = collider->cameras[0].texel_ws;
    for (int64_t t = 0; t < mesh->triangle_count; ++t) {
        const uint32_t *ix = mesh->indices + 3 * t;
        const float *a = mesh->positions + 3 * ix[0];
        const float *b = mesh->positions + 3 * ix[1];
        const float *c = mesh->positions + 3 * ix[2];
        double e1[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
        double e2[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
        double cx = e1[1] * e2[2] - e1[2] * e2[1], cy = e1[2] * e2[0] - e1[0] * e2[2],
               cz = e1[0] * e2[1] - e1[1] * e2[0];
        double area = 0.5 * sqrt(cx * cx + cy * cy + cz * cz);
        long n = (long)(area / (texel * texel) * samples) + 1;
        for (long s = 0; s < n; ++s) {
            double u = next_uniform(state), v = next_uniform(state);
            if (u + v > 1.0) {
                u = 1.0 - u;
                v = 1.0 - v;
            }
            double w[3] = { 1.0 - u - v, u, v }, p[3];
            float nn[3];
            wx_mesh_phong_point(mesh, t, w, p);
            wx_mesh_phong_normal(mesh, t, w, nn);
            float p0[3], p1[3];
            for (int k = 0; k < 3; ++k) {
                p[k] += mesh->origin[k];
                p0[k] = (float)(p[k] + 4.0 * texel * nn[k]);
                p1[k] = (float)(p[k] - 4.0 * texel * nn[k]);
            }
            wx_hit hit;
            memset(&hit, 0, sizeof hit);
            double distance = NAN;
            int camera = -1;
            unsigned vetoes = 0;
            if (wx_collider_sweep(collider, p0, p1, &hit)) {
                distance = 0.0;
                for (int k = 0; k < 3; ++k) {
                    distance += (hit.point[k] - p[k]) * nn[k];
                }
                distance /= texel;
                camera = hit.camera;
                totals->hits++;
                totals->sum += distance;
                totals->sum2 += distance * distance;
                totals->notches += distance < -0.25;
                totals->bumps += distance > 0.25;
                if (distance < -0.25) {
                    float q[3];
                    for (int k = 0; k < 3; ++k) {
                        q[k] = (float)(p[k] - 0.2 * texel * nn[k]);
                    }
                    vetoes = free_for(collider, q);
                }
            }
            totals->points++;
            fprintf(out, "%.6f %.6f %.6f %.5f %.5f %.5f %.5f %d %u\n", p[0], p[1], p[2], nn[0],
                    nn[1], nn[2], distance, camera, vetoes);
        }
    }
}

int main(int argc, char **argv)
{
    if (argc < 4 || argc > 5) {
        fprintf(stderr, "usage: surface_probe SCENE.xml RUN_DIR OUT.txt [SAMPLES]\n");
        return 2;
    }
    double samples = argc > 4 ? atof(argv[4]) : 0.5;
    if (!(samples > 0.0) || samples > 64.0) {
        fprintf(stderr, "surface_probe: SAMPLES must lie in (0, 64]\n");
        return 2;
    }
    wx_error err;
    wx_scene scene;
    if (wx_scene_load(argv[1], &scene, &err) != WX_OK) {
        fprintf(stderr, "surface_probe: %s\n", err.message);
        return 1;
    }
    wx_run_def opts = wx_default_run_def(&scene);
    snprintf(opts.out_dir, sizeof opts.out_dir, "%s", argv[2]);
    if (wx_use_baked_maps(&scene, &opts, &err) != WX_OK) {
        fprintf(stderr, "surface_probe: %s\n", err.message);
        wx_scene_free(&scene);
        return 1;
    }
    wx_camera cams[WX_MAX_INPUT_CAMERAS];
    wx_maps maps[WX_MAX_INPUT_CAMERAS];
    int count = 0;
    int status = 0;
    for (int c = 0; c < scene.camera_count && status == 0; ++c) {
        const wx_scene_camera *sc = &scene.cameras[c];
        if (sc->is_output || count == WX_MAX_INPUT_CAMERAS) {
            continue;
        }
        if (wx_maps_load_layers(&maps[count], WX_MAPS_DEPTH | WX_MAPS_NORMAL | WX_MAPS_IMPACT, 2,
                                &scene, sc->layers, sc->depth_path, sc->normal_path,
                                sc->impact_path, NULL, &err) != WX_OK) {
            fprintf(stderr, "surface_probe: %s\n", err.message);
            status = 1;
            break;
        }
        cams[count++] = sc->camera;
    }
    wx_collider collider;
    bool built = false;
    if (status == 0 && count == 0) {
        fprintf(stderr, "surface_probe: %s has no input camera\n", argv[1]);
        status = 1;
    }
    if (status == 0 && wx_collider_init(&collider, cams, maps, count, false, &err) != WX_OK) {
        fprintf(stderr, "surface_probe: %s\n", err.message);
        status = 1;
    }
    built = status == 0;
    FILE *out = status == 0 ? fopen(argv[3], "w") : NULL;
    if (status == 0 && out == NULL) {
        fprintf(stderr, "surface_probe: cannot write %s\n", argv[3]);
        status = 1;
    }
    probe_totals totals = { 0 };
    uint64_t state = 12345;
    for (int i = 0; status == 0 && i < scene.mesh_count; ++i) {
        wx_mesh_data mesh;
        if (wx_mesh_import(scene.meshes[i].path, &mesh, &err) != WX_OK) {
            fprintf(stderr, "surface_probe: %s\n", err.message);
            status = 1;
            break;
        }
        probe_mesh(&collider, &mesh, samples, &state, out, &totals);
        wx_mesh_data_free(&mesh);
    }
    if (out != NULL && fclose(out) != 0) {
        fprintf(stderr, "surface_probe: cannot write %s\n", argv[3]);
        status = 1;
    }
    if (status == 0) {
        double h = totals.hits > 0 ? (double)totals.hits : 1.0;
        printf("points %lld, hit %lld; distance along the normal (texels): mean %+.4f, RMS "
               "%.4f; notches (< -0.25) %lld, bumps (> 0.25) %lld\n",
               totals.points, totals.hits, totals.sum / h, sqrt(totals.sum2 / h), totals.notches,
               totals.bumps);
    }
    if (built) {
        wx_collider_free(&collider);
    }
    for (int c = 0; c < count; ++c) {
        wx_maps_free(&maps[c]);
    }
    wx_scene_free(&scene);
    return status;
}
