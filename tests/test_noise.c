// test_noise.c: the Noise mask and <Term age> (docs/design.md section 15,
// docs/masks.md) against exact answers: a threshold t leaves a fraction 1 - t
// of the area above it (within 1%) on a sphere and on the default house,
// measured over the mesh with points of the test's own and over a TextureMap's
// texels weighted by their area; the value does not jump across a texture's UV
// seam; the same world point has the same value from two cameras; the noise
// is the same for the same seed and differs for another; the same bytes for 1
// and 2 threads; <Term age="w"> is w * i / iterations in the frame written
// after iteration i, and Dias' stages (Noise + age - 1, steep) age a fraction
// i / iterations of the area.
#define _XOPEN_SOURCE 700 // realpath
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ensure.h"
#include "io/mesh_import.h"
#include "model/mesh.h"
#include "sim/noise.h"
#include "run_fixture.h"

#define PI 3.14159265358979323846

static wx_mask_def noise_def(double frequency, int octaves, uint64_t seed)
{
    return (wx_mask_def){ .kind = WX_MASK_NOISE,
                          .frequency = (float)frequency,
                          .octaves = octaves,
                          .gain = 0.5f,
                          .noise_seed = seed };
}

// A small generator of the test's own (not the library's hashes): xorshift64*.
static double uniform(uint64_t *state)
{
    *state ^= *state >> 12;
    *state ^= *state << 25;
    *state ^= *state >> 27;
    return (double)((*state * 0x2545f4914f6cdd1dull) >> 11) * (1.0 / 9007199254740992.0);
}

// The area-weighted fraction of `count` points above each threshold of
// {0.25, 0.5, 0.75} under a table; checks each is 1 - t within 1%.
static void ensure_uniform(const char *what, const double *table, const wx_mask_def *m,
                           const double *points, const double *weight, size_t count)
{
    static const double thresholds[3] = { 0.25, 0.5, 0.75 };
    double above[3] = { 0.0, 0.0, 0.0 }, total = 0.0;
    for (size_t k = 0; k < count; ++k) {
        double v = wx_noise_remap(table, wx_noise_raw(m, &points[3 * k]));
        double w = weight != NULL ? weight[k] : 1.0;
        total += w;
        for (int t = 0; t < 3; ++t) {
            above[t] += v > thresholds[t] ? w : 0.0;
        }
    }
    printf("        %s: above 0.25, 0.5, 0.75: %.4f %.4f %.4f of the area\n", what,
           above[0] / total, above[1] / total, above[2] / total);
    for (int t = 0; t < 3; ++t) {
        ENSURE_NEAR(above[t] / total, 1.0 - thresholds[t], 0.01);
    }
}

// ---------------------------------------------------------------------------

// The same seed gives the same noise; another seed another noise; its values
// lie about [-1, 1] and are not constant.
TEST(noise_is_deterministic_per_seed)
{
    int differ = 0, n = 0;
    double lo = 1e9, hi = -1e9;
    for (int k = 0; k < 2000; ++k) {
        double p[3] = { 0.013 * k, 0.71 * sin(0.1 * k), 3.0 - 0.0021 * k * k };
        double a = wx_noise_fbm(p, 1.7, 5, 0.5, 7), b = wx_noise_fbm(p, 1.7, 5, 0.5, 7);
        double c = wx_noise_fbm(p, 1.7, 5, 0.5, 8);
        ENSURE(a == b);
        differ += fabs(a - c) > 1e-3;
        lo = fmin(lo, a);
        hi = fmax(hi, a);
        n++;
    }
    printf("        seed 7: values in [%.3f, %.3f]; seed 8 differs at %d of %d points\n", lo, hi,
           differ, n);
    ENSURE(differ > n * 9 / 10);
    ENSURE(lo > -1.5 && hi < 1.5 && hi - lo > 0.5);
    // A table built twice from the same points is the same table.
    wx_mask_def m = noise_def(2.0, 4, 3);
    double points[3 * 1000];
    uint64_t s = 99;
    for (int k = 0; k < 3000; ++k) {
        points[k] = uniform(&s);
    }
    double *t1 = malloc(WX_NOISE_TABLE_SIZE * sizeof *t1),
           *t2 = malloc(WX_NOISE_TABLE_SIZE * sizeof *t2);
    wx_error err;
    ENSURE(t1 != NULL && t2 != NULL);
    ENSURE(wx_noise_table_build(&m, points, NULL, 1000, t1, &err) == WX_OK);
    ENSURE(wx_noise_table_build(&m, points, NULL, 1000, t2, &err) == WX_OK);
    ENSURE(memcmp(t1, t2, WX_NOISE_TABLE_SIZE * sizeof *t1) == 0);
    for (int k = 1; k < WX_NOISE_TABLE_SIZE; ++k) {
        ENSURE(t1[k] >= t1[k - 1]); // monotone
    }
    free(t1);
    free(t2);
}

// A UV sphere of radius R as mesh data (positions and indices only).
static bool sphere_mesh(wx_mesh_data *m, int stacks, int slices, double R)
{
    memset(m, 0, sizeof *m);
    m->vertex_count = (int64_t)(stacks + 1) * (slices + 1);
    m->triangle_count = 2 * (int64_t)stacks * slices;
    m->positions = malloc(3 * (size_t)m->vertex_count * sizeof *m->positions);
    m->indices = malloc(3 * (size_t)m->triangle_count * sizeof *m->indices);
    if (m->positions == NULL || m->indices == NULL) {
        return false;
    }
    for (int i = 0; i <= stacks; ++i) {
        for (int j = 0; j <= slices; ++j) {
            double th = PI * i / stacks, ph = 2 * PI * j / slices;
            float *v = &m->positions[3 * (i * (slices + 1) + j)];
            v[0] = (float)(R * sin(th) * cos(ph));
            v[1] = (float)(R * cos(th));
            v[2] = (float)(R * sin(th) * sin(ph));
        }
    }
    uint32_t *f = m->indices;
    for (int i = 0; i < stacks; ++i) {
        for (int j = 0; j < slices; ++j) {
            uint32_t a = (uint32_t)(i * (slices + 1) + j), b = a + 1, c = a + (uint32_t)slices + 1,
                     d = c + 1;
            uint32_t t[6] = { a, c, b, b, c, d };
            memcpy(f, t, sizeof t);
            f += 6;
        }
    }
    return true;
}

// On a sphere: the table from the library's sample of the mesh, measured on
// an equal-area grid of the sphere itself (z uniform, longitude uniform).
TEST(threshold_leaves_its_area_on_a_sphere)
{
    wx_mesh_data m;
    ENSURE(sphere_mesh(&m, 128, 256, 1.0));
    const wx_mesh_data *meshes[1] = { &m };
    double *sample = malloc(3 * (size_t)WX_NOISE_SAMPLE_POINTS * sizeof *sample);
    double *table = malloc(WX_NOISE_TABLE_SIZE * sizeof *table);
    const int A = 400, B = 800;
    double *grid = malloc(3 * (size_t)A * B * sizeof *grid);
    ENSURE(sample != NULL && table != NULL && grid != NULL);
    size_t n = wx_noise_sample_meshes(meshes, 1, WX_NOISE_SAMPLE_POINTS, sample);
    ENSURE(n == WX_NOISE_SAMPLE_POINTS);
    for (int a = 0; a < A; ++a) {
        for (int b = 0; b < B; ++b) {
            double y = -1.0 + 2.0 * (a + 0.5) / A, r = sqrt(1.0 - y * y),
                   ph = 2 * PI * (b + 0.5) / B;
            double *p = &grid[3 * ((size_t)a * B + b)];
            p[0] = r * cos(ph);
            p[1] = y;
            p[2] = r * sin(ph);
        }
    }
    static const double frequencies[3] = { 0.7, 2.0, 6.0 };
    for (int f = 0; f < 3; ++f) {
        wx_mask_def md = noise_def(frequencies[f], 4, 1 + f);
        wx_error err;
        ENSURE(wx_noise_table_build(&md, sample, NULL, n, table, &err) == WX_OK);
        char what[64];
        snprintf(what, sizeof what, "sphere, frequency %g", frequencies[f]);
        ensure_uniform(what, table, &md, grid, NULL, (size_t)A * B);
    }
    free(sample);
    free(table);
    free(grid);
    free(m.positions);
    free(m.indices);
}

// On the default house (xml_scenes/meshes/building.obj): the table from the
// library's sample, measured on half a million points of the test's own, drawn per
// triangle in proportion to its area with the test's generator.
TEST(threshold_leaves_its_area_on_the_house)
{
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/../xml_scenes/meshes/building.obj", ensure_tests_dir());
    wx_mesh_data m;
    wx_error err;
    ENSURE(wx_mesh_import(path, &m, &err) == WX_OK);
    const wx_mesh_data *meshes[1] = { &m };
    double *sample = malloc(3 * (size_t)WX_NOISE_SAMPLE_POINTS * sizeof *sample);
    double *table = malloc(WX_NOISE_TABLE_SIZE * sizeof *table);
    const size_t want = 500000;
    double *points = malloc(3 * (want + 100000) * sizeof *points);
    ENSURE(sample != NULL && table != NULL && points != NULL);
    size_t n = wx_noise_sample_meshes(meshes, 1, WX_NOISE_SAMPLE_POINTS, sample);
    ENSURE(n == WX_NOISE_SAMPLE_POINTS);
    double total = 0.0;
    for (int pass = 0; pass < 2; ++pass) {
        uint64_t s = 0x1234567ull;
        size_t count = 0;
        for (int64_t t = 0; t < m.triangle_count; ++t) {
            double v[3][3];
            for (int c = 0; c < 3; ++c) {
                for (int a = 0; a < 3; ++a) {
                    v[c][a] = m.origin[a] + m.positions[3 * (size_t)m.indices[3 * t + c] + a];
                }
            }
            double e[2][3], cr[3];
            for (int a = 0; a < 3; ++a) {
                e[0][a] = v[1][a] - v[0][a];
                e[1][a] = v[2][a] - v[0][a];
            }
            cr[0] = e[0][1] * e[1][2] - e[0][2] * e[1][1];
            cr[1] = e[0][2] * e[1][0] - e[0][0] * e[1][2];
            cr[2] = e[0][0] * e[1][1] - e[0][1] * e[1][0];
            double area = 0.5 * sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
            if (pass == 0) {
                total += area;
                continue;
            }
            double expected = area / total * (double)want;
            int k = (int)floor(expected) + (uniform(&s) < expected - floor(expected));
            for (int i = 0; i < k && count < want + 100000; ++i) {
                double r1 = sqrt(uniform(&s)), r2 = uniform(&s);
                for (int a = 0; a < 3; ++a) {
                    points[3 * count + a] =
                        (1 - r1) * v[0][a] + r1 * (1 - r2) * v[1][a] + r1 * r2 * v[2][a];
                }
                count++;
            }
        }
        if (pass == 1) {
            printf("        house: %.0f square metres, %zu test points\n", total, count);
            static const double frequencies[2] = { 0.25, 1.0 };
            for (int f = 0; f < 2; ++f) {
                wx_mask_def md = noise_def(frequencies[f], 5, 7);
                ENSURE(wx_noise_table_build(&md, sample, NULL, n, table, &err) == WX_OK);
                char what[64];
                snprintf(what, sizeof what, "house, frequency %g", frequencies[f]);
                ensure_uniform(what, table, &md, points, NULL, count);
            }
        }
    }
    free(sample);
    free(table);
    free(points);
    wx_mesh_data_free(&m);
}

// ---------------------------------------------------------------------------
// Whole runs.

// The unit UV sphere of tests/data/uv_sphere.obj (seam: the half meridian
// towards +X, u = 0 and u = 1) seen by six cameras, a TextureMap of 512 x 256
// texels unsmoothed, an output camera at three-quarters with frames, and
// `iterations` iterations: grain (Noise), aged (<Term age="0.8">) and stains,
// Dias' stage: clamp(40 (grain + age - 1)), above 0 on a fraction age of the
// area.
static const char *sphere_scene =
    "<Weathering>\n"
    "  <Solver><BoundingBox size=\"6\"/><Simulation timeStep=\"0.01\" steps=\"1\" "
    "iterations=\"4\"/></Solver>\n"
    "  <Collider><ProjectedMaps>\n"
    "    <Ortho cameraName=\"top\"><View eye=\"0 5 0\" target=\"0 0 0\" up=\"0 0 -1\" "
    "width=\"2.4\" height=\"2.4\" resolution=\"256\"/></Ortho>\n"
    "    <Ortho cameraName=\"bottom\"><View eye=\"0 -5 0\" target=\"0 0 0\" up=\"0 0 1\" "
    "width=\"2.4\" height=\"2.4\" resolution=\"256\"/></Ortho>\n"
    "    <Ortho cameraName=\"px\"><View eye=\"5 0 0\" target=\"0 0 0\" width=\"2.4\" "
    "height=\"2.4\" resolution=\"256\"/></Ortho>\n"
    "    <Ortho cameraName=\"nx\"><View eye=\"-5 0 0\" target=\"0 0 0\" width=\"2.4\" "
    "height=\"2.4\" resolution=\"256\"/></Ortho>\n"
    "    <Ortho cameraName=\"pz\"><View eye=\"0 0 5\" target=\"0 0 0\" width=\"2.4\" "
    "height=\"2.4\" resolution=\"256\"/></Ortho>\n"
    "    <Ortho cameraName=\"nz\"><View eye=\"0 0 -5\" target=\"0 0 0\" width=\"2.4\" "
    "height=\"2.4\" resolution=\"256\"/></Ortho>\n"
    "    <Ortho cameraName=\"shot\" out=\"true\"><View eye=\"3 2 3\" target=\"0 0 0\" "
    "width=\"2.4\" height=\"2.4\" resolution=\"128\"/><OutputMap file=\"mask.exr\" every=\"1\"/>"
    "</Ortho>\n"
    "  </ProjectedMaps></Collider>\n"
    "  <Geometry><Mesh file=\"%s\"><Surface material=\"*\"/>\n"
    "    <TextureMap file=\"tex.exr\" width=\"512\" height=\"256\" radius=\"0\" every=\"1\"/>"
    "</Mesh></Geometry>\n"
    "  <Masks><Noise name=\"grain\" frequency=\"2\" octaves=\"4\" seed=\"%d\"/>"
    "<Combine name=\"aged\"><Term age=\"0.8\"/></Combine>"
    "<Combine name=\"stains\" scale=\"40\"><Term mask=\"grain\"/><Term age=\"1\"/>"
    "<Term constant=\"-1\"/></Combine></Masks>\n"
    "</Weathering>\n";

static bool run_sphere(const char *dir, const char *folder, int seed, int threads)
{
    char text[8192], name[64], args[160];
    snprintf(text, sizeof text, sphere_scene, data_file("uv_sphere.obj"), seed);
    snprintf(name, sizeof name, "sphere%d.xml", seed);
    ensure_write_file(dir, name, text);
    snprintf(args, sizeof args, "run %s --out %s -q --threads %d", name, folder, threads);
    return weathering_in(dir, args, true) == 0;
}

static float *channel(const char *dir, const char *folder, const char *file, const char *name,
                      int *w, int *h)
{
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/%s/%s", dir, folder, file);
    return ensure_read_channel(path, name, w, h);
}

// Over the TextureMap's texels, each weighted by the area it stands for (the
// latitude-longitude layout: sin(pi v) per texel), a threshold t leaves 1 - t;
// across the seam (column 0 against column W-1, the same meridian) the value
// changes no more than between neighbouring columns elsewhere; the same bytes
// for 1 and 2 threads; another seed, another mask.
TEST(texture_uniform_seamless_and_the_same_for_any_thread_count)
{
    SLOW();
    const char *dir = ensure_tmpdir();
    ENSURE(run_sphere(dir, "one", 7, 1));
    ENSURE(run_sphere(dir, "two", 7, 2));
    ENSURE(run_sphere(dir, "other", 8, 2));
    ENSURE(ensure_shell(out, sizeof out,
                        "cd '%s' && cmp one/tex.exr two/tex.exr && cmp one/mask.exr two/mask.exr "
                        "&& cmp one/tex.0002.exr two/tex.0002.exr",
                        dir) == 0);
    int w, h, w2, h2;
    float *g = channel(dir, "one", "tex.exr", "grain.Y", &w, &h);
    float *seen = channel(dir, "one", "tex.exr", "seen", &w2, &h2);
    float *other = channel(dir, "other", "tex.exr", "grain.Y", &w2, &h2);
    ENSURE(g != NULL && seen != NULL && other != NULL && w == 512 && h == 256);
    static const double thresholds[3] = { 0.25, 0.5, 0.75 };
    double above[3] = { 0, 0, 0 }, total = 0.0, unseen = 0.0, differ = 0.0;
    for (int j = 0; j < h; ++j) {
        double v = 1.0 - (j + 0.5) / h, weight = sin(PI * v);
        for (int i = 0; i < w; ++i) {
            size_t t = (size_t)j * w + i;
            if (!(seen[t] > 0.5f)) {
                unseen += weight;
                continue;
            }
            total += weight;
            differ += fabs(g[t] - other[t]) > 0.01f ? weight : 0.0;
            for (int k = 0; k < 3; ++k) {
                above[k] += g[t] > thresholds[k] ? weight : 0.0;
            }
        }
    }
    printf("        texture: above 0.25, 0.5, 0.75: %.4f %.4f %.4f of the area (%.2g unseen); "
           "seed 8 differs on %.0f%%\n",
           above[0] / total, above[1] / total, above[2] / total, unseen / (total + unseen),
           100.0 * differ / total);
    ENSURE(unseen < 0.001 * total);
    for (int k = 0; k < 3; ++k) {
        ENSURE_NEAR(above[k] / total, 1.0 - thresholds[k], 0.01);
    }
    ENSURE(differ > 0.9 * total);
    // The seam: texel centres at u = 0.5/W and 1 - 0.5/W lie one texel apart
    // on the sphere, as do neighbouring columns.
    double seam = 0.0, inside = 0.0;
    int rows = 0;
    for (int j = h / 8; j < h - h / 8; ++j) {
        const float *row = &g[(size_t)j * w];
        seam += fabs(row[0] - row[w - 1]);
        double sum = 0.0;
        for (int i = 0; i + 1 < w; ++i) {
            sum += fabs(row[i] - row[i + 1]);
        }
        inside += sum / (w - 1);
        rows++;
    }
    printf("        seam: mean step %.4f across it, %.4f between neighbouring columns\n",
           seam / rows, inside / rows);
    ENSURE(seam / rows < 1.5 * inside / rows);
    free(g);
    free(seen);
    free(other);
}

// <Term age="0.8"> is 0.8 i / 4 in the frame after iteration i of 4, 0.8 in
// the final mask, at every point the mask holds; Dias' stage stains (noise +
// age - 1, steep) covers a fraction i / 4 of the TextureMap's area.
TEST(term_age_advances_with_the_frames)
{
    SLOW();
    const char *dir = ensure_tmpdir();
    ENSURE(run_sphere(dir, "age", 7, 2));
    static const char *const masks[5] = { "mask.0001.exr", "mask.0002.exr", "mask.0003.exr",
                                          "mask.0004.exr", "mask.exr" };
    static const char *const texs[5] = { "tex.0001.exr", "tex.0002.exr", "tex.0003.exr",
                                         "tex.0004.exr", "tex.exr" };
    for (int f = 0; f < 5; ++f) {
        int i = f < 4 ? f + 1 : 4, w, h;
        double want = 0.8 * i / 4.0;
        float *aged = channel(dir, "age", masks[f], "aged.Y", &w, &h);
        float *grain = channel(dir, "age", masks[f], "grain.Y", &w, &h);
        ENSURE(aged != NULL && grain != NULL);
        double worst = 0.0;
        int points = 0;
        for (size_t t = 0; t < (size_t)w * h; ++t) {
            if (aged[t] > 0.0f) {
                worst = fmax(worst, fabs(aged[t] - want));
                points++;
            }
        }
        free(aged);
        free(grain);
        float *stains = channel(dir, "age", texs[f], "stains.Y", &w, &h);
        float *seen = channel(dir, "age", texs[f], "seen", &w, &h);
        ENSURE(stains != NULL && seen != NULL);
        double area = 0.0, stained = 0.0;
        for (int j = 0; j < h; ++j) {
            double weight = sin(PI * (1.0 - (j + 0.5) / h));
            for (int x = 0; x < w; ++x) {
                size_t t = (size_t)j * w + x;
                if (seen[t] > 0.5f) {
                    area += weight;
                    stained += stains[t] > 0.0f ? weight : 0.0;
                }
            }
        }
        free(stains);
        free(seen);
        printf("        %s: age %.2f (worst %.2g over %d points); stains on %.4f of the area "
               "(%.2f wanted)\n",
               masks[f], want, worst, points, stained / area, i / 4.0);
        ENSURE(points > 1000 && worst <= 1e-6);
        ENSURE_NEAR(stained / area, i / 4.0, 0.01);
    }
}

// A flat floor seen straight down by two output cameras of 64 texels over 2 m
// whose frames are 8 texels apart (and at other heights): texel i + 8 of the
// first and texel i of the second are the same world point, and hold the same
// value.
TEST(same_world_point_same_value_from_two_cameras)
{
    SLOW();
    const char *dir = ensure_tmpdir();
    ensure_write_file(dir, "floor.obj",
                      "v -3 0 -3\nv 3 0 -3\nv 3 0 3\nv -3 0 3\nf 1 3 2\nf 1 4 3\n");
    const double shift = 8 * 2.0 / 64;
    for (int c = 0; c < 2; ++c) {
        char text[4096], name[32], args[96];
        snprintf(
            text, sizeof text,
            "<Weathering>\n"
            "  <Solver><BoundingBox size=\"12\"/><Simulation timeStep=\"0.01\" "
            "steps=\"1\"/></Solver>\n"
            "  <Collider><ProjectedMaps>\n"
            "    <Ortho cameraName=\"top\"><View eye=\"0 5 0\" target=\"0 0 0\" up=\"0 0 "
            "-1\" width=\"6\" height=\"6\" resolution=\"256\"/></Ortho>\n"
            "    <Ortho cameraName=\"shot\" out=\"true\"><View eye=\"%g %g 0\" target=\"%g 0 "
            "0\" up=\"0 0 -1\" width=\"2\" height=\"2\" resolution=\"64\"/>"
            "<OutputMap file=\"mask.exr\"/></Ortho>\n"
            "  </ProjectedMaps></Collider>\n"
            "  <Geometry><Mesh file=\"floor.obj\"><Surface material=\"*\"/></Mesh></Geometry>\n"
            "  <Masks><Noise name=\"grain\" frequency=\"3\"/></Masks>\n"
            "</Weathering>\n",
            c * shift, 4.0 + c, c * shift);
        snprintf(name, sizeof name, "cam%d.xml", c);
        ensure_write_file(dir, name, text);
        snprintf(args, sizeof args, "run %s --out cam%d -q", name, c);
        ENSURE(weathering_in(dir, args, true) == 0);
    }
    int w, h;
    float *a = channel(dir, "cam0", "mask.exr", "grain.Y", &w, &h);
    float *b = channel(dir, "cam1", "mask.exr", "grain.Y", &w, &h);
    ENSURE(a != NULL && b != NULL && w == 64 && h == 64);
    double worst = 0.0, lo = 1.0, hi = 0.0;
    for (int j = 0; j < h; ++j) {
        for (int i = 0; i + 8 < w; ++i) {
            float va = a[(size_t)j * w + i + 8], vb = b[(size_t)j * w + i];
            worst = fmax(worst, fabs(va - vb));
            lo = fmin(lo, va);
            hi = fmax(hi, va);
        }
    }
    printf("        two cameras: values in [%.3f, %.3f], the same point within %.2g\n", lo, hi,
           worst);
    ENSURE(hi - lo > 0.5 && worst <= 1e-4);
    free(a);
    free(b);
}

// A scene of pre-rendered maps only (no <Geometry>: the maps of a run of the
// floor above) builds its remap from the input camera's texels: over the
// output camera's pixels, which see the floor as the input camera does, a
// threshold t leaves 1 - t within 1%, and the values are those of the run with
// the mesh within 0.02 (two samples of the same surface).
TEST(pre_rendered_maps_remap_by_their_texels)
{
    SLOW();
    const char *dir = ensure_tmpdir();
    ensure_write_file(dir, "floor.obj",
                      "v -3 0 -3\nv 3 0 -3\nv 3 0 3\nv -3 0 3\nf 1 3 2\nf 1 4 3\n");
    static const char *const view =
        "<View eye=\"0 5 0\" target=\"0 0 0\" up=\"0 0 -1\" width=\"6\" height=\"6\" "
        "resolution=\"%d\"/>";
    char top[256], shot[256], text[8192];
    snprintf(top, sizeof top, view, 256);
    snprintf(shot, sizeof shot, view, 128);
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Solver><BoundingBox size=\"12\"/><Simulation timeStep=\"0.01\" "
             "steps=\"1\"/></Solver>\n"
             "  <Collider><ProjectedMaps>\n"
             "    <Ortho cameraName=\"top\">%s</Ortho>\n"
             "    <Ortho cameraName=\"shot\" out=\"true\">%s<OutputMap file=\"mask.exr\"/></Ortho>\n"
             "  </ProjectedMaps></Collider>\n"
             "  <Geometry><Mesh file=\"floor.obj\"><Surface material=\"*\"/></Mesh></Geometry>\n"
             "  <Masks><Noise name=\"grain\" frequency=\"1.5\"/></Masks>\n"
             "</Weathering>\n",
             top, shot);
    ensure_write_file(dir, "mesh.xml", text);
    ENSURE(weathering_in(dir, "run mesh.xml --out m -q", true) == 0);
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Solver><BoundingBox size=\"12\"/><Simulation timeStep=\"0.01\" "
             "steps=\"1\"/></Solver>\n"
             "  <Collider><ProjectedMaps>\n"
             "    <Ortho cameraName=\"top\">%s<DepthMap file=\"m/top_depth.exr\"/>"
             "<NormalMap file=\"m/top_normal.exr\"/><ImpactMap file=\"m/top_impact.exr\"/>"
             "<DirtMap file=\"m/top_dirt.exr\"/></Ortho>\n"
             "    <Ortho cameraName=\"shot\" out=\"true\">%s<DepthMap file=\"m/shot_depth.exr\"/>"
             "<NormalMap file=\"m/shot_normal.exr\"/><OutputMap file=\"mask.exr\"/></Ortho>\n"
             "  </ProjectedMaps></Collider>\n"
             "  <Masks><Noise name=\"grain\" frequency=\"1.5\"/></Masks>\n"
             "</Weathering>\n",
             top, shot);
    ensure_write_file(dir, "maps.xml", text);
    ENSURE(weathering_in(dir, "run maps.xml --out p -q", true) == 0);
    int w, h;
    float *a = channel(dir, "m", "mask.exr", "grain.Y", &w, &h);
    float *b = channel(dir, "p", "mask.exr", "grain.Y", &w, &h);
    ENSURE(a != NULL && b != NULL);
    static const double thresholds[3] = { 0.25, 0.5, 0.75 };
    double above[3] = { 0, 0, 0 }, worst = 0.0;
    size_t n = (size_t)w * h;
    for (size_t t = 0; t < n; ++t) {
        worst = fmax(worst, fabs(a[t] - b[t]));
        for (int k = 0; k < 3; ++k) {
            above[k] += b[t] > thresholds[k];
        }
    }
    printf("        maps only: above 0.25, 0.5, 0.75: %.4f %.4f %.4f of the pixels; within %.3f "
           "of the mesh's remap\n",
           above[0] / n, above[1] / n, above[2] / n, worst);
    for (int k = 0; k < 3; ++k) {
        ENSURE_NEAR(above[k] / n, 1.0 - thresholds[k], 0.01);
    }
    ENSURE(worst <= 0.02);
    free(a);
    free(b);
}

int main(void)
{
    RUN(noise_is_deterministic_per_seed);
    RUN(threshold_leaves_its_area_on_a_sphere);
    RUN(threshold_leaves_its_area_on_the_house);
    RUN(texture_uniform_seamless_and_the_same_for_any_thread_count);
    RUN(term_age_advances_with_the_frames);
    RUN(same_world_point_same_value_from_two_cameras);
    RUN(pre_rendered_maps_remap_by_their_texels);
    return ensure_summary();
}
