// sphere_fixture.h: the unit sphere under rain, a scene whose mask is known
// exactly (tests/test_analytic.c, tests/bench/bench_smoothing.c). A UV sphere of
// radius 1 at the origin, seen from above by an input and an output camera of
// 1024 texels over 2.4 m (image up along -Z: row 0 at z = -1.2), absorption 1,
// no force fields. Particles move in straight lines, so the density on the
// surface is known in closed form for the two emitters:
//  - a flat box above the sphere raining straight down: flux N/A through every
//    horizontal plane, so density(n) = (N/A) * max(0, n.y);
//  - a sky dome of radius R aimed at the sphere's foot c = (0, -1, 0): the ray
//    towards c enters the sphere at the point X = n it passes (the foot is on
//    the sphere), the directions are uniform over the upper hemisphere, so
//    density = N/(2 pi) * cos / |X - c|^2 = N / (4 pi sqrt(2 (1 + n.y))).
#ifndef WX_SPHERE_FIXTURE_H
#define WX_SPHERE_FIXTURE_H

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>

#include "ensure.h"
#include "io/exr.h"
#include "model/image.h"

#define SPHERE_PI 3.14159265358979323846

// A UV sphere of radius `radius` with smooth normals, as binary PLY.
static inline bool sphere_write_mesh_scaled(const char *path, int stacks, int slices,
                                            double radius)
{
    FILE *f = fopen(path, "wb");
    if (f == NULL) {
        return false;
    }
    int nv = (stacks + 1) * (slices + 1), nf = 2 * stacks * slices;
    fprintf(f,
            "ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
            "property float y\nproperty float z\nproperty float nx\nproperty float ny\n"
            "property float nz\nelement face %d\nproperty list uchar int vertex_indices\n"
            "end_header\n",
            nv, nf);
    for (int i = 0; i <= stacks; ++i) {
        for (int j = 0; j <= slices; ++j) {
            double th = SPHERE_PI * i / stacks, ph = 2 * SPHERE_PI * j / slices;
            float v[6] = { (float)(sin(th) * cos(ph)), (float)cos(th), (float)(sin(th) * sin(ph)) };
            v[3] = v[0];
            v[4] = v[1];
            v[5] = v[2];
            for (int k = 0; k < 3; ++k) {
                v[k] = (float)(v[k] * radius);
            }
            fwrite(v, sizeof v, 1, f);
        }
    }
    for (int i = 0; i < stacks; ++i) {
        for (int j = 0; j < slices; ++j) {
            int a = i * (slices + 1) + j, b = a + 1, c = a + slices + 1, d = c + 1;
            unsigned char three = 3;
            int t1[3] = { a, c, b }, t2[3] = { b, c, d };
            fwrite(&three, 1, 1, f);
            fwrite(t1, sizeof t1, 1, f);
            fwrite(&three, 1, 1, f);
            fwrite(t2, sizeof t2, 1, f);
        }
    }
    return fclose(f) == 0;
}

// A UV sphere of radius 1 with smooth normals, as binary PLY.
static inline bool sphere_write_mesh(const char *path, int stacks, int slices)
{
    return sphere_write_mesh_scaled(path, stacks, slices, 1.0);
}

// Writes dir/name: the sphere scene with the given <Emitters> content, bounding
// box size, solver time step and steps, and <OutputMap> attributes ("" for the
// adaptive gather).
static inline const char *sphere_write_scene(const char *dir, const char *name,
                                             const char *emitter, double bbox, double time_step,
                                             int steps, const char *output_attrs)
{
    char text[8192];
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Solver>\n"
             "    <BoundingBox size=\"%g\"/>\n"
             "    <Simulation timeStep=\"%g\" steps=\"%d\" seed=\"1\"/>\n"
             "  </Solver>\n"
             "  <Emitters>\n"
             "    %s\n"
             "  </Emitters>\n"
             "  <Collider>\n"
             "    <ProjectedMaps>\n"
             "      <Ortho cameraName=\"top\">\n"
             "        <View eye=\"0 5 0\" target=\"0 0 0\" up=\"0 0 -1\" width=\"2.4\" height=\"2.4\"\n"
             "              resolution=\"1024\"/>\n"
             "      </Ortho>\n"
             "      <Ortho cameraName=\"shot\" out=\"true\">\n"
             "        <View eye=\"0 5 0\" target=\"0 0 0\" up=\"0 0 -1\" width=\"2.4\" height=\"2.4\"\n"
             "              resolution=\"1024\"/>\n"
             "        <OutputMap file=\"mask.exr\" %s/>\n"
             "      </Ortho>\n"
             "    </ProjectedMaps>\n"
             "  </Collider>\n"
             "  <Geometry>\n"
             "    <Mesh file=\"sphere.ply\"><Surface material=\"*\" absorption=\"1\"/></Mesh>\n"
             "  </Geometry>\n"
             "</Weathering>\n",
             bbox, time_step, steps, emitter, output_attrs);
    return ensure_write_file(dir, name, text);
}

/// The exact density at the sphere point with normal n (n.y given).
typedef double (*sphere_density_fn)(double ny, double particles);

static inline double sphere_box_density(double ny, double particles)
{
    return particles / (2.4 * 2.4) * (ny > 0.0 ? ny : 0.0); // the box covers 2.4 m x 2.4 m
}

static inline double sphere_dome_density(double ny, double particles)
{
    return particles / (4.0 * SPHERE_PI * sqrt(2.0 * (1.0 + ny)));
}

// Relative RMSE against the exact density over the texels with n.y > 0.3, and
// the worst relative error of the mean in the rings 0.3-0.4, ..., 0.9-1 of n.y.
static inline void sphere_errors(const float *mask, int w, int h, sphere_density_fn exact,
                                 double particles, double *rmse, double *worst_ring)
{
    double se = 0.0, sx = 0.0, sum[7] = { 0 }, want_sum[7] = { 0 };
    for (int j = 0; j < h; ++j) {
        for (int i = 0; i < w; ++i) {
            double x = -1.2 + 2.4 * (i + 0.5) / w, z = -1.2 + 2.4 * (j + 0.5) / h;
            double r2 = x * x + z * z;
            if (r2 >= 1.0 || sqrt(1.0 - r2) <= 0.3) {
                continue;
            }
            double ny = sqrt(1.0 - r2), want = exact(ny, particles), v = mask[(size_t)j * w + i];
            se += (v - want) * (v - want);
            sx += want * want;
            int ring = (int)((ny - 0.3) / 0.1);
            ring = ring > 6 ? 6 : ring;
            sum[ring] += v;
            want_sum[ring] += want;
        }
    }
    *rmse = sqrt(se / sx);
    *worst_ring = 0.0;
    for (int k = 0; k < 7; ++k) {
        *worst_ring = fmax(*worst_ring, fabs(sum[k] / want_sum[k] - 1.0));
    }
}

#endif
