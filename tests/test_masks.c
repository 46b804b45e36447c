// test_masks.c: the derived masks (docs/design.md section 12, docs/masks.md)
// against answers worked out by hand: accessibility of an open plane (1), of a
// floor at distance x from a tall wall (1 - (acos c - c sqrt(1 - c^2)) / pi,
// c = x / D) and inside a closed box (0); the exposure of a plane (sin e, side
// suns adding their weighted sines) and the shadow of a wall (edge at
// h / tan e); the curvature of spheres (1/R) and of a plane (0); height linear
// in y; Riihiaho's sigmoid in a Combine; the masks as TextureMap channels.
#define _XOPEN_SOURCE 700 // realpath
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ensure.h"
#include "io/exr.h"
#include "model/image.h"
#include "sim/masks.h"
#include "run_fixture.h"
#include "sphere_fixture.h"

// Writes an OBJ of axis-aligned boxes: each line of `boxes` is x0 y0 z0 x1 y1 z1.
static void write_boxes(const char *dir, const char *name, const double (*boxes)[6], int count)
{
    char text[16384];
    size_t n = 0;
    static const int quads[6][4] = { { 0, 4, 6, 2 }, { 1, 3, 7, 5 }, { 0, 1, 5, 4 },
                                     { 2, 6, 7, 3 }, { 0, 2, 3, 1 }, { 4, 5, 7, 6 } };
    for (int b = 0; b < count; ++b) {
        for (int k = 0; k < 8; ++k) {
            n += (size_t)snprintf(text + n, sizeof text - n, "v %g %g %g\n",
                                  boxes[b][(k & 1) ? 3 : 0], boxes[b][(k & 2) ? 4 : 1],
                                  boxes[b][(k & 4) ? 5 : 2]);
        }
        for (int q = 0; q < 6; ++q) {
            int v = 8 * b + 1;
            n += (size_t)snprintf(text + n, sizeof text - n, "f %d %d %d\nf %d %d %d\n",
                                  v + quads[q][0], v + quads[q][1], v + quads[q][2],
                                  v + quads[q][0], v + quads[q][2], v + quads[q][3]);
        }
    }
    ensure_write_file(dir, name, text);
}

// A scene of the mesh `mesh` seen by a top camera (input) over `frame` metres
// centred at (cx, 0, 0), `pixels` a side, and an output camera equal to it; no
// emitter; `masks` the <Masks> content; `extra_cameras` more <Ortho>s.
static void write_scene(const char *dir, const char *name, const char *mesh, double cx,
                        double frame, int pixels, const char *masks, const char *extra_cameras,
                        const char *output_view)
{
    char text[16384], view[512];
    snprintf(view, sizeof view,
             "<View eye=\"%g 20 0\" target=\"%g 0 0\" up=\"0 0 -1\" width=\"%g\" height=\"%g\" "
             "resolution=\"%d\"/>",
             cx, cx, frame, frame, pixels);
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Solver><BoundingBox size=\"40\"/><Simulation timeStep=\"0.01\" steps=\"1\"/></Solver>\n"
             "  <Collider><ProjectedMaps>\n"
             "    <Ortho cameraName=\"top\">%s</Ortho>\n"
             "    %s\n"
             "    <Ortho cameraName=\"shot\" out=\"true\">%s<OutputMap file=\"mask.exr\"/></Ortho>\n"
             "  </ProjectedMaps></Collider>\n"
             "  <Geometry><Mesh file=\"%s\"><Surface material=\"*\"/></Mesh></Geometry>\n"
             "  <Masks>%s</Masks>\n"
             "</Weathering>\n",
             view, extra_cameras, output_view != NULL ? output_view : view, mesh, masks);
    ensure_write_file(dir, name, text);
}

// The mask's channel at world (x, z) of a top view over `frame` centred at (cx, 0, 0).
static float at_world(const float *plane, int w, int h, double cx, double frame, double x,
                      double z)
{
    int i = (int)floor(((x - cx) / frame + 0.5) * w);
    int j = (int)floor((z / frame + 0.5) * h); // up = -Z: row 0 at z = -frame/2
    return plane[(size_t)j * (size_t)w + (size_t)i];
}

// ---------------------------------------------------------------------------

TEST(sigmoid_and_sun_direction)
{
    // Riihiaho's eq. 3.7 by hand: o = 0.1, s = 10, x = 0.3: 0.2 / (2 sqrt(0.14)) + 1/2.
    ENSURE_NEAR(wx_sigmoid(0.3, 0.1, 10.0), 0.2 / (2.0 * sqrt(0.14)) + 0.5, 1e-12);
    ENSURE_NEAR(wx_sigmoid(0.1, 0.1, 10.0), 0.5, 1e-12);
    ENSURE_NEAR(wx_sigmoid(-5.0, 0.0, 4.0), -5.0 / (2.0 * sqrt(0.25 + 25.0)) + 0.5, 1e-12);
    ENSURE_NEAR(wx_sigmoid(0.7, 0.5, 0.0), 0.7, 1e-12); // steepness 0: x itself
    double d[3];
    wx_sun_direction(30.0, 90.0, d); // (cos e cos a, sin e, cos e sin a)
    ENSURE_NEAR(d[0], 0.0, 1e-12);
    ENSURE_NEAR(d[1], 0.5, 1e-12);
    ENSURE_NEAR(d[2], sqrt(3.0) / 2.0, 1e-12);
}

// An open plane: accessibility 1; exposure sin(e) under one sun, sin(e) + 2 w
// sin(f e) with side suns (e = 30, w = 0.25, f = 0.5: 0.629) (their azimuths do not matter on a plane); Height of
// a plane at y = 0 over [-1, 1]: 0.5; a Combine of constants and masks.
TEST(open_plane)
{
    const char *dir = ensure_tmpdir();
    static const double plane[1][6] = { { -3, -0.1, -3, 3, 0, 3 } };
    write_boxes(dir, "plane.obj", plane, 1);
    write_scene(dir, "plane.xml", "plane.obj", 0.0, 4.0, 256,
                "<Accessibility name=\"ao\" rays=\"64\" distance=\"1\"/>"
                "<Exposure name=\"sun\" elevation=\"30\"/>"
                "<Exposure name=\"sides\" elevation=\"30\" azimuth=\"40\" sideWeight=\"0.25\" "
                "sideElevation=\"0.5\" sideSpread=\"70\"/>"
                "<Curvature name=\"k\"/>"
                "<Height name=\"h\" min=\"-1\" max=\"1\"/>"
                "<Combine name=\"c\" scale=\"0.5\">"
                "<Term constant=\"0.3\" weight=\"2\" offset=\"0.1\" steepness=\"10\"/>"
                "<Term mask=\"h\" weight=\"-0.5\"/></Combine>",
                "", NULL);
    ENSURE(weathering_in(dir, "run plane.xml --out plane -q", true) == 0);
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/plane/mask.exr", dir);
    const char *names[6] = { "ao.Y", "sun.Y", "sides.Y", "k.Y", "h.Y", "c.Y" };
    const double want[6] = { 1.0, 0.5, 0.5 + 2.0 * 0.25 * sin(15.0 * SPHERE_PI / 180.0), 0.0, 0.5,
                             0.5 * (2.0 * (0.2 / (2.0 * sqrt(0.14)) + 0.5) - 0.25) };
    const double tol[6] = { 0.02, 1e-4, 1e-4, 1e-3, 1e-4, 1e-4 };
    for (int c = 0; c < 6; ++c) {
        int w, h;
        float *m = ensure_read_channel(path, names[c], &w, &h);
        ENSURE(m != NULL);
        if (m == NULL) {
            continue;
        }
        double worst = 0.0, sum = 0.0;
        int n = 0;
        for (int j = 16; j < h - 16; ++j) {
            for (int i = 16; i < w - 16; ++i) {
                double v = m[(size_t)j * (size_t)w + (size_t)i];
                worst = fmax(worst, fabs(v - want[c]));
                sum += v;
                n++;
            }
        }
        printf("        %-7s mean %.5f (exact %.5f), worst error %.2g\n", names[c], sum / n, want[c],
               worst);
        ENSURE(worst <= tol[c]);
        free(m);
    }
}

// A floor beside a wall 5 m tall: at distance x < D the rays that reach the
// wall within D are the cosine-weighted share (acos c - c sqrt(1 - c^2)) / pi.
// And the shadow of a wall of height 1 under a sun at elevation 45 from -X: the
// floor is dark up to x = h / tan(e) = 1, lit beyond.
TEST(floor_beside_a_wall)
{
    SLOW();
    const char *dir = ensure_tmpdir();
    static const double wall[2][6] = { { -1, -0.1, -3, 7, 0, 3 }, { -0.25, 0, -3, 0, 5, 3 } };
    write_boxes(dir, "wall.obj", wall, 2);
    // A frame over x in [-1, 7]: x = 0 falls on a texel border (64 texels a metre).
    write_scene(dir, "wall.xml", "wall.obj", 3.0, 8.0, 512,
                "<Accessibility name=\"ao\" rays=\"256\" distance=\"1\"/>", "", NULL);
    ENSURE(weathering_in(dir, "run wall.xml --out wall -q", true) == 0);
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/wall/mask.exr", dir);
    int w, h;
    float *ao = ensure_read_channel(path, "ao.Y", &w, &h);
    ENSURE(ao != NULL);
    if (ao != NULL) {
        // x = 1/128: the floor's texel next to the crease (its centre), where
        // the rays start within a texel of the surface to stay dark.
        const double xs[6] = { 0.5 / 64.0, 0.1, 0.25, 0.5, 0.75, 1.5 };
        for (int k = 0; k < 6; ++k) {
            double c = fmin(1.0, xs[k] / 1.0);
            double want = 1.0 - (acos(c) - c * sqrt(1.0 - c * c)) / SPHERE_PI;
            // The mean over a column of texels along the wall, away from its ends.
            double sum = 0.0;
            int n = 0;
            for (double z = -2.0; z <= 2.0; z += 0.05) {
                sum += at_world(ao, w, h, 3.0, 8.0, xs[k], z);
                n++;
            }
            printf("        x = %.4f: accessibility %.4f, exact %.4f\n", xs[k], sum / n, want);
            ENSURE_NEAR(sum / n, want, 0.03);
        }
        free(ao);
    }

    static const double low[2][6] = { { -1, -0.1, -3, 7, 0, 3 }, { -0.25, 0, -3, 0, 1, 3 } };
    write_boxes(dir, "low.obj", low, 2);
    write_scene(dir, "shadow.xml", "low.obj", 3.0, 8.0, 512,
                "<Exposure name=\"sun\" elevation=\"45\" azimuth=\"180\"/>", "", NULL);
    ENSURE(weathering_in(dir, "run shadow.xml --out shadow -q", true) == 0);
    snprintf(path, sizeof path, "%s/shadow/mask.exr", dir);
    float *sun = ensure_read_channel(path, "sun.Y", &w, &h);
    ENSURE(sun != NULL);
    if (sun != NULL) {
        // Row by row, the first lit texel right of the wall: its centre within
        // 2 texels (1/32 m) of the exact edge x = 1.
        double worst = 0.0;
        for (int j = h / 4; j < 3 * h / 4; ++j) {
            int first = -1;
            for (int i = 65; i < w && first < 0; ++i) { // texel 64 starts at x = 0
                first = sun[(size_t)j * (size_t)w + (size_t)i] > 0.5f ? i : -1;
            }
            double x = -1.0 + (first + 0.5) * 8.0 / w;
            worst = fmax(worst, fabs(x - 1.0));
        }
        printf("        shadow edge: worst distance from x = 1 is %.4f m (%.2f texels)\n", worst,
               worst * w / 8.0);
        ENSURE(worst <= 2.0 * 8.0 / w);
        // Lit floor beyond the edge: sin(45).
        ENSURE_NEAR(at_world(sun, w, h, 3.0, 8.0, 3.0, 0.0), sin(SPHERE_PI / 4.0), 1e-4);
        ENSURE(at_world(sun, w, h, 3.0, 8.0, 0.5, 0.0) == 0.0f);
        free(sun);
    }
}

// Inside a closed box whose lid the input camera records: every direction is
// closed, accessibility 0. The output camera looks at the floor from inside.
TEST(inside_a_closed_box)
{
    const char *dir = ensure_tmpdir();
    // Walls, floor and lid 0.3 m thick around the inside [-1, 1] x [0, 2] x [-1, 1].
    static const double box[6][6] = {
        { -1.3, -0.3, -1.3, 1.3, 0, 1.3 }, { -1.3, 2, -1.3, 1.3, 2.3, 1.3 },
        { -1.3, 0, -1.3, -1, 2, 1.3 },     { 1, 0, -1.3, 1.3, 2, 1.3 },
        { -1, 0, -1.3, 1, 2, -1 },         { -1, 0, 1, 1, 2, 1.3 },
    };
    write_boxes(dir, "box.obj", box, 6);
    write_scene(dir, "box.xml", "box.obj", 0.0, 3.0, 256,
                "<Accessibility name=\"ao\" rays=\"64\" distance=\"0.5\"/>", "",
                "<View eye=\"0 1.5 0\" target=\"0 0 0\" up=\"0 0 -1\" width=\"1.6\" "
                "height=\"1.6\" resolution=\"64\"/>");
    ENSURE(weathering_in(dir, "run box.xml --out box -q", true) == 0);
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/box/mask.exr", dir);
    int w, h;
    float *ao = ensure_read_channel(path, "ao.Y", &w, &h);
    float *depth = NULL;
    snprintf(path, sizeof path, "%s/box/shot_depth.exr", dir);
    depth = ensure_read_channel(path, "R", &w, &h);
    ENSURE(ao != NULL && depth != NULL);
    if (ao != NULL && depth != NULL) {
        double largest = 0.0;
        int n = 0;
        for (size_t t = 0; t < (size_t)w * (size_t)h; ++t) {
            if (isfinite(depth[t]) && depth[t] > 0.0f && depth[t] < 1e30f) {
                largest = fmax(largest, ao[t]);
                n++;
            }
        }
        printf("        %d texels of the floor inside, largest accessibility %g\n", n, largest);
        ENSURE(n > 1000);
        ENSURE(largest == 0.0);
    }
    free(ao);
    free(depth);
}

// Spheres of radius 0.5, 1 and 2 seen from above: curvature 1/R within 10%
// where the surface faces the camera (n.y > 0.5); Height over [-R, R] is
// (y + R) / (2R).
TEST(sphere_curvature_and_height)
{
    SLOW();
    const char *dir = ensure_tmpdir();
    const double radii[3] = { 0.5, 1.0, 2.0 };
    for (int k = 0; k < 3; ++k) {
        double R = radii[k];
        char name[64], folder[64], masks[256], args[256], sname[64], scaled[PATH_MAX + 32];
        snprintf(name, sizeof name, "s%d.xml", k);
        snprintf(folder, sizeof folder, "s%d", k);
        snprintf(masks, sizeof masks,
                 "<Curvature name=\"k\"/><Height name=\"h\" min=\"%g\" max=\"%g\"/>", -R, R);
        // A <Mesh> has no transform: a sphere of radius R of its own.
        snprintf(sname, sizeof sname, "sphere_%d.ply", k);
        snprintf(scaled, sizeof scaled, "%s/%s", dir, sname);
        ENSURE(sphere_write_mesh_scaled(scaled, 128, 256, R));
        write_scene(dir, name, sname, 0.0, 2.4 * R, 512, masks, "", NULL);
        snprintf(args, sizeof args, "run %s --out %s -q", name, folder);
        ENSURE(weathering_in(dir, args, true) == 0);
        char path[PATH_MAX];
        snprintf(path, sizeof path, "%s/%s/mask.exr", dir, folder);
        int w, h;
        float *kk = ensure_read_channel(path, "k.Y", &w, &h);
        float *hh = ensure_read_channel(path, "h.Y", &w, &h);
        ENSURE(kk != NULL && hh != NULL);
        if (kk != NULL && hh != NULL) {
            double sum = 0.0, worst_h = 0.0;
            int n = 0;
            for (int j = 0; j < h; ++j) {
                for (int i = 0; i < w; ++i) {
                    double x = ((i + 0.5) / w - 0.5) * 2.4 * R, z = ((j + 0.5) / h - 0.5) * 2.4 * R;
                    double r2 = (x * x + z * z) / (R * R);
                    if (r2 >= 0.75) { // n.y > 0.5
                        continue;
                    }
                    size_t t = (size_t)j * (size_t)w + (size_t)i;
                    sum += kk[t];
                    n++;
                    double y = R * sqrt(1.0 - r2);
                    worst_h = fmax(worst_h, fabs(hh[t] - (y + R) / (2.0 * R)));
                }
            }
            printf("        R = %.1f: mean curvature %.4f (exact %.4f), height within %.2g\n", R,
                   sum / n, 1.0 / R, worst_h);
            ENSURE_NEAR(sum / n * R, 1.0, 0.10);
            ENSURE(worst_h <= 2e-3);
        }
        free(kk);
        free(hh);
    }
}

// The masks are channels of a TextureMap too: the unit cube's atlas
// (tests/data/texture_cube.obj) under a top camera, Height over [0, 1] is 1 on
// the top island and Exposure of the top face under a sun at 30 degrees 0.5.
TEST(masks_in_a_texture)
{
    const char *dir = ensure_tmpdir();
    const char *mesh = data_file("texture_cube.obj");
    char text[8192];
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Solver><BoundingBox size=\"8\"/><Simulation timeStep=\"0.01\" steps=\"1\"/></Solver>\n"
             "  <Collider><ProjectedMaps>\n"
             "    <Ortho cameraName=\"top\"><View eye=\"0 5 0\" target=\"0 0 0\" up=\"0 0 -1\" "
             "width=\"1.6\" height=\"1.6\" resolution=\"256\"/></Ortho>\n"
             "  </ProjectedMaps></Collider>\n"
             "  <Geometry><Mesh file=\"%s\"><Surface material=\"*\"/>\n"
             "    <TextureMap file=\"cube.exr\" width=\"768\" height=\"512\"/></Mesh></Geometry>\n"
             "  <Masks><Height name=\"h\" min=\"0\" max=\"1\"/>"
             "<Exposure name=\"sun\" elevation=\"30\"/></Masks>\n"
             "</Weathering>\n",
             mesh);
    ensure_write_file(dir, "cube.xml", text);
    ENSURE(weathering_in(dir, "run cube.xml --out cube -q", true) == 0);
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/cube/cube.exr", dir);
    int w, h;
    float *hh = ensure_read_channel(path, "h.Y", &w, &h);
    float *sun = ensure_read_channel(path, "sun.Y", &w, &h);
    float *seen = ensure_read_channel(path, "seen", &w, &h);
    ENSURE(hh != NULL && sun != NULL && seen != NULL);
    if (hh != NULL && sun != NULL && seen != NULL) {
        double worst_h = 0.0, worst_sun = 0.0, side = 0.0;
        for (int j = 16; j < 240; ++j) {
            for (int i = 16; i < 240; ++i) { // the top island (test_texture.c)
                size_t t = (size_t)j * (size_t)w + (size_t)i;
                worst_h = fmax(worst_h, fabs(hh[t] - 1.0));
                worst_sun = fmax(worst_sun, fabs(sun[t] - 0.5));
            }
            for (int i = 528; i < 752; ++i) { // +X: no camera sees it, every channel 0
                size_t t = (size_t)j * (size_t)w + (size_t)i;
                side = fmax(side, fabs(hh[t]) + fabs(sun[t]) + seen[t]);
            }
        }
        printf("        top island: height within %.2g of 1, exposure within %.2g of 0.5\n",
               worst_h, worst_sun);
        ENSURE(worst_h <= 1e-4 && worst_sun <= 1e-4 && side == 0.0);
    }
    free(hh);
    free(sun);
    free(seen);
}

// Rays are stratified per point from a hash of the seed, the mask and the
// point: the same bytes for 1 and 2 threads.
TEST(same_bytes_for_any_thread_count)
{
    const char *dir = ensure_tmpdir();
    static const double wall[2][6] = { { -1, -0.1, -3, 7, 0, 3 }, { -0.25, 0, -3, 0, 1, 3 } };
    write_boxes(dir, "t.obj", wall, 2);
    write_scene(dir, "t.xml", "t.obj", 3.0, 8.0, 128,
                "<Accessibility name=\"ao\" rays=\"16\" distance=\"1\"/>"
                "<Exposure name=\"sun\" elevation=\"30\" azimuth=\"170\" sideWeight=\"0.3\" "
                "sideSpread=\"40\"/><Curvature name=\"k\"/>",
                "", NULL);
    ENSURE(weathering_in(dir, "run t.xml --out one -q --threads 1", true) == 0);
    ENSURE(weathering_in(dir, "run t.xml --out two -q --threads 2", true) == 0);
    ENSURE(ensure_shell(out, sizeof out, "cd '%s' && cmp one/mask.exr two/mask.exr", dir) == 0);
}

// With frames (`every`), the masks that read only the geometry are computed at
// the first frame and copied into the later ones (masks_phase.h): the unit
// cube of tests/data/texture_cube.obj under rain, three iterations, a frame of
// the mask and of the TextureMap after each. Exposure, Height and a Combine of
// Height are the same in every frame and in the final files; a Combine reading
// the dirt grows with it; and the final files are byte for byte those of the
// same run without frames, where nothing is kept: the copy is the computation.
static const char *frames_scene =
    "<Weathering>\n"
    "  <Solver><BoundingBox size=\"4\" centerY=\"1\"/>\n"
    "    <Simulation timeStep=\"0.02\" steps=\"40\" seed=\"3\" iterations=\"3\"/></Solver>\n"
    "  <Emitters><BoxEmitter minX=\"-0.8\" minY=\"2\" minZ=\"-0.8\" maxX=\"0.8\" maxY=\"2\" "
    "maxZ=\"0.8\" rate=\"40000\" end=\"0.5\" speed=\"10\" dirt=\"0.01\"/></Emitters>\n"
    "  <Collider><ProjectedMaps>\n"
    "    <Ortho cameraName=\"top\"><View eye=\"0 5 0\" target=\"0 0 0\" up=\"0 0 -1\" "
    "width=\"1.6\" height=\"1.6\" resolution=\"128\"/></Ortho>\n"
    "    <Ortho cameraName=\"px\"><View eye=\"5 0.5 0\" target=\"0 0.5 0\" width=\"1.6\" "
    "height=\"1.6\" resolution=\"128\"/></Ortho>\n"
    "    <Ortho cameraName=\"shot\" out=\"true\"><View eye=\"5 5 5\" target=\"0 0.5 0\" "
    "width=\"2.4\" height=\"2.4\" resolution=\"128\"/><OutputMap file=\"mask.exr\" every=\"%d\"/>"
    "</Ortho>\n"
    "  </ProjectedMaps></Collider>\n"
    "  <Geometry><Mesh file=\"%s\"><Surface material=\"*\" absorption=\"1\"/>\n"
    "    <TextureMap file=\"cube.exr\" width=\"192\" height=\"128\" every=\"%d\"/>"
    "</Mesh></Geometry>\n"
    "  <Masks><Exposure name=\"sun\" elevation=\"40\" azimuth=\"30\"/>"
    "<Height name=\"h\" min=\"0\" max=\"1\"/>"
    "<Combine name=\"low\"><Term mask=\"h\" weight=\"-1\"/><Term constant=\"1\"/></Combine>"
    "<Combine name=\"wet\" scale=\"0.5\"><Term mask=\"sun\"/><Term substance=\"dirt\" "
    "weight=\"0.001\"/></Combine></Masks>\n"
    "</Weathering>\n";

TEST(frames_copy_the_geometric_masks)
{
    const char *dir = ensure_tmpdir();
    char text[8192];
    for (int every = 0; every <= 1; ++every) {
        snprintf(text, sizeof text, frames_scene, every, data_file("texture_cube.obj"), every);
        char name[32], args[96];
        snprintf(name, sizeof name, "frames%d.xml", every);
        ensure_write_file(dir, name, text);
        snprintf(args, sizeof args, "run %s --out f%d -q", name, every);
        ENSURE(weathering_in(dir, args, true) == 0);
    }
    // The copy is the computation: the final files of both runs are the same.
    ENSURE(ensure_shell(out, sizeof out, "cd '%s' && cmp f0/mask.exr f1/mask.exr && "
                        "cmp f0/cube.exr f1/cube.exr", dir) == 0);
    static const char *const files[2][3] = { { "mask.0001.exr", "mask.0002.exr", "mask.exr" },
                                             { "cube.0001.exr", "cube.0002.exr", "cube.exr" } };
    static const char *const geometric[3] = { "sun.Y", "h.Y", "low.Y" };
    for (int f = 0; f < 2; ++f) {
        char path[PATH_MAX];
        int w = 0, h = 0, w2 = 0, h2 = 0;
        for (int c = 0; c < 3; ++c) {
            snprintf(path, sizeof path, "%s/f1/%s", dir, files[f][2]);
            float *last = ensure_read_channel(path, geometric[c], &w, &h);
            snprintf(path, sizeof path, "%s/f1/%s", dir, files[f][0]);
            float *first = ensure_read_channel(path, geometric[c], &w2, &h2);
            ENSURE(last != NULL && first != NULL && w == w2 && h == h2);
            double lit = 0.0;
            for (size_t t = 0; last != NULL && first != NULL && t < (size_t)w * (size_t)h; ++t) {
                ENSURE(first[t] == last[t]);
                lit += last[t];
            }
            ENSURE(lit > 0.0); // the mask is not trivially zero
            free(last);
            free(first);
        }
        // The Combine of the dirt grows from frame to frame.
        double sums[3] = { 0.0, 0.0, 0.0 };
        for (int k = 0; k < 3; ++k) {
            snprintf(path, sizeof path, "%s/f1/%s", dir, files[f][k]);
            float *wet = ensure_read_channel(path, "wet.Y", &w, &h);
            ENSURE(wet != NULL);
            for (size_t t = 0; wet != NULL && t < (size_t)w * (size_t)h; ++t) {
                sums[k] += wet[t];
            }
            free(wet);
        }
        printf("        %s: wet sums %.1f, %.1f, %.1f over the three frames\n", files[f][2],
               sums[0], sums[1], sums[2]);
        ENSURE(sums[0] < sums[1] && sums[1] < sums[2]);
    }
}

// <Curvature radius="1e30"> overflowed the cast of its reach to int and became
// one texel without a word: it is the largest neighbourhood (32 target texels
// each way, docs/masks.md), so it equals a radius of 10 (533 texels, wider than
// the unit sphere and clamped to that window too) byte for byte, and differs
// from one texel's.
TEST(huge_curvature_radius_is_the_largest_window)
{
    const char *dir = ensure_tmpdir();
    const int px = 128;
    const double R = 1.0, frame = 2.4 * R, texel = frame / px;
    char masks[512];
    snprintf(masks, sizeof masks,
             "<Curvature name=\"huge\" radius=\"1e30\"/>"
             "<Curvature name=\"window\" radius=\"%.9g\"/>"
             "<Curvature name=\"one\" radius=\"%.9g\"/>",
             10.0, 1.0 * texel);
    char mesh[PATH_MAX + 32];
    snprintf(mesh, sizeof mesh, "%s/sphere.ply", dir);
    ENSURE(sphere_write_mesh_scaled(mesh, 64, 128, R));
    write_scene(dir, "k.xml", "sphere.ply", 0.0, frame, px, masks, "", NULL);
    ENSURE(weathering_in(dir, "run k.xml --out k -q", true) == 0);
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/k/mask.exr", dir);
    int w, h;
    float *huge = ensure_read_channel(path, "huge.Y", &w, &h);
    float *window = ensure_read_channel(path, "window.Y", &w, &h);
    float *one = ensure_read_channel(path, "one.Y", &w, &h);
    bool read = huge != NULL && window != NULL && one != NULL;
    bool same = read && memcmp(huge, window, (size_t)w * (size_t)h * sizeof *huge) == 0;
    bool differs = read && memcmp(huge, one, (size_t)w * (size_t)h * sizeof *huge) != 0;
    free(huge);
    free(window);
    free(one);
    ENSURE(read && same && differs);
}

int main(void)
{
    RUN(sigmoid_and_sun_direction);
    RUN(open_plane);
    RUN(floor_beside_a_wall);
    RUN(inside_a_closed_box);
    RUN(sphere_curvature_and_height);
    RUN(huge_curvature_radius_is_the_largest_window);
    RUN(masks_in_a_texture);
    RUN(same_bytes_for_any_thread_count);
    RUN(frames_copy_the_geometric_masks);
    return ensure_summary();
}
