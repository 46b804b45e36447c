// test_analytic.c: whole runs (`weathering run`) on scenes whose masks are known
// exactly, with a box emitter and the adaptive gather (issue 15; docs/mask.md).
//
//  - A unit sphere under vertical rain from a flat box (no forces, absorption
//    1): N particles from a rectangle of area A put flux N/A on every
//    horizontal plane, so the surface density is (N/A) * max(0, N.y). Output
//    camera 1024 px over 2.4 m, looking down.
//  - A wall under an overhang in rain slanting at 45 degrees towards it: the
//    overhang's front edge (y = 3, 1 m out) casts the shadow edge y = 2 on the
//    wall; below it the wall takes N/A per square metre, above it nothing;
//    and the same turned 30 degrees in the camera grid (issue 25).
//  - A coarse lumpy sphere with UVs under vertical rain, as it is and turned
//    30 degrees: its TextureMap against the exact F max(0, N.y) (issue 25).
#define _XOPEN_SOURCE 700 // realpath
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ensure.h"
#include "sphere_fixture.h"

static char out[65536];

static bool run_scene(const char *dir, const char *scene, const char *name)
{
    char build[PATH_MAX];
    if (realpath(ensure_build_dir(), build) == NULL) {
        return false;
    }
    int status = ensure_shell(out, sizeof out, "cd '%s' && '%s/weathering' run %s --out %s -q",
                              dir, build, scene, name);
    if (status != 0) {
        fprintf(stderr, "        %s", out);
    }
    return status == 0;
}

// 8 million particles (1.39 million per square metre): at most 5% RMSE and every
// ring's mean within 2%; a quarter of them: at most 7% and 3%.
TEST(sphere_under_rain_from_a_box)
{
    SLOW();
    const char *dir = ensure_tmpdir();
    char mesh[4200];
    snprintf(mesh, sizeof mesh, "%s/sphere.ply", dir);
    ENSURE(sphere_write_mesh(mesh, 256, 512));
    const double counts[2] = { 8e6, 2e6 }, rmse_max[2] = { 0.05, 0.07 }, ring_max[2] = { 0.02, 0.03 };
    for (int k = 0; k < 2; ++k) {
        char name[64], folder[64], path[4300], emitter[512];
        snprintf(name, sizeof name, "sphere_%d.xml", k);
        snprintf(folder, sizeof folder, "sphere_%d", k);
        snprintf(emitter, sizeof emitter,
                 "<BoxEmitter minX=\"-1.2\" minY=\"1.2\" minZ=\"-1.2\" maxX=\"1.2\" maxY=\"1.2\" "
                 "maxZ=\"1.2\" rate=\"%.0f\" end=\"1\" speed=\"10\"/>",
                 counts[k]);
        sphere_write_scene(dir, name, emitter, 4.0, 0.02, 60, "");
        ENSURE(run_scene(dir, name, folder));
        snprintf(path, sizeof path, "%s/%s/mask.exr", dir, folder);
        int w, h;
        float *mask = ensure_read_channel(path, "Y", &w, &h);
        ENSURE(mask != NULL && w == 1024 && h == 1024);
        double rmse, ring;
        sphere_errors(mask, w, h, sphere_box_density, counts[k], &rmse, &ring);
        free(mask);
        printf("        %.0f particles: relative RMSE %.4f, worst ring %.4f\n", counts[k], rmse,
               ring);
        ENSURE(rmse <= rmse_max[k]);
        ENSURE(ring <= ring_max[k]);
    }
}

// A sky dome of radius 3 aimed at the sphere's foot (sphere_fixture.h): the
// density N / (4 pi sqrt(2 (1 + n.y))) is 1.5 times higher at the rim of the
// evaluated region than at the top; 2 million particles, every ring's mean
// within 3% and the RMSE at most 8% (the adaptive gather aims at 4%, the dome's
// particles are spread over the whole upper half of the sphere).
TEST(sphere_under_a_dome_aimed_at_its_foot)
{
    SLOW();
    const char *dir = ensure_tmpdir();
    char mesh[4200], path[4300];
    snprintf(mesh, sizeof mesh, "%s/sphere.ply", dir);
    ENSURE(sphere_write_mesh(mesh, 256, 512));
    sphere_write_scene(dir, "dome.xml",
                       "<HemisphereEmitter centerY=\"-1\" radius=\"3\" rate=\"2000000\" end=\"1\" "
                       "speed=\"10\"/>",
                       8.0, 0.02, 70, "");
    ENSURE(run_scene(dir, "dome.xml", "dome"));
    snprintf(path, sizeof path, "%s/dome/mask.exr", dir);
    int w, h;
    float *mask = ensure_read_channel(path, "Y", &w, &h);
    ENSURE(mask != NULL);
    double rmse, ring;
    sphere_errors(mask, w, h, sphere_dome_density, 2e6, &rmse, &ring);
    free(mask);
    printf("        dome: relative RMSE %.4f, worst ring %.4f\n", rmse, ring);
    ENSURE(rmse <= 0.08);
    ENSURE(ring <= 0.03);
}

static const char *overhang_mesh =
    "# a wall x -2..2, y 0..3.2, z -0.3..0; an overhang x -2..2, y 3..3.2, z 0..1\n"
    "v -2 0 -0.3\nv 2 0 -0.3\nv 2 3.2 -0.3\nv -2 3.2 -0.3\n"
    "v -2 0 0\nv 2 0 0\nv 2 3.2 0\nv -2 3.2 0\n"
    "f 5 6 7\nf 5 7 8\nf 2 1 4\nf 2 4 3\nf 1 5 8\nf 1 8 4\nf 6 2 3\nf 6 3 7\n"
    "f 8 7 3\nf 8 3 4\nf 1 2 6\nf 1 6 5\n"
    "v -2 3 0\nv 2 3 0\nv 2 3.2 0\nv -2 3.2 0\n"
    "v -2 3 1\nv 2 3 1\nv 2 3.2 1\nv -2 3.2 1\n"
    "f 13 14 15\nf 13 15 16\nf 9 13 16\nf 9 16 12\nf 14 10 11\nf 14 11 15\n"
    "f 16 15 11\nf 16 11 12\nf 9 10 14\nf 9 14 13\n";

static const char *overhang_scene =
    "<Weathering>\n"
    "  <Solver>\n"
    "    <BoundingBox size=\"16\" centerX=\"0\" centerY=\"2\" centerZ=\"2\"/>\n"
    "    <Simulation timeStep=\"0.02\" steps=\"120\" seed=\"3\"/>\n"
    "  </Solver>\n"
    "  <Emitters>\n"
    "    <BoxEmitter minX=\"-2\" minY=\"6\" minZ=\"2.5\" maxX=\"2\" maxY=\"6\" maxZ=\"6.5\"\n"
    "                dirX=\"0\" dirY=\"-1\" dirZ=\"-1\" rate=\"2000000\" end=\"1\" speed=\"10\"/>\n"
    "  </Emitters>\n"
    "  <Collider>\n"
    "    <ProjectedMaps>\n"
    "      <Ortho cameraName=\"front\">\n"
    "        <View eye=\"0 1.6 10\" target=\"0 1.6 0\" up=\"0 1 0\" width=\"4\" height=\"4\"\n"
    "              resolution=\"512\"/>\n"
    "      </Ortho>\n"
    "      <Ortho cameraName=\"top\">\n"
    "        <View eye=\"0 10 0.5\" target=\"0 0 0.5\" up=\"0 0 -1\" width=\"4\" height=\"4\"\n"
    "              resolution=\"512\"/>\n"
    "      </Ortho>\n"
    "      <Ortho cameraName=\"shot\" out=\"true\">\n"
    "        <View eye=\"0 1.6 10\" target=\"0 1.6 0\" up=\"0 1 0\" width=\"4\" height=\"4\"\n"
    "              resolution=\"512\"/>\n"
    "      </Ortho>\n"
    "    </ProjectedMaps>\n"
    "  </Collider>\n"
    "  <Geometry>\n"
    "    <Mesh file=\"wall.obj\"><Surface material=\"*\" absorption=\"1\"/></Mesh>\n"
    "  </Geometry>\n"
    "</Weathering>\n";

// Writes the wall mesh and the scene, runs it into NAME/ and reads the 512 x
// 512 mask (NULL on any failure).
static float *run_wall(const char *dir, const char *mesh, const char *scene_text,
                       const char *name)
{
    char scene[256], path[4300];
    snprintf(scene, sizeof scene, "%s.xml", name);
    ensure_write_file(dir, "wall.obj", mesh);
    ensure_write_file(dir, scene, scene_text);
    if (!run_scene(dir, scene, name)) {
        return NULL;
    }
    snprintf(path, sizeof path, "%s/%s/mask.exr", dir, name);
    int w = 0, h = 0;
    float *mask = ensure_read_channel(path, "Y", &w, &h);
    if (mask != NULL && (w != 512 || h != 512)) {
        free(mask);
        return NULL;
    }
    return mask;
}

// The shadow of the overhang: 2 million particles from 16 m^2 put 125000 per
// square metre on the wall below y = 2 and none above. The edge rises from 10%
// to 90% within 8 output texels (7.8 mm each), the sheltered band (y 2.1 to 2.95)
// holds at most 2% of the exposed wall's mean, which is within 3% of exact.
TEST(wall_under_an_overhang_in_slanting_rain)
{
    SLOW();
    float *mask = run_wall(ensure_tmpdir(), overhang_mesh, overhang_scene, "overhang");
    ENSURE(mask != NULL);
    const int w = 512, h = 512;
    // Rows averaged over |x| < 1.5; row j at y = 3.6 - 4 (j + 0.5) / 512.
    double profile[512];
    for (int j = 0; j < h; ++j) {
        double s = 0.0;
        int n = 0;
        for (int i = 0; i < w; ++i) {
            double x = -2.0 + 4.0 * (i + 0.5) / w;
            if (fabs(x) < 1.5) {
                s += mask[(size_t)j * w + i];
                n++;
            }
        }
        profile[j] = s / n;
    }
    free(mask);
    double exposed = 0.0, band = 0.0;
    int ne = 0, nb = 0;
    for (int j = 0; j < h; ++j) {
        double y = 3.6 - 4.0 * (j + 0.5) / h;
        if (y > 0.3 && y < 1.7) {
            exposed += profile[j];
            ne++;
        } else if (y > 2.1 && y < 2.95) {
            band += profile[j];
            nb++;
        }
    }
    exposed /= ne;
    band /= nb;
    int j10 = -1, j90 = -1; // going down from the band: first rows above 10% and 90%
    for (int j = 0; j < h; ++j) {
        double y = 3.6 - 4.0 * (j + 0.5) / h;
        if (y > 2.6 || y < 1.4) {
            continue;
        }
        if (j10 < 0 && profile[j] >= 0.1 * exposed) {
            j10 = j;
        }
        if (j90 < 0 && profile[j] >= 0.9 * exposed) {
            j90 = j;
        }
    }
    printf("        exposed %.1f (exact 125000), band %.4f%% of it, rise %d texels\n", exposed,
           100.0 * band / exposed, j90 - j10);
    ENSURE_NEAR(exposed, 125000.0, 0.03 * 125000.0);
    ENSURE(band <= 0.02 * exposed);
    ENSURE(j10 >= 0 && j90 >= j10 && j90 - j10 <= 8);
}

// The same wall and overhang turned 30 degrees about the vertical, so the
// shadow's edge runs at 30 degrees to the input cameras' texel rows and columns
// (issue 25, item 3): input cameras 384 px over 6 m (15.6 mm texels), the
// output camera 512 px over 4 m facing the wall (7.8 mm as above, two pixels
// to an input texel). In every input-texel-wide column of the output the 50%
// level of the exposed wall's mean is found going down from the shelter; a
// straight line fitted to those points leaves at most 0.5 input texel RMS, and
// the edge rises from 10% to 90% within 8 output texels, as above. Before the
// cameras that frame the model vouched for the space outside their frames,
// particles passing beside this wall were caught behind it, and its lower
// half took 1.75 times the rain.
static void rotated_overhang_mesh(char *obj, size_t size)
{
    // Two boxes: the wall x -2..2, y 0..3.2, z -0.3..0 and the overhang
    // x -2..2, y 3..3.2, z 0..1, turned by 30 degrees about +y.
    static const double box[2][2][3] = { { { -2, 0, -0.3 }, { 2, 3.2, 0 } },
                                         { { -2, 3, 0 }, { 2, 3.2, 1 } } };
    static const int faces[12][3] = { { 5, 6, 7 }, { 5, 7, 8 }, { 2, 1, 4 }, { 2, 4, 3 },
                                      { 1, 5, 8 }, { 1, 8, 4 }, { 6, 2, 3 }, { 6, 3, 7 },
                                      { 8, 7, 3 }, { 8, 3, 4 }, { 1, 2, 6 }, { 1, 6, 5 } };
    const double c = cos(M_PI / 6.0), s = sin(M_PI / 6.0);
    size_t n = 0;
    for (int b = 0; b < 2; ++b) {
        for (int v = 0; v < 8; ++v) {
            // The corner order of overhang_mesh: z low for 1-4, high for 5-8;
            // x, y going round (-,-) (+,-) (+,+) (-,+).
            double x = box[b][(v % 4 == 1 || v % 4 == 2) ? 1 : 0][0];
            double y = box[b][(v % 4 >= 2) ? 1 : 0][1];
            double z = box[b][v >= 4 ? 1 : 0][2];
            n += (size_t)snprintf(obj + n, size - n, "v %.7f %.7f %.7f\n", c * x + s * z, y,
                                  -s * x + c * z);
        }
        for (int f = 0; f < 12; ++f) {
            n += (size_t)snprintf(obj + n, size - n, "f %d %d %d\n", faces[f][0] + 8 * b,
                                  faces[f][1] + 8 * b, faces[f][2] + 8 * b);
        }
    }
}

static const char *rotated_overhang_scene =
    "<Weathering>\n"
    "  <Solver>\n"
    "    <BoundingBox size=\"20\" centerX=\"0\" centerY=\"2\" centerZ=\"0\"/>\n"
    "    <Simulation timeStep=\"0.02\" steps=\"120\" seed=\"3\"/>\n"
    "  </Solver>\n"
    "  <Emitters>\n"
    "    <BoxEmitter minX=\"-0.482051\" minY=\"6\" minZ=\"1.165064\" maxX=\"4.982051\" maxY=\"6\"\n"
    "                maxZ=\"6.629165\" dirX=\"-0.5\" dirY=\"-1\" dirZ=\"-0.8660254\"\n"
    "                rate=\"3732050\" end=\"1\" speed=\"10\"/>\n"
    "  </Emitters>\n"
    "  <Collider>\n"
    "    <ProjectedMaps>\n"
    "      <Ortho cameraName=\"front\">\n"
    "        <View eye=\"0 1.6 10\" target=\"0 1.6 0\" up=\"0 1 0\" width=\"6\" height=\"6\"\n"
    "              resolution=\"384\"/>\n"
    "      </Ortho>\n"
    "      <Ortho cameraName=\"top\">\n"
    "        <View eye=\"0 10 0.5\" target=\"0 0 0.5\" up=\"0 0 -1\" width=\"6\" height=\"6\"\n"
    "              resolution=\"384\"/>\n"
    "      </Ortho>\n"
    "      <Ortho cameraName=\"right\">\n"
    "        <View eye=\"10 1.6 0\" target=\"0 1.6 0\" up=\"0 1 0\" width=\"6\" height=\"6\"\n"
    "              resolution=\"384\"/>\n"
    "      </Ortho>\n"
    "      <Ortho cameraName=\"shot\" out=\"true\">\n"
    "        <View eye=\"5 1.6 8.6602540\" target=\"0 1.6 0\" up=\"0 1 0\" width=\"4\"\n"
    "              height=\"4\" resolution=\"512\"/>\n"
    "        <OutputMap file=\"mask.exr\"/>\n"
    "      </Ortho>\n"
    "    </ProjectedMaps>\n"
    "  </Collider>\n"
    "  <Geometry>\n"
    "    <Mesh file=\"wall.obj\"><Surface material=\"*\" absorption=\"1\"/></Mesh>\n"
    "  </Geometry>\n"
    "</Weathering>\n";

TEST(shelter_edge_at_30_degrees_to_the_cameras_is_straight)
{
    SLOW();
    char obj[4096];
    rotated_overhang_mesh(obj, sizeof obj);
    float *mask = run_wall(ensure_tmpdir(), obj, rotated_overhang_scene, "turned");
    ENSURE(mask != NULL);
    const int w = 512, h = 512;
    // Output pixel (i, j) is at x = -2 + 4 (i + 0.5) / 512 along the wall,
    // y = 3.6 - 4 (j + 0.5) / 512.
    double exposed = 0.0;
    size_t ne = 0;
    for (int j = 0; j < h; ++j) {
        double y = 3.6 - 4.0 * (j + 0.5) / h;
        for (int i = 0; i < w && y > 0.3 && y < 1.7; ++i) {
            if (fabs(-2.0 + 4.0 * (i + 0.5) / w) < 1.5) {
                exposed += mask[(size_t)j * w + i];
                ne++;
            }
        }
    }
    exposed /= (double)ne;
    // One point per column of 2 output pixels (one input texel) over |x| < 1.5.
    enum { GROUP = 2, MAX_POINTS = 512 / GROUP };
    double px[MAX_POINTS], py[MAX_POINTS], rise = 0.0;
    int np = 0;
    for (int i0 = 0; i0 + GROUP <= w; i0 += GROUP) {
        double x = -2.0 + 4.0 * (i0 + 0.5 * GROUP) / w;
        if (fabs(x) > 1.5) {
            continue;
        }
        double prof[512];
        for (int j = 0; j < h; ++j) {
            prof[j] = 0.0;
            for (int i = i0; i < i0 + GROUP; ++i) {
                prof[j] += mask[(size_t)j * w + i] / GROUP;
            }
        }
        // Down from y = 2.6 (in the shelter): the first rows at 10%, 50%, 90%.
        int j_top = (int)((3.6 - 2.6) * h / 4.0), j_bottom = (int)((3.6 - 1.4) * h / 4.0);
        int j10 = -1, j50 = -1, j90 = -1;
        for (int j = j_top; j < j_bottom; ++j) {
            if (j10 < 0 && prof[j] >= 0.1 * exposed) {
                j10 = j;
            }
            if (j50 < 0 && prof[j] >= 0.5 * exposed) {
                j50 = j;
            }
            if (j90 < 0 && prof[j] >= 0.9 * exposed) {
                j90 = j;
            }
        }
        if (!(j10 > j_top && j50 >= j10 && j90 >= j50)) {
            printf("        column x %.3f: rows %d %d %d from %d\n", x, j10, j50, j90, j_top);
        }
        ENSURE(j10 > j_top && j50 >= j10 && j90 >= j50);
        double f = (0.5 * exposed - prof[j50 - 1]) / (prof[j50] - prof[j50 - 1]);
        px[np] = x;
        py[np] = j50 - 1 + f;
        rise += j90 - j10;
        np++;
    }
    free(mask);
    // Least-squares line through the points; the RMS of what it leaves.
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (int k = 0; k < np; ++k) {
        sx += px[k];
        sy += py[k];
        sxx += px[k] * px[k];
        sxy += px[k] * py[k];
    }
    double slope = (np * sxy - sx * sy) / (np * sxx - sx * sx);
    double offset = (sy - slope * sx) / np;
    double ss = 0.0;
    for (int k = 0; k < np; ++k) {
        double r = py[k] - (offset + slope * px[k]);
        ss += r * r;
    }
    double rms_texels = sqrt(ss / np) / GROUP; // output pixels to an input texel
    printf("        exposed %.1f (exact 125000), 50%% line at y %.4f + %.4f x, "
           "RMS off it %.3f input texel, mean 10-90%% rise %.1f texels\n",
           exposed, 3.6 - 4.0 * (offset + 0.5) / h, -4.0 * slope / h, rms_texels, rise / np);
    ENSURE_NEAR(exposed, 125000.0, 0.03 * 125000.0);
    ENSURE(fabs(slope) < 0.01 * h / 4.0); // the edge is level: y = 2 all along
    ENSURE(fabs(3.6 - 4.0 * (offset + 0.5) / h - 2.0) <= 0.05); // and where it should be
    ENSURE(rms_texels <= 0.5);
    ENSURE(rise / np <= 8.0);
}

// --- A coarse lumpy sphere under vertical rain, turned in the camera grid ----
//
// Issue 25, item 1: tests/tools/lumpy_sphere.sh's model (radius 1 with lumps of
// 0.12 and 0.08, 24 x 12 segments, equirectangular UVs), every drop absorbed at
// its first hit, so the exact density is F max(0, N.y) (F drops per square
// metre across the box), which the scene's <Exposure elevation="90"> mask
// writes beside the dirt in the same TextureMap. Once as it is and once turned
// 30 degrees about the vertical, with the same cameras and drops.
// Written as `name` in `dir`; inward: every face wound the other way, as an
// export with flipped normals gives it; squash: its heights scaled about
// y = 1.2 (1 for the sphere).
static void lumpy_sphere_squashed(const char *dir, const char *name, double turn_degrees,
                                  bool inward, double squash)
{
    static char obj[200000];
    const size_t size = sizeof obj;
    const int nu = 24, nv = 12;
    const double c = cos(turn_degrees * M_PI / 180.0), s = sin(turn_degrees * M_PI / 180.0);
    size_t n = 0;
    for (int j = 0; j <= nv; ++j) {
        double ph = M_PI * j / nv;
        for (int i = 0; i <= nu; ++i) {
            double th = 2.0 * M_PI * i / nu;
            double r = 1.0 + 0.12 * sin(3.0 * th) * sin(2.0 * ph) + 0.08 * cos(5.0 * ph);
            double x = r * sin(ph) * cos(th), y = squash * r * cos(ph) + 1.2;
            double z = r * sin(ph) * sin(th);
            n += (size_t)snprintf(obj + n, size - n, "v %.6f %.6f %.6f\n", c * x + s * z, y,
                                  -s * x + c * z);
        }
    }
    for (int j = 0; j <= nv; ++j) {
        for (int i = 0; i <= nu; ++i) {
            n += (size_t)snprintf(obj + n, size - n, "vt %.6f %.6f\n", (double)i / nu,
                                  1.0 - (double)j / nv);
        }
    }
    for (int j = 0; j < nv; ++j) {
        for (int i = 0; i < nu; ++i) {
            int a = j * (nu + 1) + i + 1, b = a + 1, d = a + nu + 1, e = d + 1;
            int second = inward ? e : b, third = inward ? b : e;
            if (j > 0) {
                n += (size_t)snprintf(obj + n, size - n, "f %d/%d %d/%d %d/%d\n", a, a, second,
                                      second, third, third);
            }
            second = inward ? d : e;
            third = inward ? e : d;
            if (j < nv - 1) {
                n += (size_t)snprintf(obj + n, size - n, "f %d/%d %d/%d %d/%d\n", a, a, second,
                                      second, third, third);
            }
        }
    }
    ensure_write_file(dir, name, obj);
}

static void lumpy_sphere(const char *dir, const char *name, double turn_degrees, bool inward)
{
    lumpy_sphere_squashed(dir, name, turn_degrees, inward, 1.0);
}

// 400 000 drops over 3 x 3 m: F = 44 444 per square metre. Input cameras of
// 384 px over 3 m, the TextureMap 512 x 512.
static const char *lumpy_scene =
    "<Weathering>\n"
    "  <Solver>\n"
    "    <BoundingBox size=\"8\" centerX=\"0\" centerY=\"1.2\" centerZ=\"0\"/>\n"
    "    <Simulation timeStep=\"%g\" steps=\"%d\" seed=\"%d\"/>\n"
    "  </Solver>\n"
    "  <Emitters>\n"
    "    <BoxEmitter minX=\"-1.5\" minY=\"3\" minZ=\"-1.5\" maxX=\"1.5\" maxY=\"3\" maxZ=\"1.5\"\n"
    "                dirX=\"0\" dirY=\"-1\" dirZ=\"0\" rate=\"400000\" end=\"1\" speed=\"10\"/>\n"
    "  </Emitters>\n"
    "  <Collider%s>\n"
    "    <ProjectedMaps>\n"
    "      <Ortho cameraName=\"top\"%s><View eye=\"0 5 0\" target=\"0 1.2 0\" up=\"0 0 -1\"\n"
    "        width=\"3\" height=\"3\" resolution=\"%d\"/></Ortho>\n"
    "      <Ortho cameraName=\"front\"%s><View eye=\"0 1.2 5\" target=\"0 1.2 0\" up=\"0 1 0\"\n"
    "        width=\"3\" height=\"3\" resolution=\"%d\"/></Ortho>\n"
    "      <Ortho cameraName=\"back\"%s><View eye=\"0 1.2 -5\" target=\"0 1.2 0\" up=\"0 1 0\"\n"
    "        width=\"3\" height=\"3\" resolution=\"%d\"/></Ortho>\n"
    "      <Ortho cameraName=\"left\"%s><View eye=\"-5 1.2 0\" target=\"0 1.2 0\" up=\"0 1 0\"\n"
    "        width=\"3\" height=\"3\" resolution=\"%d\"/></Ortho>\n"
    "      <Ortho cameraName=\"right\"%s><View eye=\"5 1.2 0\" target=\"0 1.2 0\" up=\"0 1 0\"\n"
    "        width=\"3\" height=\"3\" resolution=\"%d\"/></Ortho>\n"
    "    </ProjectedMaps>\n"
    "  </Collider>\n"
    "  <Geometry>\n"
    "    <Mesh file=\"%s\">\n"
    "      <Surface material=\"*\" %s/>\n"
    "      <TextureMap file=\"t.exr\" resolution=\"512\" padding=\"4\"/>\n"
    "    </Mesh>\n"
    "  </Geometry>\n"
    "  <Masks><Exposure name=\"sun\" elevation=\"90\" azimuth=\"0\"/></Masks>\n"
    "</Weathering>\n";

// Every drop absorbed where it lands (the exact density is known); or, with
// `sliding`, the rain preset's collider and surfaces on finer maps and steps,
// as init makes them for a model of this size (texels of 4 mm, a step of 7 ms).
typedef struct lumpy_setup {
    const char *collider, *surface, *suffix;
    double time_step;
    int steps, resolution;
} lumpy_setup;

static const lumpy_setup ABSORB = { "", "absorption=\"1\"", "", 0.02, 100, 384 };
static const lumpy_setup SLIDE = {
    " resilience=\"0.2\" friction=\"0.9\" adherence=\"1\" deposit=\"1\" erosion=\"1\"",
    "absorption=\"0.05\" bounce=\"0.15\" deposit=\"0.3\" erosion=\"0.4\"",
    "_s",
    0.007,
    430,
    768,
};

// Runs the lumpy sphere (turned or not, seed) under a setup, and reads its
// texture's dirt, the exact shape (sun) and seen; false on failure.
static bool run_lumpy_with(const char *dir, const char *model, int seed, int layers,
                           const lumpy_setup *setup, float **dirt, float **sun, float **seen)
{
    char name[64], scene[8192], path[4300], mesh[80];
    snprintf(mesh, sizeof mesh, "%s.obj", model);
    snprintf(name, sizeof name, "%s%d_%d%s", model, seed, layers, setup->suffix);
    char file[80];
    snprintf(file, sizeof file, "%s.xml", name);
    char attr[32];
    snprintf(attr, sizeof attr, " layers=\"%d\"", layers);
    int px = setup->resolution;
    snprintf(scene, sizeof scene, lumpy_scene, setup->time_step, setup->steps, seed,
             setup->collider, attr, px, attr, px, attr, px, attr, px, attr, px, mesh,
             setup->surface);
    ensure_write_file(dir, file, scene);
    if (!run_scene(dir, file, name)) {
        return false;
    }
    snprintf(path, sizeof path, "%s/%s/t.exr", dir, name);
    int w[3], h[3];
    *dirt = ensure_read_channel(path, "dirt.Y", &w[0], &h[0]);
    *sun = ensure_read_channel(path, "sun.Y", &w[1], &h[1]);
    *seen = ensure_read_channel(path, "seen", &w[2], &h[2]);
    for (int k = 0; k < 3; ++k) {
        if (w[k] != 512 || h[k] != 512) {
            return false;
        }
    }
    return *dirt != NULL && *sun != NULL && *seen != NULL;
}

static void free_runs(float **dirt, float **sun, float **seen, int runs)
{
    for (int r = 0; r < runs; ++r) {
        free(dirt[r]);
        free(sun[r]);
        free(seen[r]);
    }
}

static bool run_lumpy(const char *dir, const char *model, int seed, int layers, float **dirt,
                      float **sun, float **seen)
{
    return run_lumpy_with(dir, model, seed, layers, &ABSORB, dirt, sun, seen);
}

// The lumpy sphere under the rain preset's sliding drops, five cameras of four
// layers, seeds 1 and 2, as it is and turned 30 degrees: over 16 x 16-texel
// blocks of the upper sphere the two orientations may differ at most
// MAX_TURN_RATIO times as much as the two seeds do. Measured (4 December
// 2026): seeds 0.0230 of the mean apart, orientations 0.0274, ratio 1.190;
// before each camera's crossings were widened by their margin
// (docs/physics.md, "Which camera's surface a particle meets") the sliding
// followed whichever camera's surface lay innermost: 0.0235, 0.0300, 1.277.
// The run is deterministic, so the bound between the two tells them apart;
// issue 25's 1.05 is not met (docs/performance.md). 6 December 2026, with the
// margins' reach at 32 texels and the fills' fix: 0.0220, 0.0256, 1.161.
// Later the same day, erosion per contact (docs/physics.md, "Dirt
// exchange"): 0.0217, 0.0237, 1.092; with the old exchange (and the edges'
// changes since) it reads 0.0222, 0.0256, 1.152: the bound keeps the gain.
// 7 December 2026, the collider's cells curved to second order
// (docs/physics.md, "Depth between texels"): 0.0219, 0.0231, 1.055, where
// the chords read 0.0217, 0.0236, 1.090; the bound keeps that gain too.
#define MAX_TURN_RATIO 1.075
TEST(lumpy_sphere_turned_slides_as_a_new_seed_does)
{
    SLOW();
    const char *dir = ensure_tmpdir();
    lumpy_sphere(dir, "lumpy.obj", 0.0, false);
    lumpy_sphere(dir, "turned.obj", 30.0, false);
    enum { RUNS = 4, W = 512, B = 16 };
    const char *model[RUNS] = { "lumpy", "lumpy", "turned", "turned" };
    const int seed[RUNS] = { 1, 2, 1, 2 };
    float *dirt[RUNS] = { NULL }, *sun[RUNS] = { NULL }, *seen[RUNS] = { NULL };
    for (int r = 0; r < RUNS; ++r) {
        ENSURE(run_lumpy_with(dir, model[r], seed[r], 4, &SLIDE, &dirt[r], &sun[r], &seen[r]));
    }
    double seeds = 0.0, turn = 0.0, mean = 0.0;
    int blocks = 0;
    for (int by = 48 / B; by < 192 / B; ++by) {
        for (int bx = 0; bx < W / B; ++bx) {
            double d[RUNS] = { 0 };
            bool ok = true;
            for (int y = by * B; y < (by + 1) * B && ok; ++y) {
                for (int x = bx * B; x < (bx + 1) * B; ++x) {
                    size_t i = (size_t)y * W + (size_t)x;
                    for (int r = 0; r < RUNS && ok; ++r) {
                        ok = seen[r][i] > 0.5f && sun[r][i] > 0.3f;
                    }
                    if (!ok) {
                        break;
                    }
                    for (int r = 0; r < RUNS; ++r) {
                        d[r] += dirt[r][i];
                    }
                }
            }
            if (!ok) {
                continue;
            }
            seeds += pow(d[1] - d[0], 2.0) + pow(d[3] - d[2], 2.0);
            turn += pow(d[2] - d[0], 2.0) + pow(d[3] - d[1], 2.0);
            mean += 0.25 * (d[0] + d[1] + d[2] + d[3]);
            blocks++;
        }
    }
    free_runs(dirt, sun, seen, RUNS);
    ENSURE(blocks >= 200);
    mean /= blocks;
    seeds = sqrt(seeds / (2.0 * blocks)) / mean;
    turn = sqrt(turn / (2.0 * blocks)) / mean;
    printf("        %d blocks of 16 x 16: seeds differ %.4f, orientations %.4f of the mean: "
           "ratio %.3f\n",
           blocks, seeds, turn, turn / seeds);
    ENSURE(turn <= MAX_TURN_RATIO * seeds);
}

// Contour lines on a flat top (docs/physics.md, "Contour lines on flat
// tops"): the lumpy sphere squashed to 0.35 of its height, a dome whose top
// the side cameras see at grazing angles, under the rain preset's sliding
// drops, five cameras of four layers. Between two of its rows' crossings a
// side camera's surface lies inside a curved top; a margin capped at two
// texels left those grooves, one per row along lines of equal height, and
// the sliding drops drew them in the top camera's hits. Binned by where the
// height of each top texel with N.y > 0.97 lies within the side cameras' rows
// (ten bins), the hits per texel (0.44 each, 64 644 texels) varied by 3.2% RMS
// from bin to bin then (0.94 to 1.05 of their mean); with the margin's reach
// at 32 texels, by 1.2% (0.99 to 1.03), about what 2 800 hits per bin leave.
// The run is deterministic, so the bound between the two tells them apart.
TEST(sliding_rain_draws_no_contours_on_a_flat_top)
{
    SLOW();
    const char *dir = ensure_tmpdir();
    lumpy_sphere_squashed(dir, "dome.obj", 0.0, false, 0.35);
    float *dirt = NULL, *sun = NULL, *seen = NULL;
    ENSURE(run_lumpy_with(dir, "dome", 1, 4, &SLIDE, &dirt, &sun, &seen));
    free(dirt);
    free(sun);
    free(seen);
    char path[4300];
    int w[3], h[3];
    snprintf(path, sizeof path, "%s/dome1_4_s/top_depth.exr", dir);
    float *depth = ensure_read_channel(path, "R", &w[0], &h[0]);
    snprintf(path, sizeof path, "%s/dome1_4_s/top_normal.exr", dir);
    float *ny = ensure_read_channel(path, "G", &w[1], &h[1]);
    snprintf(path, sizeof path, "%s/dome1_4_s/top_dirt.exr", dir);
    float *hits = ensure_read_channel(path, "hits", &w[2], &h[2]);
    ENSURE(depth != NULL && ny != NULL && hits != NULL);
    const int px = SLIDE.resolution;
    for (int k = 0; k < 3; ++k) {
        ENSURE(w[k] == px && h[k] == px);
    }
    // The top camera's eye is at y = 5; the side cameras' rows are 3 / px
    // tall from y = 1.2 - 1.5.
    enum { BINS = 10 };
    double sum[BINS] = { 0 }, count[BINS] = { 0 };
    const double row = 3.0 / px;
    for (size_t t = 0; t < (size_t)px * (size_t)px; ++t) {
        if (!(depth[t] < 1e6f) || !(ny[t] > 0.97f) || !isfinite(hits[t])) {
            continue;
        }
        double height = 5.0 - depth[t];
        double phase = (height - (1.2 - 1.5)) / row;
        int bin = (int)((phase - floor(phase)) * BINS) % BINS;
        sum[bin] += hits[t];
        count[bin] += 1.0;
    }
    free(depth);
    free(ny);
    free(hits);
    double mean = 0.0, spread = 0.0, least = INFINITY, most = 0.0, texels = 0.0;
    for (int b = 0; b < BINS; ++b) {
        ENSURE(count[b] > 500.0);
        mean += sum[b] / count[b] / BINS;
        texels += count[b];
    }
    for (int b = 0; b < BINS; ++b) {
        double r = sum[b] / count[b] / mean;
        spread += (r - 1.0) * (r - 1.0) / BINS;
        least = fmin(least, r);
        most = fmax(most, r);
    }
    spread = sqrt(spread);
    printf("        %.0f top texels with N.y > 0.97, %.2f hits each: by the height's place in "
           "the side cameras' rows %.3f to %.3f of the mean, %.4f RMS\n",
           texels, mean, least, most, spread);
    ENSURE(spread < 0.02);
}

// Measured (3 December 2026): each run within 1.6% RMS of the exact density
// over 16 x 16-texel blocks, two seeds 0.67% apart, the two orientations 1.14%
// apart. Issue 25 asks the orientations to differ at most 1.05 times as much
// as the seeds: not met (docs/performance.md); this test holds what is.
TEST(lumpy_sphere_turned_in_the_camera_grid_keeps_its_exact_rain)
{
    SLOW();
    const char *dir = ensure_tmpdir();
    lumpy_sphere(dir, "lumpy.obj", 0.0, false);
    lumpy_sphere(dir, "turned.obj", 30.0, false);
    enum { RUNS = 3, W = 512, B = 16 };
    const bool turned[RUNS] = { false, false, true };
    const int seed[RUNS] = { 1, 2, 1 };
    float *dirt[RUNS] = { NULL }, *sun[RUNS] = { NULL }, *seen[RUNS] = { NULL };
    for (int r = 0; r < RUNS; ++r) {
        ENSURE(run_lumpy(dir, turned[r] ? "turned" : "lumpy", seed[r], 1, &dirt[r], &sun[r],
                         &seen[r]));
    }
    // 16 x 16 blocks of the upper sphere (N.y > 0.3 everywhere in them) below
    // the pole's fan of thin triangles (rows 48 to 192 of 512).
    const double F = 400000.0 / 9.0;
    double err[RUNS] = { 0 }, seeds = 0.0, turn = 0.0;
    int blocks = 0;
    for (int by = 48 / B; by < 192 / B; ++by) {
        for (int bx = 0; bx < W / B; ++bx) {
            double d[RUNS] = { 0 }, exact = 0.0;
            bool ok = true;
            for (int y = by * B; y < (by + 1) * B && ok; ++y) {
                for (int x = bx * B; x < (bx + 1) * B; ++x) {
                    size_t i = (size_t)y * W + (size_t)x;
                    if (!(seen[0][i] > 0.5f && seen[2][i] > 0.5f && sun[0][i] > 0.3f)) {
                        ok = false;
                        break;
                    }
                    exact += F * sun[0][i];
                    for (int r = 0; r < RUNS; ++r) {
                        d[r] += dirt[r][i];
                    }
                }
            }
            if (!ok) {
                continue;
            }
            for (int r = 0; r < RUNS; ++r) {
                double e = d[r] / exact - 1.0;
                err[r] += e * e;
            }
            seeds += pow((d[1] - d[0]) / exact, 2.0);
            turn += pow((d[2] - d[0]) / exact, 2.0);
            blocks++;
        }
    }
    free_runs(dirt, sun, seen, RUNS);
    ENSURE(blocks >= 200);
    for (int r = 0; r < RUNS; ++r) {
        err[r] = sqrt(err[r] / blocks);
    }
    seeds = sqrt(seeds / blocks);
    turn = sqrt(turn / blocks);
    printf("        %d blocks of 16 x 16: against the exact density %.4f, %.4f (seeds 1, 2), "
           "%.4f (turned); seeds differ %.4f, orientations %.4f\n",
           blocks, err[0], err[1], err[2], seeds, turn);
    for (int r = 0; r < RUNS; ++r) {
        ENSURE(err[r] <= 0.02);
    }
    ENSURE(turn <= 0.02);
}

// The smooth surface closed along creases (docs/cameras.md, "Creases stay
// straight"): the lumpy sphere under vertical rain absorbed at its first hit,
// seen by one top camera of four layers at 2.9 mm texels. The fans at its
// poles span more than the 60 degree smoothing, so their triangles keep split
// normals at the pole; while each side curved their shared edges its own way,
// the top camera's first layer held the sphere's bottom through the cracks of
// the north pole's fan, and the south pole took the top's rain (here 10 634
// of the lower half's 93 893 seen texels). No drop can reach the lower half:
// it stays clean, exactly.
static const char *lumpy_top_scene =
    "<Weathering>\n"
    "  <Solver>\n"
    "    <BoundingBox size=\"8\" centerX=\"0\" centerY=\"1.2\" centerZ=\"0\"/>\n"
    "    <Simulation timeStep=\"0.02\" steps=\"100\" seed=\"1\"/>\n"
    "  </Solver>\n"
    "  <Emitters>\n"
    "    <BoxEmitter minX=\"-1.5\" minY=\"3\" minZ=\"-1.5\" maxX=\"1.5\" maxY=\"3\" maxZ=\"1.5\"\n"
    "                dirX=\"0\" dirY=\"-1\" dirZ=\"0\" rate=\"200000\" end=\"1\" speed=\"10\"/>\n"
    "  </Emitters>\n"
    "  <Collider>\n"
    "    <ProjectedMaps>\n"
    "      <Ortho cameraName=\"top\" layers=\"4\"><View eye=\"0 5 0\" target=\"0 1.2 0\"\n"
    "        up=\"0 0 -1\" width=\"3\" height=\"3\" resolution=\"1024\"/></Ortho>\n"
    "    </ProjectedMaps>\n"
    "  </Collider>\n"
    "  <Geometry>\n"
    "    <Mesh file=\"lumpy.obj\">\n"
    "      <Surface material=\"*\" absorption=\"1\"/>\n"
    "      <TextureMap file=\"t.exr\" resolution=\"512\" padding=\"4\"/>\n"
    "    </Mesh>\n"
    "  </Geometry>\n"
    "</Weathering>\n";

TEST(lumpy_sphere_bottom_stays_dry_under_a_layered_top_camera)
{
    SLOW();
    const char *dir = ensure_tmpdir();
    lumpy_sphere(dir, "lumpy.obj", 0.0, false);
    ensure_write_file(dir, "lumpy_top.xml", lumpy_top_scene);
    ENSURE(run_scene(dir, "lumpy_top.xml", "lumpy_top"));
    char path[4300];
    snprintf(path, sizeof path, "%s/lumpy_top/t.exr", dir);
    int w[2], h[2];
    float *dirt = ensure_read_channel(path, "Y", &w[0], &h[0]);
    float *seen = ensure_read_channel(path, "seen", &w[1], &h[1]);
    ENSURE(dirt != NULL && seen != NULL && w[0] == 512 && h[0] == 512);
    // Rows 320 on (of 512) face down; the upper rows hold the rain.
    double below = 0.0, above = 0.0;
    int64_t below_seen = 0, below_wet = 0;
    for (size_t i = 0; i < (size_t)512 * 512; ++i) {
        if (!(seen[i] > 0.5f)) {
            continue;
        }
        if (i >= (size_t)320 * 512) {
            below_seen++;
            below_wet += dirt[i] != 0.0f;
            below += dirt[i];
        } else {
            above += dirt[i];
        }
    }
    free(dirt);
    free(seen);
    printf("        lower half: %lld texels seen, %lld wet, rain %g (upper half %g)\n",
           (long long)below_seen, (long long)below_wet, below, above);
    ENSURE(below_seen > 50000);
    ENSURE(above > 0.0);
    ENSURE(below_wet == 0);
}

// Issue 26, item 6: the same sphere with every face wound the other way (the
// OBJ has no normals, so the generated ones point in, as an export with its
// normals flipped gives them). Before the import turned it outwards, its
// texture was seen on about 1% of the texels the outward sphere's was; now
// the same texels are seen and the same drops give the same rain.
TEST(lumpy_sphere_wound_inwards_weathers_as_wound_outwards)
{
    SLOW();
    const char *dir = ensure_tmpdir();
    lumpy_sphere(dir, "lumpy.obj", 0.0, false);
    lumpy_sphere(dir, "inward.obj", 0.0, true);
    float *dirt[2] = { NULL }, *sun[2] = { NULL }, *seen[2] = { NULL };
    ENSURE(run_lumpy(dir, "lumpy", 1, 1, &dirt[0], &sun[0], &seen[0]));
    ENSURE(run_lumpy(dir, "inward", 1, 1, &dirt[1], &sun[1], &seen[1]));
    enum { W = 512, B = 16 };
    int64_t seen_out = 0, seen_in = 0, differ = 0;
    double sum_out = 0.0, sum_in = 0.0, diff2 = 0.0, mean2 = 0.0;
    for (size_t i = 0; i < (size_t)W * W; ++i) {
        seen_out += seen[0][i] > 0.5f;
        seen_in += seen[1][i] > 0.5f;
        differ += (seen[0][i] > 0.5f) != (seen[1][i] > 0.5f);
        sum_out += dirt[0][i];
        sum_in += dirt[1][i];
        ENSURE(fabsf(sun[0][i] - sun[1][i]) <= 1e-3f);
    }
    for (int by = 0; by < W / B; ++by) {
        for (int bx = 0; bx < W / B; ++bx) {
            double a = 0.0, b = 0.0;
            for (int y = by * B; y < (by + 1) * B; ++y) {
                for (int x = bx * B; x < (bx + 1) * B; ++x) {
                    a += dirt[0][(size_t)y * W + (size_t)x];
                    b += dirt[1][(size_t)y * W + (size_t)x];
                }
            }
            diff2 += (a - b) * (a - b);
            mean2 += a * a;
        }
    }
    printf("        seen: %lld texels outwards, %lld inwards (%lld differ); rain %.6g and "
           "%.6g; 16 x 16 blocks %.4f apart\n",
           (long long)seen_out, (long long)seen_in, (long long)differ, sum_out, sum_in,
           sqrt(diff2 / mean2));
    ENSURE(seen_out > W * W / 2);
    ENSURE(differ <= seen_out / 1000);
    ENSURE(fabs(sum_in / sum_out - 1.0) <= 0.002);
    ENSURE(sqrt(diff2 / mean2) <= 0.005);
    for (int r = 0; r < 2; ++r) {
        free(dirt[r]);
        free(sun[r]);
        free(seen[r]);
    }
}

int main(void)
{
    RUN(sphere_under_rain_from_a_box);
    RUN(sphere_under_a_dome_aimed_at_its_foot);
    RUN(wall_under_an_overhang_in_slanting_rain);
    RUN(shelter_edge_at_30_degrees_to_the_cameras_is_straight);
    RUN(lumpy_sphere_turned_in_the_camera_grid_keeps_its_exact_rain);
    RUN(lumpy_sphere_turned_slides_as_a_new_seed_does);
    RUN(sliding_rain_draws_no_contours_on_a_flat_top);
    RUN(lumpy_sphere_bottom_stays_dry_under_a_layered_top_camera);
    RUN(lumpy_sphere_wound_inwards_weathers_as_wound_outwards);
    return ensure_summary();
}
