// test_memory.c: the memory estimate (pipeline/memory.h, docs/reliability.md)
// against the peak resident memory of real runs: meshes in OBJ, binary PLY and
// glTF, and an emitter whose drops die at their first hit. The shipped scenes'
// estimates are checked in test_shipped_scenes.c.
#define _DEFAULT_SOURCE // wait4
#include <fcntl.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "core/big_alloc.h"
#include "ensure.h"
#include "memory_fixture.h"

// A folder of this test's scenes with the unit box of tests/data (box.obj).
static const char *scene_dir(void)
{
    static char dir[4200];
    if (dir[0] == '\0') {
        snprintf(dir, sizeof dir, "%s/scene", ensure_tmpdir());
        mkdir(dir, 0777);
        char src[4200];
        snprintf(src, sizeof src, "%s/data/bake_box.obj", ensure_tests_dir());
        char *box = ensure_read_file(src);
        ensure_write_file(dir, "box.obj", box != NULL ? box : "");
        free(box);
    }
    return dir;
}

static const char *out_dir(const char *name)
{
    static char dirs[4][4200];
    static int next;
    char *dir = dirs[next++ % 4];
    snprintf(dir, sizeof dirs[0], "%s/%s", ensure_tmpdir(), name);
    return dir;
}

// A bumpy square of about `triangles` triangles (a grid of n x n quads, each
// two triangles) as `format` ("obj" with texture coordinates, binary "ply",
// "gltf" with its .bin beside it) at dir/name.
static bool write_grid_mesh(const char *dir, const char *name, const char *format, int triangles)
{
    int n = (int)sqrt(triangles / 2.0);
    n = n < 2 ? 2 : n;
    const int nv = (n + 1) * (n + 1), nt = 2 * n * n;
    char path[4400];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    bool gltf = strcmp(format, "gltf") == 0, ply = strcmp(format, "ply") == 0;
    char bin[4410];
    snprintf(bin, sizeof bin, "%s.bin", path);
    FILE *f = fopen(gltf ? bin : path, "wb");
    if (f == NULL) {
        return false;
    }
    if (ply) {
        fprintf(f,
                "ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
                "property float y\nproperty float z\nelement face %d\n"
                "property list uchar int vertex_indices\nend_header\n",
                nv, nt);
    }
    for (int pass = 0; pass < (gltf || ply ? 1 : 2); ++pass) {
        for (int j = 0; j <= n; ++j) {
            for (int i = 0; i <= n; ++i) {
                float x = 2.0f * i / n - 1.0f, z = 2.0f * j / n - 1.0f;
                float p[3] = { x, 0.1f * sinf(7.0f * x) * cosf(5.0f * z), z };
                if (gltf || ply) {
                    fwrite(p, sizeof p, 1, f);
                } else if (pass == 0) {
                    fprintf(f, "v %.6f %.6f %.6f\n", p[0], p[1], p[2]);
                } else {
                    fprintf(f, "vt %.6f %.6f\n", 0.5 * (x + 1.0), 0.5 * (z + 1.0));
                }
            }
        }
    }
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
            int tris[2][3] = { { a, c, b }, { b, c, d } };
            for (int t = 0; t < 2; ++t) {
                if (gltf) {
                    uint32_t idx[3] = { (uint32_t)tris[t][0], (uint32_t)tris[t][1],
                                        (uint32_t)tris[t][2] };
                    fwrite(idx, sizeof idx, 1, f);
                } else if (ply) {
                    unsigned char three = 3;
                    fwrite(&three, 1, 1, f);
                    fwrite(tris[t], sizeof tris[t], 1, f);
                } else {
                    fprintf(f, "f %d/%d %d/%d %d/%d\n", tris[t][0] + 1, tris[t][0] + 1,
                            tris[t][1] + 1, tris[t][1] + 1, tris[t][2] + 1, tris[t][2] + 1);
                }
            }
        }
    }
    if (fclose(f) != 0) {
        return false;
    }
    if (gltf) {
        long pos = 12L * nv, idx = 12L * nt;
        static char json[8192];
        const char *slash = strrchr(bin, '/');
        snprintf(json, sizeof json,
                 "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
                 "\"nodes\":[{\"mesh\":0}],\"meshes\":[{\"primitives\":[{\"attributes\":"
                 "{\"POSITION\":0},\"indices\":1}]}],\"buffers\":[{\"byteLength\":%ld,\"uri\":"
                 "\"%s\"}],\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":%ld},"
                 "{\"buffer\":0,\"byteOffset\":%ld,\"byteLength\":%ld}],\"accessors\":[{"
                 "\"bufferView\":0,\"componentType\":5126,\"count\":%d,\"type\":\"VEC3\","
                 "\"min\":[-1,-0.1,-1],\"max\":[1,0.1,1]},{\"bufferView\":1,\"componentType\":"
                 "5125,\"count\":%d,\"type\":\"SCALAR\"}]}",
                 pos + idx, slash != NULL ? slash + 1 : bin, pos, pos, idx, nv, 3 * nt);
        ensure_write_file(dir, name, json);
    }
    return true;
}

// The estimate stays an upper bound within 3x of the peak for meshes in OBJ,
// binary PLY and glTF (it was 3.7x for a 2-million-triangle OBJ, counting 32
// bytes per file byte, and glTF's buffers not at all: 0.5x for 500 000
// triangles), now that it counts the imported triangles; and for an emitter
// that rains for 20 s, drops dying at their first hit, it counts the drops
// alive at once (at most 0.49 s of rain), not all 2 million (5.7x before).
TEST(memory_estimate_bounds_meshes_and_particles_alive_at_once)
{
    SLOW();
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
    SKIP("sanitizers change the memory a run takes");
#endif
    const char *dir = scene_dir();
    static const char *const formats[3] = { "obj", "ply", "gltf" };
    static const int sizes[2] = { 10000, 300000 };
    static const char *const scene =
        "<Weathering>\n"
        "  <Solver><BoundingBox size=\"%s\" centerY=\"%s\"/><Simulation timeStep=\"0.01\" "
        "steps=\"%d\" seed=\"1\"/></Solver>\n"
        "  <ForceFields><Gravity acceleration=\"9.8\"/></ForceFields>\n"
        "  <Emitters><BoxEmitter minX=\"-1.5\" minY=\"2.5\" minZ=\"-1.5\" maxX=\"1.5\" "
        "maxY=\"2.5\" maxZ=\"1.5\" rate=\"%d\" end=\"%s\" speed=\"5\" "
        "maxCollisions=\"%d\"/></Emitters>\n"
        "  <Collider><ProjectedMaps>\n"
        "    <Ortho cameraName=\"top\"><View eye=\"0 5 0\" target=\"0 0 0\" up=\"0 0 -1\" "
        "width=\"4\" height=\"4\" resolution=\"64\"/></Ortho>\n"
        "    <Ortho cameraName=\"front\"><View eye=\"0 0 5\" target=\"0 0 0\" up=\"0 1 0\" "
        "width=\"4\" height=\"4\" resolution=\"64\"/></Ortho>\n"
        "    <Ortho cameraName=\"shot\" out=\"true\"><View eye=\"3 4 5\" target=\"0 0 0\" "
        "up=\"0 1 0\" width=\"5\" height=\"5\" resolution=\"48\"/><OutputMap file=\"mask.exr\"/>"
        "</Ortho>\n"
        "  </ProjectedMaps></Collider>\n"
        "  <Geometry><Mesh file=\"%s\"><Surface material=\"*\" absorption=\"0.2\"/></Mesh>"
        "</Geometry>\n"
        "</Weathering>\n";
    int failures = 0;
    for (int f = 0; f < 3; ++f) {
        for (int k = 0; k < 2; ++k) {
            char mesh[64], name[64], text[4096], path[4400];
            snprintf(mesh, sizeof mesh, "grid_%d.%s", sizes[k], formats[f]);
            snprintf(name, sizeof name, "grid_%d_%s.xml", sizes[k], formats[f]);
            ENSURE(write_grid_mesh(dir, mesh, formats[f], sizes[k]));
            snprintf(text, sizeof text, scene, "6", "0", 50, 20000, "0.1", 100, mesh);
            ensure_write_file(dir, name, text);
            snprintf(path, sizeof path, "%s/%s", dir, name);
            double estimate = estimate_mib(path);
            double peak = run_peak_mib(path, out_dir(name), NULL);
            fprintf(stderr, "        %-22s estimate %6.0f MiB, peak %6.0f MiB (%.2fx)\n", name,
                    estimate, peak, estimate / peak);
            failures += !(peak > 0.0 && estimate >= peak && estimate <= 3.0 * peak);
        }
    }
    // 100 000 drops a second for 20 s (2 million) on the unit box, each gone at
    // its first hit or at the solver box's floor.
    char text[4096], path[4400];
    snprintf(text, sizeof text, scene, "4", "1", 2100, 100000, "20", 1, "box.obj");
    ensure_write_file(dir, "rain_20s.xml", text);
    snprintf(path, sizeof path, "%s/rain_20s.xml", dir);
    double estimate = estimate_mib(path);
    double peak = run_peak_mib(path, out_dir("rain_20s"), NULL);
    fprintf(stderr, "        %-22s estimate %6.0f MiB, peak %6.0f MiB (%.2fx)\n", "rain_20s.xml",
            estimate, peak, estimate / peak);
    failures += !(peak > 0.0 && estimate >= peak && estimate <= 3.0 * peak);
    ENSURE(failures == 0);
}

// core/big_alloc: a large block starts on a huge page and is whole; calloc's
// zeroes; an overflowing count refused; small blocks still given.
TEST(big_blocks_are_aligned_zeroed_and_refuse_overflow)
{
    const size_t huge = (size_t)2 << 20;
    size_t bytes = 5 * huge + 12345; // a tail past the last whole huge page
    unsigned char *p = wx_big_malloc(bytes);
    ENSURE(p != NULL);
    ENSURE(((uintptr_t)p & (huge - 1)) == 0);
    memset(p, 0xab, bytes); // every byte asked for is usable
    ENSURE(p[bytes - 1] == 0xab);
    free(p);
    size_t count = 3 * huge / sizeof(float) + 7;
    float *z = wx_big_calloc(count, sizeof(float));
    ENSURE(z != NULL);
    size_t nonzero = 0;
    for (size_t i = 0; i < count; ++i) {
        nonzero += z[i] != 0.0f;
    }
    ENSURE(nonzero == 0);
    free(z);
    ENSURE(wx_big_calloc(SIZE_MAX / 2, 4) == NULL);
    void *small = wx_big_malloc(100), *none = wx_big_calloc(0, 4);
    ENSURE(small != NULL && none != NULL);
    free(small);
    free(none);
}

// --stats' peak_memory_mib is the run's own high-water mark: positive and no
// more than what wait4 reports for the same child (which also counts this
// test's memory at the fork).
TEST(stats_report_the_runs_own_peak_memory)
{
    const char *dir = scene_dir();
    ensure_write_file(
        dir, "peak.xml",
        "<Weathering>\n"
        "  <Solver><BoundingBox size=\"4\" centerY=\"1\"/><Simulation "
        "timeStep=\"0.01\" steps=\"20\" seed=\"1\"/></Solver>\n"
        "  <ForceFields><Gravity acceleration=\"9.8\"/></ForceFields>\n"
        "  <Emitters><BoxEmitter minX=\"-1\" minY=\"2.5\" minZ=\"-1\" maxX=\"1\" "
        "maxY=\"2.5\" maxZ=\"1\" rate=\"10000\" end=\"0.1\" speed=\"5\"/>"
        "</Emitters>\n"
        "  <Collider><ProjectedMaps>\n"
        "    <Ortho cameraName=\"top\"><View eye=\"0 5 0\" target=\"0 0 0\" "
        "up=\"0 0 -1\" width=\"4\" height=\"4\" resolution=\"64\"/></Ortho>\n"
        "    <Ortho cameraName=\"shot\" out=\"true\"><View eye=\"3 4 5\" "
        "target=\"0 0 0\" up=\"0 1 0\" width=\"5\" height=\"5\" "
        "resolution=\"48\"/><OutputMap file=\"mask.exr\"/></Ortho>\n"
        "  </ProjectedMaps></Collider>\n"
        "  <Geometry><Mesh file=\"box.obj\"><Surface material=\"*\"/></Mesh></Geometry>\n"
        "</Weathering>\n");
    char path[4400], stats[4400];
    snprintf(path, sizeof path, "%s/peak.xml", dir);
    snprintf(stats, sizeof stats, "%s/peak.json", dir);
    double wait4_peak = run_peak_mib(path, out_dir("peak"), stats);
    ENSURE(wait4_peak > 0.0);
    char *json = ensure_read_file(stats);
    const char *at = json != NULL ? strstr(json, "\"peak_memory_mib\": ") : NULL;
    ENSURE(at != NULL);
    double own = at != NULL ? atof(at + strlen("\"peak_memory_mib\": ")) : -1.0;
    fprintf(stderr, "        own peak %.1f MiB, wait4's %.1f MiB\n", own, wait4_peak);
    ENSURE(own > 0.0 && own <= wait4_peak + 1.0);
    free(json);
}

// The bake's peak is the same from one run to the next. With llvmpipe's
// rasteriser threads it was not: the renderer starts a new binned scene (up to
// 36 MiB) whenever drawing outruns them, and keeps it, so four bakes of the
// bunny peaked at 333.7 to 344.3 MiB and the estimate could not bound such
// runs (docs/reliability.md, "What the renderer keeps"). Rasterising on the
// drawing thread, they agree within 4 MiB (221.1 to 224.4) and stay under 300.
TEST(the_bakes_peak_does_not_depend_on_the_renderers_timing)
{
    SLOW();
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
    SKIP("sanitizers change the memory a run takes");
#endif
    char scene[4300];
    snprintf(scene, sizeof scene, "%s/../xml_scenes/bunny.xml", ensure_tests_dir());
    double least = 1e30, most = 0.0;
    for (int k = 0; k < 4; ++k) {
        char name[32];
        snprintf(name, sizeof name, "bunny_bake_%d", k);
        double peak = command_peak_mib("bake", scene, out_dir(name), NULL);
        ENSURE(peak > 0.0);
        least = fmin(least, peak);
        most = fmax(most, peak);
    }
    fprintf(stderr, "        bunny's bake: peak %.1f to %.1f MiB over 4 runs\n", least, most);
    ENSURE(most - least <= 8.0);
    ENSURE(most <= 300.0);
}

int main(void)
{
    RUN(big_blocks_are_aligned_zeroed_and_refuse_overflow);
    RUN(stats_report_the_runs_own_peak_memory);
    RUN(memory_estimate_bounds_meshes_and_particles_alive_at_once);
    RUN(the_bakes_peak_does_not_depend_on_the_renderers_timing);
    return ensure_summary();
}
