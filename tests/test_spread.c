// test_spread.c: the surface automata (docs/design.md section 15), <Seed> and
// <Spread>, against answers worked out by hand:
//  - on a plane, rust that starts on a 2 cm square at the origin and spreads
//    with probability 1 and radius 5 cm covers, after iteration k, the disc of
//    radius k * 5 cm around the square, within one texel;
//  - around a cylinder whose texture's seam runs along +x, rust that starts
//    next to the seam reaches the texels on both sides of it;
//  - Seed's density gives the Poisson expectation of seeds, sum over the
//    points of 1 - exp(-density * area), within 3 standard deviations;
//  - a <Crack> grows one point per tip per iteration, a line whose points lie
//    within its radius of each other, and <Peel> spreads from it;
//  - the ledger balances with what was seeded and spread counted as grown;
//  - 1 and 2 threads give the same bytes.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "ensure.h"

#define TEXEL_M  0.01
#define RADIUS_M 0.05
// The seed square covers 2 x 2 texels, whose centres lie 5 mm off its axes.
#define SEED_HALF_M 0.005
enum { PLANE_PX = 240, PLANE_ITERATIONS = 4 };

// y = 0, x and z in [-1, 1], facing +y; the 2 cm square at the origin is "seed".
static const char PLANE_OBJ[] = "mtllib plane.mtl\n"
                                "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n"
                                "v -0.01 0 -0.01\nv 0.01 0 -0.01\nv 0.01 0 0.01\nv -0.01 0 0.01\n"
                                "vn 0 1 0\n"
                                "usemtl iron\n"
                                "f 1//1 4//1 8//1 5//1\nf 4//1 3//1 7//1 8//1\n"
                                "f 3//1 2//1 6//1 7//1\nf 2//1 1//1 5//1 6//1\n"
                                "usemtl seed\nf 5//1 8//1 7//1 6//1\n";

static const char PLANE_MTL[] = "newmtl iron\nKd 0.5 0.5 0.5\nnewmtl seed\nKd 0.7 0.7 0.7\n";

// %s: the <Ageing> rules.
static const char PLANE_XML[] =
    "<Weathering>\n"
    "  <Substances><Substance name=\"rust\"/><Substance name=\"spot\"/></Substances>\n"
    "  <Solver><Simulation timeStep=\"0.01\" steps=\"2\" seed=\"3\" iterations=\"4\"/>"
    "<BoundingBox size=\"8\"/></Solver>\n"
    "  <Ageing>\n%s  </Ageing>\n"
    "  <Collider><ProjectedMaps>\n"
    "    <Ortho cameraName=\"top\"><View eye=\"0 3 0\" target=\"0 0 0\" up=\"0 0 -1\" "
    "width=\"2.4\" height=\"2.4\" resolution=\"240\"/></Ortho>\n"
    "    <Ortho cameraName=\"shot\" out=\"true\"><View eye=\"0 3 0\" target=\"0 0 0\" "
    "up=\"0 0 -1\" width=\"2.4\" height=\"2.4\" resolution=\"240\"/>\n"
    "      <OutputMap file=\"mask.exr\" every=\"1\" radius=\"0\"/></Ortho>\n"
    "  </ProjectedMaps></Collider>\n"
    "  <Geometry><Mesh file=\"plane.obj\">\n"
    "    <Surface material=\"iron\"/>\n"
    "    <Surface material=\"seed\"><Exchange substance=\"rust\" initial=\"1\"/></Surface>\n"
    "  </Mesh></Geometry>\n"
    "</Weathering>\n";

#define SPOT_DENSITY 500.0

static const char PLANE_RULES[] =
    "    <Spread substance=\"rust\" radius=\"0.05\" probability=\"1\"/>\n"
    "    <Seed substance=\"spot\" density=\"500\"/>\n";

// Runs DIR/scene.xml into DIR/out with its statistics in DIR/stats.json and
// the extra command-line words; false (with the run's output on stderr) when
// it fails.
static bool run_scene(const char *dir, const char *extra)
{
    char log[8192];
    int status = ensure_shell(log, sizeof log,
                              "'%s/weathering' run '%s/scene.xml' --out '%s/out' -q --stats "
                              "'%s/stats.json' %s",
                              ensure_build_dir(), dir, dir, dir, extra);
    if (status != 0) {
        fprintf(stderr, "        weathering run: status %d\n%s\n", status, log);
    }
    return status == 0;
}

// Runs the plane scene in tmp/NAME with `rules` and extra command-line words;
// returns the folder (static) or NULL.
static const char *run_plane(const char *name, const char *rules, const char *extra)
{
    static char dir[4200];
    snprintf(dir, sizeof dir, "%s/%s", ensure_tmpdir(), name);
    mkdir(dir, 0777);
    ensure_write_file(dir, "plane.obj", PLANE_OBJ);
    ensure_write_file(dir, "plane.mtl", PLANE_MTL);
    char xml[8192];
    snprintf(xml, sizeof xml, PLANE_XML, rules);
    ensure_write_file(dir, "scene.xml", xml);
    return run_scene(dir, extra) ? dir : NULL;
}

static const char *plane_dir(void)
{
    static const char *dir;
    static bool ran;
    if (!ran) {
        dir = run_plane("spread_plane", PLANE_RULES, "--threads 2");
        ran = true;
    }
    return dir;
}

TEST(spread_grows_a_disc_by_the_radius_every_iteration)
{
    const char *dir = plane_dir();
    ENSURE(dir != NULL);
    if (dir == NULL) {
        return;
    }
    for (int k = 1; k <= PLANE_ITERATIONS; ++k) {
        char path[4400];
        snprintf(path, sizeof path, "%s/out/mask.%04d.exr", dir, k);
        if (k == PLANE_ITERATIONS) {
            snprintf(path, sizeof path, "%s/out/mask.exr", dir);
        }
        int w = 0, h = 0;
        float *rust = ensure_read_channel(path, "rust.Y", &w, &h);
        ENSURE(rust != NULL && w == PLANE_PX && h == PLANE_PX);
        if (rust == NULL) {
            return;
        }
        // The disc around the seed texels: distance from their centres.
        double reach = k * RADIUS_M, inside_max = 0.0, outside_min = 1e9;
        int missing = 0, extra = 0;
        for (int j = 0; j < h; ++j) {
            for (int i = 0; i < w; ++i) {
                double x = ((i + 0.5) / w - 0.5) * 2.4, z = ((j + 0.5) / h - 0.5) * 2.4;
                double dx = fmax(fabs(x) - SEED_HALF_M, 0.0), dz = fmax(fabs(z) - SEED_HALF_M, 0.0);
                double d = sqrt(dx * dx + dz * dz);
                bool holds = rust[(size_t)j * (size_t)w + (size_t)i] > 0.5f;
                if (holds) {
                    inside_max = fmax(inside_max, d);
                    extra += d > reach + TEXEL_M;
                } else {
                    outside_min = fmin(outside_min, d);
                    missing += d < reach - TEXEL_M;
                }
            }
        }
        printf("        iteration %d: holders reach %.4f m, the first point without %.4f m "
               "(exact %.4f), %d missing, %d beyond\n",
               k, inside_max, outside_min, reach, missing, extra);
        ENSURE(missing == 0 && extra == 0);
        ENSURE(fabs(inside_max - reach) <= TEXEL_M);
        free(rust);
    }
}

TEST(seed_density_gives_the_poisson_expectation)
{
    const char *dir = plane_dir();
    ENSURE(dir != NULL);
    if (dir == NULL) {
        return;
    }
    // Iteration 1's seeds: each texel of the plane (area TEXEL_M^2, owned by
    // the one camera) is seeded with probability 1 - exp(-density * area).
    char path[4400];
    snprintf(path, sizeof path, "%s/out/mask.0001.exr", dir);
    int w = 0, h = 0;
    float *spot = ensure_read_channel(path, "spot.Y", &w, &h);
    ENSURE(spot != NULL);
    if (spot == NULL) {
        return;
    }
    int seeds = 0, points = 0;
    for (int j = 0; j < h; ++j) {
        for (int i = 0; i < w; ++i) {
            double x = ((i + 0.5) / w - 0.5) * 2.4, z = ((j + 0.5) / h - 0.5) * 2.4;
            if (fabs(x) < 1.0 && fabs(z) < 1.0) {
                points++;
                seeds += spot[(size_t)j * (size_t)w + (size_t)i] > 0.5f;
            }
        }
    }
    double p = -expm1(-SPOT_DENSITY * TEXEL_M * TEXEL_M);
    double mean = points * p, sd = sqrt(points * p * (1.0 - p));
    printf("        %d seeds on %d points: expected %.1f +- %.1f (%.1f per square metre, "
           "density %g)\n",
           seeds, points, mean, sd, seeds / 4.0, SPOT_DENSITY);
    ENSURE(points == 200 * 200);
    ENSURE(fabs(seeds - mean) <= 3.0 * sd);
    free(spot);
}

TEST(the_ledger_counts_seeded_and_spread_amounts_as_grown)
{
    const char *dir = plane_dir();
    ENSURE(dir != NULL);
    if (dir == NULL) {
        return;
    }
    char path[4400];
    snprintf(path, sizeof path, "%s/stats.json", dir);
    char *json = ensure_read_file(path);
    ENSURE(json != NULL);
    if (json == NULL) {
        return;
    }
    const char *names[2] = { "rust", "spot" };
    for (int s = 0; s < 2; ++s) {
        char key[32];
        snprintf(key, sizeof key, "\"%s\": {", names[s]);
        const char *at = strstr(json, key);
        ENSURE(at != NULL);
        if (at == NULL) {
            continue;
        }
        double in, out;
        ensure_ledger_sides(at, &in, &out);
        double grown = ensure_json_number(at, NULL, "grown");
        printf("        %s: in %.17g, out %.17g, grown %.6g\n", names[s], in, out, grown);
        ENSURE(grown > 0.0);
        ENSURE(fabs(in - out) <= 1e-9 * (fabs(in) + 1.0));
    }
    // The rust disc after 4 iterations: radius 0.2 m within a texel around
    // the seed texels' centres (a 1 cm square), 1 per square metre.
    const char *rust = strstr(json, "\"rust\": {");
    double final = rust != NULL ? ensure_json_number(rust, NULL, "final_surface") : 0.0;
    double lo = 3.14159265 * 0.19 * 0.19 + 4 * 0.01 * 0.19 + 0.01 * 0.01;
    double hi = 3.14159265 * 0.21 * 0.21 + 4 * 0.01 * 0.21 + 0.01 * 0.01;
    printf("        rust over the plane: %.5f m^2 (the disc within a texel: %.5f to %.5f)\n", final,
           lo, hi);
    ENSURE(final > lo && final < hi);
    free(json);
}

TEST(one_and_two_threads_give_the_same_bytes)
{
    const char *two = plane_dir();
    ENSURE(two != NULL);
    const char *one = run_plane("spread_plane_one", PLANE_RULES, "--threads 1");
    ENSURE(one != NULL);
    if (one == NULL || two == NULL) {
        return;
    }
    char log[8192];
    const char *files[] = { "mask.exr", "mask.0001.exr", "mask.0002.exr", "top_dirt.exr" };
    for (size_t k = 0; k < sizeof files / sizeof files[0]; ++k) {
        ENSURE(ensure_shell(log, sizeof log, "cmp -s '%s/spread_plane/out/%s' '%s/out/%s'",
                            ensure_tmpdir(), files[k], one, files[k]) == 0);
    }
}

// A cylinder of radius 0.5 around the y axis, y in [-0.5, 0.5], of 64 slices;
// u = angle / 2 pi (the seam along +x, angle 0), v = y + 0.5. Slice 0 (angle
// 0 to 2 pi / 64, just past the seam) holds the "seed" band |y| < 0.05.
static bool write_cylinder(const char *dir)
{
    char path[4400];
    snprintf(path, sizeof path, "%s/cylinder.obj", dir);
    FILE *f = fopen(path, "w");
    if (f == NULL) {
        return false;
    }
    enum { SLICES = 64 };
    static const double ys[4] = { -0.5, -0.05, 0.05, 0.5 };
    fprintf(f, "mtllib cylinder.mtl\n");
    for (int s = 0; s <= SLICES; ++s) {
        double a = 2.0 * 3.14159265358979323846 * s / SLICES;
        for (int b = 0; b < 4; ++b) {
            fprintf(f, "v %.9f %.9f %.9f\n", 0.5 * cos(a), ys[b], -0.5 * sin(a));
            fprintf(f, "vt %.9f %.9f\n", (double)s / SLICES, ys[b] + 0.5);
        }
        fprintf(f, "vn %.9f 0 %.9f\n", cos(a), -sin(a));
    }
    for (int b = 0; b < 3; ++b) {
        for (int s = 0; s < SLICES; ++s) {
            bool seed = s == 0 && b == 1;
            fprintf(f, "usemtl %s\n", seed ? "seed" : "iron");
            int v0 = 4 * s + b + 1, v1 = 4 * (s + 1) + b + 1;
            int n0 = s + 1, n1 = s + 2;
            fprintf(f, "f %d/%d/%d %d/%d/%d %d/%d/%d %d/%d/%d\n", v0, v0, n0, v1, v1, n1, v1 + 1,
                    v1 + 1, n1, v0 + 1, v0 + 1, n0);
        }
    }
    fclose(f);
    return true;
}

static const char CYLINDER_XML[] =
    "<Weathering>\n"
    "  <Substances><Substance name=\"rust\"/></Substances>\n"
    "  <Solver><Simulation timeStep=\"0.01\" steps=\"2\" seed=\"3\" iterations=\"2\"/>"
    "<BoundingBox size=\"8\"/></Solver>\n"
    "  <Ageing><Spread substance=\"rust\" radius=\"0.1\"/></Ageing>\n"
    "  <Collider><ProjectedMaps>\n"
    "    <Ortho cameraName=\"px\"><View eye=\"5 0 0\" target=\"0 0 0\" width=\"1.2\" "
    "height=\"1.2\" resolution=\"240\"/></Ortho>\n"
    "    <Ortho cameraName=\"nx\"><View eye=\"-5 0 0\" target=\"0 0 0\" width=\"1.2\" "
    "height=\"1.2\" resolution=\"240\"/></Ortho>\n"
    "    <Ortho cameraName=\"pz\"><View eye=\"0 0 5\" target=\"0 0 0\" width=\"1.2\" "
    "height=\"1.2\" resolution=\"240\"/></Ortho>\n"
    "    <Ortho cameraName=\"nz\"><View eye=\"0 0 -5\" target=\"0 0 0\" width=\"1.2\" "
    "height=\"1.2\" resolution=\"240\"/></Ortho>\n"
    "  </ProjectedMaps></Collider>\n"
    "  <Geometry><Mesh file=\"cylinder.obj\">\n"
    "    <Surface material=\"iron\"/>\n"
    "    <Surface material=\"seed\"><Exchange substance=\"rust\" initial=\"1\"/></Surface>\n"
    "    <TextureMap file=\"cylinder.exr\" width=\"256\" height=\"64\" padding=\"0\"/>\n"
    "  </Mesh></Geometry>\n"
    "</Weathering>\n";

TEST(spread_crosses_the_texture_seam_around_a_cylinder)
{
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/spread_cylinder", ensure_tmpdir());
    mkdir(dir, 0777);
    ENSURE(write_cylinder(dir));
    ensure_write_file(dir, "cylinder.mtl", PLANE_MTL);
    ensure_write_file(dir, "scene.xml", CYLINDER_XML);
    ENSURE(run_scene(dir, ""));
    char path[4400];
    snprintf(path, sizeof path, "%s/out/cylinder.exr", dir);
    int w = 0, h = 0;
    float *rust = ensure_read_channel(path, "rust.Y", &w, &h);
    ENSURE(rust != NULL && w == 256 && h == 64);
    if (rust == NULL) {
        return;
    }
    // The middle row (y = 0): the seed's slice spans u in [0, 1/64], so two
    // iterations of 0.1 m (0.2 / pi = 0.064 of the circumference, 16 columns)
    // reach u = 1/64 + 0.064 ahead and u = 1 - 0.064 behind the seam.
    int row = h / 2;
    const float *r = &rust[(size_t)row * (size_t)w];
    int before = 0, after = 0, far = 0;
    for (int i = 0; i < w; ++i) {
        bool holds = r[i] > 0.5f;
        double u = (i + 0.5) / w;
        before += holds && u > 0.5;
        after += holds && u < 0.5;
        far += holds && u > 0.25 && u < 0.75;
    }
    printf("        row y = 0: %d texels hold rust past the seam (u near 1), %d before it, "
           "%d far away; u = 0.995: %g, u = 0.005: %g\n",
           before, after, far, r[w - 1], r[0]);
    ENSURE(r[w - 1] > 0.5f && r[0] > 0.5f);
    // 0.064 of 256 columns = 16.3: the band behind the seam within a column.
    ENSURE(before >= 15 && before <= 18);
    ENSURE(far == 0);
    free(rust);
    snprintf(path, sizeof path, "%s/stats.json", dir);
    char *json = ensure_read_file(path);
    ENSURE(json != NULL);
    if (json != NULL) {
        double in, out;
        ensure_ledger_sides(strstr(json, "\"rust\": {"), &in, &out);
        ENSURE(fabs(in - out) <= 1e-9 * (fabs(in) + 1.0));
        free(json);
    }
}

// Crack and Peel on the plane: the seed square (4 texels) holds "rust" as a
// crack; each tip takes one point 1.5 to 3 cm away per iteration, so after 4
// iterations the crack holds 5 to 20 points, each (but the square's) within
// 3 cm of another; "spot" peels from the crack with probability 1 within 2 cm
// per iteration, so after 4 lies within 8 cm of a crack point.
TEST(a_crack_grows_a_line_and_paint_peels_from_it)
{
    const char *dir = run_plane("spread_crack",
                                "    <Crack substance=\"rust\" radius=\"0.03\" strength=\"0.5\"/>\n"
                                "    <Peel substance=\"spot\" from=\"rust\" radius=\"0.02\"/>\n",
                                "");
    ENSURE(dir != NULL);
    if (dir == NULL) {
        return;
    }
    char path[4400];
    snprintf(path, sizeof path, "%s/out/mask.exr", dir);
    int w = 0, h = 0;
    float *crack = ensure_read_channel(path, "rust.Y", &w, &h);
    float *peel = ensure_read_channel(path, "spot.Y", &w, &h);
    ENSURE(crack != NULL && peel != NULL);
    if (crack == NULL || peel == NULL) {
        free(crack);
        free(peel);
        return;
    }
    enum { MAX_CRACK = 64 };
    double cx[MAX_CRACK], cz[MAX_CRACK];
    int n = 0, peeled = 0, stray = 0, lonely = 0;
    for (int t = 0; t < w * h; ++t) {
        if (crack[t] > 0.5f && n < MAX_CRACK) {
            cx[n] = ((t % w + 0.5) / w - 0.5) * 2.4;
            cz[n++] = ((t / w + 0.5) / h - 0.5) * 2.4;
        }
    }
    for (int a = 0; a < n; ++a) {
        bool seed = fabs(cx[a]) < 0.01 && fabs(cz[a]) < 0.01;
        bool near = false;
        for (int b = 0; b < n && !seed; ++b) {
            double d = hypot(cx[a] - cx[b], cz[a] - cz[b]);
            near = near || (b != a && d <= 0.03 + 1e-6);
        }
        lonely += !seed && !near;
    }
    for (int t = 0; t < w * h; ++t) {
        if (!(peel[t] > 0.5f)) {
            continue;
        }
        peeled++;
        double x = ((t % w + 0.5) / w - 0.5) * 2.4, z = ((t / w + 0.5) / h - 0.5) * 2.4;
        double nearest = 1e9;
        for (int a = 0; a < n; ++a) {
            nearest = fmin(nearest, hypot(x - cx[a], z - cz[a]));
        }
        stray += nearest > 4 * 0.02 + TEXEL_M;
    }
    printf("        crack: %d points (%d not within 3 cm of another); peel: %d points, %d "
           "farther than 8 cm from the crack\n",
           n, lonely, peeled, stray);
    ENSURE(n > 4 && n <= 4 + 4 * 4);
    ENSURE(lonely == 0);
    ENSURE(peeled > 0 && stray == 0);
    free(crack);
    free(peel);
    snprintf(path, sizeof path, "%s/stats.json", dir);
    char *json = ensure_read_file(path);
    ENSURE(json != NULL);
    const char *names[2] = { "\"rust\": {", "\"spot\": {" };
    for (int s = 0; s < 2 && json != NULL; ++s) {
        double in, out;
        ensure_ledger_sides(strstr(json, names[s]), &in, &out);
        ENSURE(fabs(in - out) <= 1e-9 * (fabs(in) + 1.0));
    }
    free(json);
}

int main(void)
{
    RUN(spread_grows_a_disc_by_the_radius_every_iteration);
    RUN(seed_density_gives_the_poisson_expectation);
    RUN(the_ledger_counts_seeded_and_spread_amounts_as_grown);
    RUN(one_and_two_threads_give_the_same_bytes);
    RUN(spread_crosses_the_texture_seam_around_a_cylinder);
    RUN(a_crack_grows_a_line_and_paint_peels_from_it);
    return ensure_summary();
}
