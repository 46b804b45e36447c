// test_depth_layers.c: layered depth maps through the whole pipeline (issue
// 26, docs/design.md section 14): free space behind what the first surface
// hides, and the surfaces there, as exact answers on scenes made here.
//
// A balcony niche: a back wall, a floor, a roof above and a parapet in front,
// closed at the sides. Every camera's first surface hides the niche's lower
// half (the front camera sees the parapet, the top camera the roof, the side
// camera the side wall), so with one layer the collider calls it solid and rain
// slanting in over the parapet stops in mid-air. With layers it flies on and
// lands where the geometry says.
#define _XOPEN_SOURCE 700 // realpath
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ensure.h"
#include "io/exr.h"
#include "model/camera.h"
#include "model/image.h"
#include "run_fixture.h"

// An axis-aligned box lo..hi, wound outwards, appended to the OBJ text.
static void put_box(char *obj, size_t size, size_t *n, int *vertices, const double lo[3],
                    const double hi[3])
{
    for (int v = 0; v < 8; ++v) {
        *n += (size_t)snprintf(obj + *n, size - *n, "v %g %g %g\n", (v & 1) ? hi[0] : lo[0],
                               (v & 2) ? hi[1] : lo[1], (v & 4) ? hi[2] : lo[2]);
    }
    // Corner v = x + 2y + 4z; each quad counter-clockwise seen from outside.
    static const int quads[6][4] = { { 0, 4, 6, 2 }, { 1, 3, 7, 5 }, { 0, 1, 5, 4 },
                                     { 2, 6, 7, 3 }, { 0, 2, 3, 1 }, { 4, 5, 7, 6 } };
    int b = *vertices + 1;
    for (int q = 0; q < 6; ++q) {
        const int *c = quads[q];
        *n += (size_t)snprintf(obj + *n, size - *n, "f %d %d %d\nf %d %d %d\n", b + c[0],
                               b + c[1], b + c[2], b + c[0], b + c[2], b + c[3]);
    }
    *vertices += 8;
}

// The niche (x -2..2): floor y -0.2..0 (z -1.2..1), back wall z -1.2..-1 (y
// 0..3), roof y 2.5..2.7 (z -1.2..0), parapet z 0..0.2 (y 0..1), side walls
// x +-(2..2.2).
static void niche_mesh(char *obj, size_t size)
{
    static const double boxes[6][2][3] = {
        { { -2.2, -0.2, -1.2 }, { 2.2, 0.0, 1.0 } },  // floor
        { { -2.0, 0.0, -1.2 }, { 2.0, 3.0, -1.0 } },  // back wall
        { { -2.0, 2.5, -1.2 }, { 2.0, 2.7, 0.0 } },   // roof
        { { -2.0, 0.0, 0.0 }, { 2.0, 1.0, 0.2 } },    // parapet
        { { -2.2, 0.0, -1.2 }, { -2.0, 2.7, 0.2 } },  // side walls
        { { 2.0, 0.0, -1.2 }, { 2.2, 2.7, 0.2 } },
    };
    size_t n = 0;
    int vertices = 0;
    for (int b = 0; b < 6; ++b) {
        put_box(obj, size, &n, &vertices, boxes[b][0], boxes[b][1]);
    }
}

// Rain along (0, -2, -1), straight (no field), from y = 6 over x -1.5..1.5, z
// 0.5..4 (10.5 m^2): RATE * 0.5 s drops. Crossing the niche's front (z = 0)
// between the parapet (y 1) and the roof (y 2.5), a drop lands on the floor
// at z -0.5..-1 (heights 1..2) or on the back wall below y 0.5 (heights 2 to
// 2.5): per unit area the floor strip gets the open sky's F, the wall F / 2,
// the floor in the parapet's shadow (z -0.5..0) nothing.
enum { RATE = 420000 };
static const double EMITTER_AREA = 3.0 * 3.5, EMIT_SECONDS = 0.5;

static void niche_scene(char *xml, size_t size, int layers)
{
    char attr[32] = "";
    if (layers > 1) {
        snprintf(attr, sizeof attr, " layers=\"%d\"", layers);
    }
    snprintf(
        xml, size,
        "<Weathering>\n"
        "  <Solver>\n"
        "    <BoundingBox size=\"14\" centerX=\"0\" centerY=\"3\" centerZ=\"1\"/>\n"
        "    <Simulation timeStep=\"0.02\" steps=\"70\" seed=\"5\"/>\n"
        "  </Solver>\n"
        "  <Emitters>\n"
        "    <BoxEmitter minX=\"-1.5\" minY=\"6\" minZ=\"0.5\" maxX=\"1.5\" maxY=\"6\" maxZ=\"4\"\n"
        "                dirX=\"0\" dirY=\"-2\" dirZ=\"-1\" rate=\"%d\" end=\"%g\" speed=\"10\"/>\n"
        "  </Emitters>\n"
        "  <Collider>\n"
        "    <ProjectedMaps>\n"
        "      <Ortho cameraName=\"front\"%s>\n"
        "        <View eye=\"0 1.5 10\" target=\"0 1.5 0\" up=\"0 1 0\" width=\"6\" height=\"6\"\n"
        "              resolution=\"256\"/>\n"
        "      </Ortho>\n"
        "      <Ortho cameraName=\"top\"%s>\n"
        "        <View eye=\"0 10 0\" target=\"0 0 0\" up=\"0 0 -1\" width=\"6\" height=\"6\"\n"
        "              resolution=\"256\"/>\n"
        "      </Ortho>\n"
        "      <Ortho cameraName=\"right\"%s>\n"
        "        <View eye=\"10 1.5 0\" target=\"0 1.5 0\" up=\"0 1 0\" width=\"6\" height=\"6\"\n"
        "              resolution=\"256\"/>\n"
        "      </Ortho>\n"
        "      <Ortho cameraName=\"shot\" out=\"true\">\n"
        "        <View eye=\"0 1.5 10\" target=\"0 1.5 0\" up=\"0 1 0\" width=\"6\" height=\"6\"\n"
        "              resolution=\"256\"/>\n"
        "      </Ortho>\n"
        "    </ProjectedMaps>\n"
        "  </Collider>\n"
        "  <Geometry>\n"
        "    <Mesh file=\"niche.obj\"><Surface material=\"*\" absorption=\"1\"/></Mesh>\n"
        "  </Geometry>\n"
        "</Weathering>\n",
        RATE, EMIT_SECONDS, attr, attr, attr);
}

// Hits per square metre a camera's dirt map records over the texels of a
// surface: those of any layer whose point lies in the box lo..hi (world).
typedef struct tally {
    double hits;
    double area;
    bool read; ///< every layer's maps were read (no hits counts only then)
} tally;

static bool read_camera(const char *path, wx_camera *cam)
{
    wx_image header;
    wx_error err;
    memset(&header, 0, sizeof header);
    if (wx_exr_read_header(path, &header, &err) != WX_OK) {
        return false;
    }
    const wx_attr *wtc = wx_image_find_attr(&header, "WTCMatrix");
    const wx_attr *ctw = wx_image_find_attr(&header, "CTWMatrix");
    bool ok = wtc != NULL && ctw != NULL;
    if (ok) {
        memcpy(cam->wtc, wtc->m44f, sizeof cam->wtc);
        memcpy(cam->ctw, ctw->m44f, sizeof cam->ctw);
        cam->width = header.width;
        cam->height = header.height;
    }
    wx_image_free(&header);
    return ok;
}

static tally count_hits(const char *dir, const char *camera, int layers, const double lo[3],
                        const double hi[3])
{
    tally t = { 0.0, 0.0, false };
    char depth_path[PATH_MAX], dirt_path[PATH_MAX];
    snprintf(depth_path, sizeof depth_path, "%s/%s_depth.exr", dir, camera);
    snprintf(dirt_path, sizeof dirt_path, "%s/%s_dirt.exr", dir, camera);
    wx_camera cam;
    if (!read_camera(depth_path, &cam)) {
        return t;
    }
    float fw, fh;
    wx_camera_frame_size(&cam, &fw, &fh);
    double texel_area = (double)fw / cam.width * (double)fh / cam.height;
    t.read = true;
    for (int k = 0; k < layers; ++k) {
        char depth_name[32], hits_name[32];
        snprintf(depth_name, sizeof depth_name, k > 0 ? "layer%d.R" : "R", k);
        snprintf(hits_name, sizeof hits_name, k > 0 ? "layer%d.hits" : "hits", k);
        int w = 0, h = 0, w2 = 0, h2 = 0;
        float *depth = ensure_read_channel(depth_path, depth_name, &w, &h);
        float *hits = ensure_read_channel(dirt_path, hits_name, &w2, &h2);
        t.read = t.read && depth != NULL && hits != NULL && w == w2 && h == h2;
        if (depth != NULL && hits != NULL && w == w2 && h == h2) {
            for (int j = 0; j < h; ++j) {
                for (int i = 0; i < w; ++i) {
                    size_t q = (size_t)j * (size_t)w + (size_t)i;
                    if (!(depth[q] > 0.0f && depth[q] < 1e30f)) {
                        continue;
                    }
                    float uvd[3], p[3];
                    wx_map_texel_center(w, h, i, j, &uvd[0], &uvd[1]);
                    uvd[2] = depth[q];
                    wx_camera_map_to_world(&cam, uvd, p);
                    if (p[0] > lo[0] && p[0] < hi[0] && p[1] > lo[1] && p[1] < hi[1] &&
                        p[2] > lo[2] && p[2] < hi[2]) {
                        t.hits += hits[q];
                        t.area += texel_area;
                    }
                }
            }
        }
        free(depth);
        free(hits);
    }
    return t;
}

static bool run_niche(const char *dir, int layers)
{
    static char obj[16384], xml[8192];
    niche_mesh(obj, sizeof obj);
    niche_scene(xml, sizeof xml, layers);
    ensure_write_file(dir, "niche.obj", obj);
    ensure_write_file(dir, "niche.xml", xml);
    char args[PATH_MAX];
    snprintf(args, sizeof args, "run niche.xml --out out%d -q", layers);
    return weathering_in(dir, args, true) == 0;
}

// Rain slanting into the niche over the parapet: with 4 layers the floor strip
// behind the parapet's shadow takes the open sky's rain and the back wall half
// of it, within 4%, the shadow none; with 1 layer the collider calls the
// niche solid and the floor stays dry.
TEST(rain_reaches_the_floor_of_a_niche_every_first_surface_hides)
{
    const char *dir = ensure_tmpdir();
    ENSURE(run_niche(dir, 4));
    ENSURE(run_niche(dir, 1));
    const double F = RATE * EMIT_SECONDS / EMITTER_AREA;
    const double strip_lo[3] = { -1.4, -0.05, -0.95 }, strip_hi[3] = { 1.4, 0.05, -0.55 };
    const double shadow_lo[3] = { -1.4, -0.05, -0.45 }, shadow_hi[3] = { 1.4, 0.05, -0.05 };
    const double wall_lo[3] = { -1.4, 0.05, -1.05 }, wall_hi[3] = { 1.4, 0.45, -0.95 };
    char out4[PATH_MAX], out1[PATH_MAX];
    snprintf(out4, sizeof out4, "%s/out4", dir);
    snprintf(out1, sizeof out1, "%s/out1", dir);
    tally strip = count_hits(out4, "top", 4, strip_lo, strip_hi);
    tally shadow = count_hits(out4, "top", 4, shadow_lo, shadow_hi);
    tally wall = count_hits(out4, "front", 4, wall_lo, wall_hi);
    tally dry = count_hits(out1, "top", 1, strip_lo, strip_hi);
    printf("        per m^2 (open sky %.0f): floor strip %.0f over %.2f m^2, parapet's shadow "
           "%.0f, back wall %.0f (exact %.0f); one layer: floor %.0f over %.2f m^2\n",
           F, strip.hits / strip.area, strip.area, shadow.hits / fmax(shadow.area, 1e-9),
           wall.hits / fmax(wall.area, 1e-9), 0.5 * F, dry.hits / fmax(dry.area, 1e-9),
           dry.area);
    ENSURE(strip.read && shadow.read && wall.read && dry.read);
    ENSURE(strip.area > 0.9 && wall.area > 0.9 && shadow.area > 0.9);
    ENSURE_NEAR(strip.hits / strip.area, F, 0.04 * F);
    ENSURE_NEAR(wall.hits / wall.area, 0.5 * F, 0.04 * 0.5 * F);
    ENSURE(shadow.hits / shadow.area < 0.01 * F);
    // One layer: the top camera cannot see the floor under the roof at all.
    ENSURE(dry.hits < 0.01 * F);
}

// Replaces the first `from` in `text` (a malloc'ed string) by `to`; false when
// `from` is not there.
static bool replace_once(char **text, const char *from, const char *to)
{
    char *at = strstr(*text, from);
    if (at == NULL) {
        return false;
    }
    size_t head = (size_t)(at - *text), from_len = strlen(from), to_len = strlen(to);
    size_t tail = strlen(at + from_len);
    char *joined = malloc(head + to_len + tail + 1);
    if (joined == NULL) {
        return false;
    }
    memcpy(joined, *text, head);
    memcpy(joined + head, to, to_len);
    memcpy(joined + head + to_len, at + from_len, tail + 1);
    free(*text);
    *text = joined;
    return true;
}

// The mask's frames of a layered scene are gathered as the final mask is: the
// last frame is its bytes. Spot's generated scene (4 layers per camera, front
// and back cameras tied on every surface, so ownership needs the layers'
// outward normals) over two iterations. The frames' views used to lose the
// layers' `outward`, and the last frame differed from mask.exr.
TEST(the_last_frame_of_a_layered_scene_is_the_final_mask)
{
    const char *dir = ensure_tmpdir();
    char tests[PATH_MAX], args[PATH_MAX + 128];
    ENSURE(realpath(ensure_tests_dir(), tests) != NULL);
    snprintf(args, sizeof args,
             "init '%s/../xml_scenes/meshes/spot.obj' -o frames.xml --resolution 128 --force",
             tests);
    ENSURE(weathering_in(dir, args, true) == 0);
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/frames.xml", dir);
    char *xml = ensure_read_file(path);
    ENSURE(xml != NULL);
    ENSURE(strstr(xml, "layers=\"4\"") != NULL);
    ENSURE(replace_once(&xml, "seed=\"1\"/>", "seed=\"1\" iterations=\"2\"/>"));
    ENSURE(replace_once(&xml, "<OutputMap file=\"mask.exr\"/>",
                        "<OutputMap file=\"mask.exr\" every=\"1\"/>"));
    const char *rate = strstr(xml, "rate=\"");
    ENSURE(rate != NULL);
    size_t len = strcspn(rate + 6, "\"");
    ENSURE(len < 40);
    char old_rate[64];
    snprintf(old_rate, sizeof old_rate, "rate=\"%.*s\"", (int)len, rate + 6);
    ENSURE(replace_once(&xml, old_rate, "rate=\"40000\""));
    ensure_write_file(dir, "frames.xml", xml);
    free(xml);
    ENSURE(weathering_in(dir, "run frames.xml --out frames -q", true) == 0);
    char log[4096];
    ENSURE(ensure_shell(log, sizeof log, "cd '%s/frames' && cmp mask.exr mask.0002.exr", dir) == 0);
    ENSURE(ensure_shell(log, sizeof log, "cd '%s/frames' && ! cmp -s mask.0001.exr mask.0002.exr",
                        dir) == 0);
}

// Cuts the text between `open` and `close` (both kept) and puts `with` there.
static bool replace_between(char **text, const char *open, const char *close, const char *with)
{
    char *a = strstr(*text, open);
    char *b = a != NULL ? strstr(a, close) : NULL;
    if (b == NULL) {
        return false;
    }
    a += strlen(open);
    size_t head = (size_t)(a - *text), with_len = strlen(with), tail = strlen(b);
    char *joined = malloc(head + with_len + tail + 1);
    if (joined == NULL) {
        return false;
    }
    memcpy(joined, *text, head);
    memcpy(joined + head, with, with_len);
    memcpy(joined + head + with_len, b, tail + 1);
    free(*text);
    *text = joined;
    return true;
}

// A one-sided sign (a quad 2 x 2 m in a vertical plane, turned `degrees` about
// the vertical) under a horizontal spray aimed at its face, through init's
// scene: every drop meets it. Lined up with the grid (0 degrees) the top and
// side cameras see it edge-on and record nothing (their fills make them
// abstain, docs/physics.md, "Surfaces a camera sees edge-on"); turned 30
// degrees the front and back cameras see it from its two sides, and init gives
// them the second layer that reads it as a slab (docs/cameras.md, "Layers").
// Before, no drop hit it at either turn; with the fills alone, 18% at 30
// degrees (the one-layer front and back cameras agree on its plane alone).
TEST(a_one_sided_sign_stops_the_spray_at_any_turn)
{
    const char *dir = ensure_tmpdir();
    for (int degrees = 0; degrees <= 30; degrees += 30) {
        double c = cos(degrees * 3.14159265358979 / 180.0);
        double s = sin(degrees * 3.14159265358979 / 180.0);
        char obj[1024];
        size_t n = 0;
        static const double corner[4][2] = { { -1, 0 }, { 1, 0 }, { 1, 2 }, { -1, 2 } };
        for (int k = 0; k < 4; ++k) {
            n += (size_t)snprintf(obj + n, sizeof obj - n, "v %.7f %.7f %.7f\n", c * corner[k][0],
                                  corner[k][1], -s * corner[k][0]);
        }
        snprintf(obj + n, sizeof obj - n, "f 1 2 3\nf 1 3 4\n");
        ensure_write_file(dir, "sign.obj", obj);
        ENSURE(weathering_in(dir, "init sign.obj -o sign.xml --resolution 256 --force -q", true) ==
               0);
        char path[PATH_MAX];
        snprintf(path, sizeof path, "%s/sign.xml", dir);
        char *xml = ensure_read_file(path);
        ENSURE(xml != NULL);
        ENSURE(strstr(xml, "cameraName=\"front\" layers=\"2\"") != NULL);
        ENSURE(strstr(xml, "cameraName=\"back\" layers=\"2\"") != NULL);
        // 20 000 drops from a 1 x 1 m square 1.5 m in front, flying at the face.
        ENSURE(
            replace_between(&xml, "<Emitters>", "</Emitters>",
                            "\n<BoxEmitter name=\"spray\" minX=\"-0.5\" minY=\"0.5\" minZ=\"1.5\" "
                            "maxX=\"0.5\" maxY=\"1.5\" maxZ=\"1.5\" dirX=\"0\" dirY=\"0\" "
                            "dirZ=\"-1\" spread=\"0\" speed=\"6\" rate=\"200000\" start=\"0\" "
                            "end=\"0.1\" maxCollisions=\"60\" dirt=\"1\"/>\n"));
        ENSURE(replace_between(&xml, "<ForceFields>", "</ForceFields>",
                               "\n<Gravity acceleration=\"9.8\"/>\n"));
        ensure_write_file(dir, "sign.xml", xml);
        free(xml);
        ENSURE(weathering_in(dir, "run sign.xml --out sign --stats sign.json -q", true) == 0);
        snprintf(path, sizeof path, "%s/sign.json", dir);
        char *stats = ensure_read_file(path);
        ENSURE(stats != NULL);
        const char *emitted = strstr(stats, "\"particles_emitted\":");
        const char *missed = strstr(stats, "\"escaped_without_hit\":");
        ENSURE(emitted != NULL && missed != NULL);
        double e = strtod(emitted + strlen("\"particles_emitted\":"), NULL);
        double m = strtod(missed + strlen("\"escaped_without_hit\":"), NULL);
        free(stats);
        fprintf(stderr, "        %d degrees: %.0f drops, %.0f missed the sign\n", degrees, e, m);
        ENSURE(e > 19000.0);
        ENSURE(m < 0.01 * e);
    }
}

int main(void)
{
    RUN(rain_reaches_the_floor_of_a_niche_every_first_surface_hides);
    RUN(the_last_frame_of_a_layered_scene_is_the_final_mask);
    RUN(a_one_sided_sign_stops_the_spray_at_any_turn);
    return ensure_summary();
}
