// test_scene.c: the scene file (docs/design.md sections 3, 8, 9, 10, 11, 12):
// defaults, every attribute, camera matrices, substances, loads, exchanges,
// iterations and ageing rules, texture maps, derived masks, the bad scenes of
// tests/bad/, entity attacks, and the schema.
#include <dirent.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "ensure.h"
#include "io/exr.h"
#include "model/scene.h"
#include "io/scene_xml.h"
#include "model/camera.h"
#include "model/image.h"

// The schema checks (xmllint against xml_scenes/weathering.xsd), at the end.
static bool have_xmllint_and_schema(void);

// The matrices of tests/data: a camera at z = 10 looking along -Z over a
// 4 x 4 m frame centred on the origin (u = x/4 + 1/2, v = y/4 + 1/2, d = 10 - z).
static const float front_wtc[16] = { 0.25f, 0, 0, 0, 0,    0.25f, 0,  0,
                                     0,     0, -1, 0, 0.5f, 0.5f, 10, 1 };
static const float front_ctw[16] = { 4, 0, 0, 0, 0, 4, 0, 0, 0, 0, -1, 0, -2, -2, 10, 1 };

static const char *data_path(const char *name)
{
    static char paths[4][4096];
    static int next;
    char *path = paths[next];
    next = (next + 1) % 4;
    snprintf(path, 4096, "%s/data/%s", ensure_tests_dir(), name);
    return path;
}

// A W x H map with channels R, G, B (depth 5, normal +Z...: values do not
// matter to the scene loader, only the size).
static bool write_map(const char *path, int width, int height)
{
    static const char *const names[3] = { "R", "G", "B" };
    wx_image image;
    wx_error err;
    memset(&image, 0, sizeof image);
    if (wx_image_alloc(&image, width, height, 3, names, &err) != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
        return false;
    }
    for (int i = 0; i < width * height; ++i) {
        image.channels[0][i] = 5.0f;
        image.channels[2][i] = 1.0f;
    }
    wx_result r = wx_exr_write(path, &image, &err);
    wx_image_free(&image);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    return r == WX_OK;
}

static bool map_size(const char *path, int *width, int *height)
{
    wx_image header;
    wx_error err;
    memset(&header, 0, sizeof header);
    wx_result r = wx_exr_read_header(path, &header, &err);
    *width = header.width;
    *height = header.height;
    wx_image_free(&header);
    return r == WX_OK;
}

static bool matrices_near(const float *a, const float *b, float tol)
{
    for (int i = 0; i < 16; ++i) {
        if (!(fabsf(a[i] - b[i]) <= tol)) {
            return false;
        }
    }
    return true;
}

// The committed maps of tests/data (WX_REGEN_TEST_DATA=1 writes them again).
TEST(data_maps)
{
    if (getenv("WX_REGEN_TEST_DATA") != NULL) {
        ENSURE(write_map(data_path("map4.exr"), 4, 4));
        ENSURE(write_map(data_path("map8.exr"), 8, 8));
    }
    int w, h;
    ENSURE(map_size(data_path("map4.exr"), &w, &h));
    ENSURE(w == 4 && h == 4);
    ENSURE(map_size(data_path("map8.exr"), &w, &h));
    ENSURE(w == 8 && h == 8);
}

// A scene in the thesis' format: only the collider; everything else defaults.
TEST(thesis_minimal_defaults)
{
    wx_scene s;
    wx_error err;
    wx_result r = wx_scene_load(data_path("thesis_minimal.xml"), &s, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    char dir[4096];
    snprintf(dir, sizeof dir, "%s/data", ensure_tests_dir());
    ENSURE(strcmp(s.dir, dir) == 0);
    ENSURE(strcmp(s.name, "thesis_minimal") == 0);
    ENSURE(strcmp(s.path, data_path("thesis_minimal.xml")) == 0);
    ENSURE(s.bbox_size == 100.0f);
    ENSURE(s.bbox_center[0] == 0.0f && s.bbox_center[1] == 0.0f && s.bbox_center[2] == 0.0f);
    ENSURE(s.time_step == 0.01);
    ENSURE(s.steps == 1000);
    ENSURE(s.seed == 1);
    ENSURE_NEAR(wx_scene_duration(&s), 10.0, 1e-12);
    ENSURE(s.collider.resilience == 0.5f && s.collider.friction == 0.8f);
    ENSURE(s.collider.adherence == 1.0f && s.collider.deposit == 1.0f);
    ENSURE(s.collider.erosion == 1.0f);
    ENSURE(s.field_count == 0 && s.fields == NULL);
    ENSURE(s.emitter_count == 0 && s.emitters == NULL);
    ENSURE(s.mesh_count == 0);
    ENSURE(s.camera_count == 1 && s.input_count == 1 && s.output_index == -1);
    const wx_scene_camera *c = &s.cameras[0];
    ENSURE(strcmp(c->name, "front") == 0 && !c->is_output && !c->has_view);
    ENSURE(c->camera.width == 4 && c->camera.height == 4);
    ENSURE(matrices_near(c->camera.wtc, front_wtc, 0.0f));
    ENSURE(matrices_near(c->camera.ctw, front_ctw, 0.0f));
    ENSURE(strcmp(c->depth_path, data_path("map4.exr")) == 0);
    ENSURE(strcmp(c->dirt_path, data_path("map4.exr")) == 0);
    ENSURE(c->line == 9);
    wx_scene_free(&s);
    ENSURE(s.cameras == NULL && s.camera_count == 0);
}

// Each element with no optional attribute takes the defaults of docs/design.md section 3.
TEST(element_defaults)
{
    wx_scene s;
    wx_error err;
    wx_result r = wx_scene_load(data_path("defaults.xml"), &s, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    ENSURE(s.bbox_size == 100.0f && s.time_step == 0.01 && s.steps == 1000 && s.seed == 1);

    ENSURE(s.field_count == 3);
    ENSURE(s.fields[0].kind == WX_FIELD_GRAVITY && s.fields[0].strength == 9.8f);
    ENSURE(s.fields[0].line == 10);
    ENSURE(s.fields[1].kind == WX_FIELD_WIND && s.fields[1].strength == 0.0f);
    ENSURE(s.fields[1].dir[0] == 1.0f && s.fields[1].dir[1] == 0.0f && s.fields[1].dir[2] == 0.0f);
    ENSURE(s.fields[2].kind == WX_FIELD_TURBULENCE && s.fields[2].strength == 0.0f);
    ENSURE(s.fields[2].frequency == 1.0f && s.fields[2].octaves == 4);

    ENSURE(s.emitter_count == 3);
    for (int i = 0; i < 3; ++i) {
        const wx_emitter *e = &s.emitters[i];
        ENSURE(e->name[0] == '\0');
        ENSURE(e->center[0] == 0.0f && e->center[1] == 0.0f && e->center[2] == 0.0f);
        ENSURE(e->rate == 1000.0 && e->start == 0.0);
        ENSURE_NEAR(e->end, 10.0, 1e-12); // steps * timeStep = 1000 * 0.01
        ENSURE(e->speed == 1.0f && e->mass == 1.0f && e->load[0] == 1.0f);
        ENSURE(e->max_collisions == 100);
    }
    ENSURE(s.emitters[0].kind == WX_EMITTER_POINT && s.emitters[0].radius == 0.0f);
    ENSURE(s.emitters[1].kind == WX_EMITTER_HEMISPHERE && s.emitters[1].radius == 1.0f);
    // A box emitter: straight down, no spread (docs/design.md section 8).
    const wx_emitter *box = &s.emitters[2];
    ENSURE(box->kind == WX_EMITTER_BOX);
    ENSURE(box->box_min[0] == -1.0f && box->box_min[1] == 2.0f && box->box_min[2] == -1.0f);
    ENSURE(box->box_max[0] == 1.0f && box->box_max[1] == 2.0f && box->box_max[2] == 1.0f);
    ENSURE(box->dir[0] == 0.0f && box->dir[1] == -1.0f && box->dir[2] == 0.0f);
    ENSURE(box->spread == 0.0f);

    ENSURE(s.camera_count == 2 && s.input_count == 1 && s.output_index == 1);
    const wx_scene_camera *in = &s.cameras[0];
    // CTWMatrix absent: derived from WTCMatrix.
    ENSURE(matrices_near(in->camera.ctw, front_ctw, 1e-5f));
    const wx_scene_camera *out = &s.cameras[1];
    ENSURE(out->is_output && strcmp(out->name, "out") == 0);
    ENSURE(out->camera.width == 8 && out->camera.height == 8);
    ENSURE(strcmp(out->output_file, "mask.exr") == 0);
    ENSURE(out->output_width == 8 && out->output_height == 8);
    // No radius: the adaptive smoothing, noise 4%, radii up to 16 output texels
    // (the frame is 4 m wide over 8 texels: 8 m).
    ENSURE(out->adaptive && out->noise == WX_DEFAULT_NOISE && WX_DEFAULT_NOISE == 0.04f);
    ENSURE_NEAR(out->max_radius, 8.0, 1e-5);
    ENSURE(out->second_pass == WX_SECOND_PASS_MEAN && !out->normalize);
    ENSURE(!wx_has_path(out->impact_path) && !wx_has_path(out->dirt_path));

    ENSURE(s.mesh_count == 1 && s.meshes[0].surface_count == 1);
    ENSURE(strcmp(s.meshes[0].path, data_path("box.obj")) == 0);
    const wx_surface *sf = &s.meshes[0].surfaces[0];
    ENSURE(strcmp(sf->material, "*") == 0);
    ENSURE(sf->absorption == 0.0f && sf->bounce == 0.0f && sf->initial[0] == 0.0f);
    ENSURE(sf->deposit[0] == 0.0f && sf->erosion[0] == 0.0f && sf->colors == WX_COLOR_NONE);
    wx_scene_free(&s);
}

// Every element and attribute, in an unusual order, parsed to the right values.
TEST(full_scene)
{
    wx_scene s;
    wx_error err;
    wx_result r = wx_scene_load(data_path("full.xml"), &s, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    ENSURE(strcmp(s.name, "full") == 0);
    ENSURE(s.bbox_size == 50.0f);
    ENSURE(s.bbox_center[0] == 1.0f && s.bbox_center[1] == 2.5f && s.bbox_center[2] == -3.0f);
    ENSURE(s.time_step == 0.02 && s.steps == 500);
    ENSURE(s.seed == UINT64_MAX);
    ENSURE(s.collider.resilience == 0.25f && s.collider.friction == 0.75f);
    ENSURE(s.collider.adherence == 2.0f && s.collider.deposit == 0.5f);
    ENSURE(s.collider.erosion == 1.5f);

    ENSURE(s.field_count == 4);
    ENSURE(s.fields[0].kind == WX_FIELD_WIND && s.fields[0].strength == 2.0f);
    ENSURE_NEAR(s.fields[0].dir[0], 0.6, 1e-7); // (3, 0, 4) normalised
    ENSURE_NEAR(s.fields[0].dir[1], 0.0, 1e-7);
    ENSURE_NEAR(s.fields[0].dir[2], 0.8, 1e-7);
    ENSURE(s.fields[1].kind == WX_FIELD_GRAVITY && s.fields[1].strength == 3.7f);
    ENSURE(s.fields[2].kind == WX_FIELD_TURBULENCE && s.fields[2].strength == 0.5f);
    ENSURE(s.fields[2].frequency == 0.25f && s.fields[2].octaves == 6);
    ENSURE(s.fields[3].kind == WX_FIELD_WIND && s.fields[3].dir[2] == -1.0f);

    ENSURE(s.emitter_count == 3);
    const wx_emitter *p1 = &s.emitters[0];
    ENSURE(p1->kind == WX_EMITTER_POINT && strcmp(p1->name, "p1") == 0);
    ENSURE(p1->center[0] == 1.0f && p1->center[1] == 5.0f && p1->center[2] == -2.0f);
    ENSURE(p1->rate == 250.0 && p1->start == 0.5 && p1->end == 2.0);
    ENSURE(p1->speed == 3.0f && p1->mass == 2.0f && p1->load[0] == 0.5f);
    ENSURE(p1->max_collisions == 7);
    const wx_emitter *sky = &s.emitters[1];
    ENSURE(sky->kind == WX_EMITTER_HEMISPHERE && strcmp(sky->name, "sky") == 0);
    ENSURE(sky->center[1] == 1.0f && sky->radius == 20.0f);
    ENSURE(sky->rate == 5000.0 && sky->start == 1.0 && sky->end == 9.5);
    ENSURE(sky->speed == 2.0f && sky->mass == 0.5f && sky->load[0] == 1.5f);
    ENSURE(sky->max_collisions == 50);
    const wx_emitter *rain = &s.emitters[2];
    ENSURE(rain->kind == WX_EMITTER_BOX && strcmp(rain->name, "rain") == 0);
    ENSURE(rain->box_min[0] == -2.0f && rain->box_min[1] == 6.0f && rain->box_min[2] == -3.0f);
    ENSURE(rain->box_max[0] == 2.0f && rain->box_max[1] == 6.0f && rain->box_max[2] == 3.0f);
    ENSURE_NEAR(rain->dir[0], 1.0 / 3.0, 1e-7); // (1, -2, 2) made unit
    ENSURE_NEAR(rain->dir[1], -2.0 / 3.0, 1e-7);
    ENSURE_NEAR(rain->dir[2], 2.0 / 3.0, 1e-7);
    ENSURE(rain->spread == 15.0f && rain->rate == 8000.0 && rain->start == 0.25);
    ENSURE(rain->end == 3.0 && rain->speed == 6.0f && rain->mass == 0.25f);
    ENSURE(rain->load[0] == 2.0f && rain->max_collisions == 3);

    ENSURE(s.camera_count == 4 && s.input_count == 3 && s.output_index == 3);
    const wx_scene_camera *front = &s.cameras[0];
    ENSURE(!front->is_output && !front->has_view);
    ENSURE(matrices_near(front->camera.wtc, front_wtc, 0.0f));
    ENSURE(matrices_near(front->camera.ctw, front_ctw, 0.0f));
    ENSURE(strcmp(front->normal_path, data_path("map4.exr")) == 0);
    ENSURE(strcmp(front->impact_path, data_path("map4.exr")) == 0);

    const wx_scene_camera *side = &s.cameras[1];
    ENSURE(strcmp(side->name, "side.cam-1") == 0 && side->has_view && !side->is_output);
    ENSURE(side->view.eye[0] == 10.0f && side->view.up[1] == 1.0f);
    ENSURE(side->view.width_ws == 4.0f && side->view.height_ws == 2.0f);
    ENSURE(side->view.width_px == 8 && side->view.height_px == 4);
    ENSURE(side->camera.width == 8 && side->camera.height == 4);
    ENSURE(!wx_has_path(side->depth_path) && !wx_has_path(side->dirt_path));

    const wx_scene_camera *top = &s.cameras[2];
    ENSURE(top->has_view && top->view.up[2] == -1.0f);
    ENSURE(top->view.width_px == 8 && top->view.height_px == 8); // "8" means 8 x 8
    ENSURE(strcmp(top->dirt_path, data_path("map8.exr")) == 0);

    const wx_scene_camera *out = &s.cameras[3];
    ENSURE(out->is_output && strcmp(out->output_file, "dirt_mask.exr") == 0);
    ENSURE(out->output_width == 8 && out->output_height == 8);
    ENSURE(!out->adaptive && out->radius == 0.25f && out->second_pass == WX_SECOND_PASS_SUM && out->normalize);
    ENSURE(out->camera.width == 8 && out->camera.height == 8);

    ENSURE(s.mesh_count == 2);
    ENSURE(s.meshes[0].surface_count == 2 && s.meshes[1].surface_count == 0);
    const wx_surface *wall = &s.meshes[0].surfaces[0];
    ENSURE(strcmp(wall->material, "wall") == 0);
    ENSURE(wall->absorption == 0.25f && wall->bounce == 0.5f && wall->initial[0] == 2.0f);
    ENSURE(wall->deposit[0] == 0.75f && wall->erosion[0] == 0.125f && wall->colors == WX_COLOR_IMPACT);
    const wx_surface *rest = &s.meshes[0].surfaces[1];
    ENSURE(strcmp(rest->material, "*") == 0 && rest->absorption == 1.0f);
    ENSURE(rest->erosion[0] == 1.0f && rest->colors == WX_COLOR_DIRT);
    wx_scene_free(&s);
}

// View cameras: world points land where they were worked out by hand.
TEST(view_camera_matrices)
{
    const char *dir = ensure_tmpdir();
    const char *path = ensure_write_file(
        dir, "view.xml",
        "<Weathering>\n"
        "  <Collider><ProjectedMaps>\n"
        "    <Ortho cameraName=\"side\">\n"
        "      <View eye=\"10 0 0\" target=\"0 0 0\" width=\"4\" height=\"2\"\n"
        "            resolution=\"8 4\"/>\n"
        "    </Ortho>\n"
        "    <Ortho cameraName=\"front\" out=\"true\">\n"
        "      <View eye=\"0 0 10\" target=\"0 0 0\" up=\"0 1 0\" width=\"4\" height=\"2\"\n"
        "            resolution=\"8 4\"/>\n"
        "    </Ortho>\n"
        "  </ProjectedMaps></Collider>\n"
        "</Weathering>\n");
    wx_scene s;
    wx_error err;
    wx_result r = wx_scene_load(path, &s, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    ENSURE(strcmp(s.name, "view") == 0 && strcmp(s.dir, dir) == 0);
    // side: looks along -X, so right = forward x up = -Z, up = +Y, d = 10 - x.
    // (2, 0.5, -1): u = 1/4 + 1/2, v = 0.5/2 + 1/2, d = 8.
    const wx_camera *side = &s.cameras[0].camera;
    float uvd[3];
    wx_camera_world_to_map(side, (const float[3]){ 2.0f, 0.5f, -1.0f }, uvd);
    ENSURE_NEAR(uvd[0], 0.75, 1e-6);
    ENSURE_NEAR(uvd[1], 0.75, 1e-6);
    ENSURE_NEAR(uvd[2], 8.0, 1e-5);
    // (2, -0.5, 1): u = -1/4 + 1/2, v = -0.5/2 + 1/2.
    wx_camera_world_to_map(side, (const float[3]){ 2.0f, -0.5f, 1.0f }, uvd);
    ENSURE_NEAR(uvd[0], 0.25, 1e-6);
    ENSURE_NEAR(uvd[1], 0.25, 1e-6);
    ENSURE_NEAR(uvd[2], 8.0, 1e-5);
    ENSURE(s.cameras[0].camera.width == 8 && s.cameras[0].camera.height == 4);
    // front: looks along -Z: (1, 0.5, 3) -> u = 0.75, v = 0.75, d = 7.
    const wx_scene_camera *out = &s.cameras[1];
    wx_camera_world_to_map(&out->camera, (const float[3]){ 1.0f, 0.5f, 3.0f }, uvd);
    ENSURE_NEAR(uvd[0], 0.75, 1e-6);
    ENSURE_NEAR(uvd[1], 0.75, 1e-6);
    ENSURE_NEAR(uvd[2], 7.0, 1e-5);
    // No <OutputMap>: mask.exr at the View's resolution, adaptive smoothing with
    // radii up to 16 texels = 16 * 4/8 m.
    ENSURE(out->is_output && strcmp(out->output_file, "mask.exr") == 0);
    ENSURE(out->output_width == 8 && out->output_height == 4);
    ENSURE(out->adaptive && out->noise == 0.04f);
    ENSURE_NEAR(out->max_radius, 8.0, 1e-5);
    ENSURE(!wx_has_path(out->depth_path));
    wx_scene_free(&s);
}

// A camera rotated to look down -Y: u = x/4 + 1/2, v = -z/4 + 1/2, d = 10 - y.
static const char *const top_wtc = "0.25 0 0 0  0 0 -1 0  0 -0.25 0 0  0.5 0.5 10 1";
static const char *const top_ctw = "4 0 0 0  0 0 -4 0  0 -1 0 0  -2 10 2 1";
static const float top_ctw_values[16] = { 4, 0, 0, 0, 0, 0, -4, 0, 0, -1, 0, 0, -2, 10, 2, 1 };
static const float top_wtc_values[16] = { 0.25f, 0, 0, 0,     0,    0,  -1, 0,
                                          0,     -0.25f, 0, 0, 0.5f, 0.5f, 10, 1 };

static const char *matrix_scene(const char *name, const char *wtc, const char *ctw)
{
    const char *dir = ensure_tmpdir();
    char maps[4][64];
    for (int k = 0; k < 4; ++k) {
        snprintf(maps[k], sizeof maps[k], "%s_%d.exr", name, k);
        char path[4200];
        snprintf(path, sizeof path, "%s/%s", dir, maps[k]);
        if (!write_map(path, 16, 8)) {
            return NULL;
        }
    }
    char text[4096];
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Collider>\n"
             "    <ProjectedMaps>\n"
             "      <Ortho cameraName=\"top\">\n"
             "%s%s%s"
             "%s%s%s"
             "        <DepthMap file=\"%s\"/>\n"
             "        <NormalMap file=\"%s\"/>\n"
             "        <ImpactMap file=\"%s\"/>\n"
             "        <DirtMap file=\"%s\"/>\n"
             "      </Ortho>\n"
             "    </ProjectedMaps>\n"
             "  </Collider>\n"
             "</Weathering>\n",
             wtc != NULL ? "        <WTCMatrix matrix=\"" : "", wtc != NULL ? wtc : "",
             wtc != NULL ? "\"/>\n" : "", ctw != NULL ? "        <CTWMatrix matrix=\"" : "",
             ctw != NULL ? ctw : "", ctw != NULL ? "\"/>\n" : "", maps[0], maps[1], maps[2],
             maps[3]);
    char file[128];
    snprintf(file, sizeof file, "%s.xml", name);
    return ensure_write_file(dir, file, text);
}

// CTWMatrix absent: the inverse of WTCMatrix; WTCMatrix absent: the inverse of CTW.
TEST(ctw_derived_when_absent)
{
    const char *path = matrix_scene("wtc_only", top_wtc, NULL);
    ENSURE(path != NULL);
    wx_scene s;
    wx_error err;
    wx_result r = wx_scene_load(path, &s, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    const wx_camera *cam = &s.cameras[0].camera;
    ENSURE(matrices_near(cam->wtc, top_wtc_values, 0.0f));
    ENSURE(matrices_near(cam->ctw, top_ctw_values, 1e-5f));
    ENSURE(cam->width == 16 && cam->height == 8);
    // Map centre at depth 3 is the world point (0, 7, 0).
    float p[3];
    wx_camera_map_to_world(cam, (const float[3]){ 0.5f, 0.5f, 3.0f }, p);
    ENSURE_NEAR(p[0], 0.0, 1e-5);
    ENSURE_NEAR(p[1], 7.0, 1e-5);
    ENSURE_NEAR(p[2], 0.0, 1e-5);
    wx_scene_free(&s);

    path = matrix_scene("ctw_only", NULL, top_ctw);
    ENSURE(path != NULL);
    r = wx_scene_load(path, &s, &err);
    ENSURE(r == WX_OK);
    ENSURE(matrices_near(s.cameras[0].camera.wtc, top_wtc_values, 1e-6f));
    ENSURE(matrices_near(s.cameras[0].camera.ctw, top_ctw_values, 0.0f));
    wx_scene_free(&s);

    // Both given, printed with a few digits: within the tolerance.
    path = matrix_scene("both_rounded", "0.250001 0 0 0  0 0 -1 0  0 -0.25 0 0  0.5 0.5 10 1",
                        top_ctw);
    ENSURE(path != NULL);
    r = wx_scene_load(path, &s, &err);
    ENSURE(r == WX_OK);
    wx_scene_free(&s);
}

TEST(ctw_not_inverse_is_an_error)
{
    const char *path =
        matrix_scene("not_inverse", top_wtc, "4 0 0 0  0 0 -4 0  0 -1 0 0  -2 10 3 1");
    ENSURE(path != NULL);
    wx_scene s;
    wx_error err;
    ENSURE(wx_scene_load(path, &s, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_CAMERA);
    char expected[4200];
    snprintf(expected, sizeof expected, "%s:6: <CTWMatrix> of camera 'top' is not the inverse",
             path);
    if (!ensure_contains(err.message, expected)) {
        fprintf(stderr, "got: %s\n", err.message);
    }
    ENSURE(strncmp(err.message, expected, strlen(expected)) == 0);
    ENSURE(s.cameras == NULL && s.camera_count == 0); // left empty
    wx_scene_free(&s);                                // and safe to free
}

static int compare_names(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

// Every tests/bad/*.xml fails for its cause with "path:LINE:" and its substring.
TEST(bad_scenes)
{
    char dir_path[4096];
    snprintf(dir_path, sizeof dir_path, "%s/bad", ensure_tests_dir());
    DIR *dir = opendir(dir_path);
    ENSURE(dir != NULL);
    char *names[256];
    int count = 0;
    struct dirent *entry;
    while ((entry = readdir(dir)) != NULL && count < 256) {
        size_t len = strlen(entry->d_name);
        if (len > 4 && strcmp(entry->d_name + len - 4, ".xml") == 0) {
            names[count++] = strdup(entry->d_name);
        }
    }
    closedir(dir);
    qsort(names, (size_t)count, sizeof names[0], compare_names);
    int failures = 0;
    for (int i = 0; i < count; ++i) {
        char path[4400];
        snprintf(path, sizeof path, "%s/%s", dir_path, names[i]);
        ensure_expectation want;
        if (!ensure_read_expectation(path, &want)) {
            failures++;
            continue;
        }
        wx_scene s;
        wx_error err;
        memset(&err, 0, sizeof err);
        wx_result r = wx_scene_load(path, &s, &err);
        char prefix[4500];
        snprintf(prefix, sizeof prefix, "%s:%d: ", path, want.line);
        bool ok = r == WX_BAD_INPUT && err.cause == want.cause &&
                  strncmp(err.message, prefix, strlen(prefix)) == 0 &&
                  ensure_contains(err.message, want.substring);
        if (!ok) {
            fprintf(stderr, "%s: expected %s with \"%s...%s\", got %d %s: %s\n", names[i],
                    wx_cause_name(want.cause), prefix, want.substring, (int)r,
                    wx_cause_name(err.cause), err.message);
            failures++;
        }
        ENSURE(s.cameras == NULL && s.fields == NULL && s.emitters == NULL && s.meshes == NULL);
        wx_scene_free(&s);
    }
    for (int i = 0; i < count; ++i) {
        free(names[i]);
    }
    ENSURE(count >= 12);
    ENSURE(failures == 0);
}

// --- substances, loads, exchanges, iterations, rules (docs/design.md sections 9, 10) ---

// A version-1 scene has the one substance "dirt" at index 0, emitters carry 1
// of it, one iteration, no rules, no image sequence.
TEST(version1_scene_has_substance_dirt)
{
    wx_scene s;
    wx_error err;
    wx_result r = wx_scene_load(data_path("defaults.xml"), &s, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    ENSURE(!s.substances_declared && s.substance_count == 1);
    ENSURE(strcmp(s.substances[0], "dirt") == 0 && s.dirt_substance == 0);
    ENSURE(wx_scene_substance(&s, "dirt") == 0 && wx_scene_substance(&s, "water") == -1);
    ENSURE(s.iterations == 1 && s.rule_count == 0 && s.rules == NULL);
    ENSURE(!wx_scene_has_ageing(&s) && !wx_scene_has_surface_rules(&s));
    for (int i = 0; i < s.emitter_count; ++i) {
        ENSURE(s.emitters[i].load[0] == 1.0f);
        for (int k = 1; k < WX_MAX_SUBSTANCES; ++k) {
            ENSURE(s.emitters[i].load[k] == 0.0f);
        }
    }
    ENSURE(s.cameras[s.output_index].every == 0);
    const wx_surface *sf = &s.meshes[0].surfaces[0];
    ENSURE(sf->rule_count == 0 && sf->rules == NULL);
    for (int k = 0; k < WX_MAX_SUBSTANCES; ++k) {
        ENSURE(sf->initial[k] == 0.0f && sf->deposit[k] == 0.0f && sf->erosion[k] == 0.0f);
    }
    wx_scene_free(&s);

    // The thesis' format: no emitters, no <Solver>, the same substance defaults.
    r = wx_scene_load(data_path("thesis_minimal.xml"), &s, &err);
    ENSURE(r == WX_OK);
    ENSURE(s.substance_count == 1 && strcmp(s.substances[0], "dirt") == 0);
    ENSURE(s.dirt_substance == 0 && !s.substances_declared && s.iterations == 1);
    wx_scene_free(&s);

    // full.xml's dirt attributes are substance dirt's, at index 0.
    r = wx_scene_load(data_path("full.xml"), &s, &err);
    ENSURE(r == WX_OK);
    ENSURE(s.emitters[0].load[0] == 0.5f && s.emitters[0].load[1] == 0.0f);
    ENSURE(s.meshes[0].surfaces[0].initial[0] == 2.0f);
    ENSURE(s.meshes[0].surfaces[0].deposit[0] == 0.75f);
    wx_scene_free(&s);
}

// A file of tests/data by an absolute path, for scenes written elsewhere.
static const char *abs_data_path(const char *name)
{
    static char paths[2][8200];
    static int next;
    char *path = paths[next];
    next = (next + 1) % 2;
    const char *rel = data_path(name);
    char cwd[4096];
    if (rel[0] == '/' || getcwd(cwd, sizeof cwd) == NULL) {
        snprintf(path, 8200, "%s", rel);
    } else {
        snprintf(path, 8200, "%s/%s", cwd, rel);
    }
    return path;
}

// A collider of two View cameras (maps that bake makes), as text for a scene.
#define VIEW_COLLIDER                                                                        \
    "  <Collider><ProjectedMaps>\n"                                                          \
    "    <Ortho cameraName=\"top\">\n"                                                       \
    "      <View eye=\"0 10 0\" target=\"0 0 0\" up=\"0 0 -1\" width=\"4\" height=\"4\"\n"  \
    "            resolution=\"8\"/>\n"                                                       \
    "    </Ortho>\n"                                                                         \
    "    <Ortho cameraName=\"out\" out=\"true\">\n"                                          \
    "      <View eye=\"0 10 0\" target=\"0 0 0\" up=\"0 0 -1\" width=\"4\" height=\"4\"\n"  \
    "            resolution=\"8\"/>\n"                                                       \
    "      <OutputMap file=\"mask.exr\" every=\"3\"/>\n"                                     \
    "    </Ortho>\n"                                                                         \
    "  </ProjectedMaps></Collider>\n"

static bool rule_is(const wx_rule *rule, wx_rule_kind kind, int substance, int to, float rate,
                    float amount, int line)
{
    bool ok = rule->kind == kind && rule->substance == substance && rule->to == to &&
              rule->rate == rate && rule->amount == amount && rule->line == line;
    if (!ok) {
        fprintf(stderr, "rule at line %d: kind %d substance %d to %d rate %g amount %g\n",
                rule->line, (int)rule->kind, rule->substance, rule->to, (double)rule->rate,
                (double)rule->amount);
    }
    return ok;
}

// Every element of sections 9 and 10, <Substances> after the elements that name
// its substances (it is read first, wherever it stands).
TEST(substances_loads_exchanges_rules)
{
    char text[65536];
    snprintf(text, sizeof text,
             "<Weathering>\n"                                                          // 1
             "  <Emitters>\n"                                                          // 2
             "    <BoxEmitter name=\"rain\" minX=\"-1\" minY=\"5\" minZ=\"-1\" maxX=\"1\" "
             "maxY=\"5\" maxZ=\"1\" dirt=\"0.2\">\n"                                   // 3
             "      <Load substance=\"water\" amount=\"1\"/>\n"                        // 4
             "      <Load substance=\"rust\" amount=\"0\"/>\n"                         // 5
             "    </BoxEmitter>\n"                                                     // 6
             "    <PointEmitter name=\"dry\" centerY=\"3\"/>\n"                        // 7
             "    <HemisphereEmitter name=\"mist\" radius=\"9\">\n"                    // 8
             "      <Load substance=\"moss\" amount=\"0.5\"/>\n"                       // 9
             "    </HemisphereEmitter>\n"                                              // 10
             "  </Emitters>\n"                                                         // 11
             "  <Ageing>\n"                                                            // 12
             "    <Transfer from=\"water\" to=\"rust\" rate=\"0.1\"/>\n"               // 13
             "    <Decay substance=\"water\" rate=\"0.5\"/>\n"                         // 14
             "    <Grow substance=\"moss\" amount=\"0.01\"/>\n"                        // 15
             "    <Transfer from=\"rust\" to=\"dirt\" rate=\"1\"/>\n"                  // 16
             "  </Ageing>\n"                                                           // 17
             "  <Geometry><Mesh file=\"%s\">\n"                                        // 18
             "    <Surface material=\"iron\" absorption=\"0.2\" bounce=\"0.3\" dirt=\"0.5\" "
             "deposit=\"0.25\" erosion=\"0.125\">\n"                                   // 19
             "      <Decay substance=\"rust\" rate=\"0\"/>\n"                          // 20
             "      <Exchange substance=\"water\" initial=\"2\" deposit=\"0.75\" "
             "erosion=\"0.5\"/>\n"                                                     // 21
             "      <Transfer from=\"water\" to=\"rust\" rate=\"0.3\"/>\n"             // 22
             "      <Exchange substance=\"moss\" deposit=\"1\"/>\n"                    // 23
             "      <Grow substance=\"moss\" amount=\"2\"/>\n"                         // 24
             "    </Surface>\n"                                                        // 25
             "    <Surface material=\"*\"/>\n"                                         // 26
             "  </Mesh></Geometry>\n"                                                  // 27
             "  <Solver><Simulation steps=\"10\" iterations=\"7\"/></Solver>\n"        // 28
             "  <Substances>\n"                                                        // 29
             "    <Substance name=\"water\"/>\n"                                       // 30
             "    <Substance name=\"rust\"/>\n"                                        // 31
             "    <Substance name=\"dirt\"/>\n"                                        // 32
             "    <Substance name=\"moss\"/>\n"                                        // 33
             "  </Substances>\n" VIEW_COLLIDER "</Weathering>\n",
             abs_data_path("box.obj"));
    const char *path = ensure_write_file(ensure_tmpdir(), "substances.xml", text);
    wx_scene s;
    wx_error err;
    wx_result r = wx_scene_load(path, &s, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    enum { WATER, RUST, DIRT, MOSS };
    ENSURE(s.substances_declared && s.substance_count == 4);
    ENSURE(strcmp(s.substances[WATER], "water") == 0 && strcmp(s.substances[RUST], "rust") == 0);
    ENSURE(strcmp(s.substances[DIRT], "dirt") == 0 && strcmp(s.substances[MOSS], "moss") == 0);
    ENSURE(s.substances[4][0] == '\0');
    ENSURE(s.dirt_substance == DIRT && s.iterations == 7 && s.steps == 10);
    ENSURE(wx_scene_has_ageing(&s) && wx_scene_has_surface_rules(&s) && wx_scene_has_grow(&s));

    // Loads: dirt= is substance dirt's; every other load defaults to 0.
    ENSURE(s.emitter_count == 3);
    const float rain[WX_MAX_SUBSTANCES] = { [WATER] = 1.0f, [DIRT] = 0.2f };
    const float mist[WX_MAX_SUBSTANCES] = { [MOSS] = 0.5f };
    for (int k = 0; k < WX_MAX_SUBSTANCES; ++k) {
        ENSURE(s.emitters[0].load[k] == rain[k]);
        ENSURE(s.emitters[1].load[k] == 0.0f);
        ENSURE(s.emitters[2].load[k] == mist[k]);
    }

    // Global rules in document order.
    ENSURE(s.rule_count == 4);
    ENSURE(rule_is(&s.rules[0], WX_RULE_TRANSFER, WATER, RUST, 0.1f, 0.0f, 13));
    ENSURE(rule_is(&s.rules[1], WX_RULE_DECAY, WATER, -1, 0.5f, 0.0f, 14));
    ENSURE(rule_is(&s.rules[2], WX_RULE_GROW, MOSS, -1, 0.0f, 0.01f, 15));
    ENSURE(rule_is(&s.rules[3], WX_RULE_TRANSFER, RUST, DIRT, 1.0f, 0.0f, 16));

    // Exchanges: the attributes are dirt's, <Exchange> the others', 0 elsewhere.
    const wx_surface *iron = &s.meshes[0].surfaces[0];
    ENSURE(strcmp(iron->material, "iron") == 0 && iron->line == 19);
    ENSURE(iron->absorption == 0.2f && iron->bounce == 0.3f);
    const float initial[WX_MAX_SUBSTANCES] = { [WATER] = 2.0f, [DIRT] = 0.5f };
    const float deposit[WX_MAX_SUBSTANCES] = { [WATER] = 0.75f, [DIRT] = 0.25f, [MOSS] = 1.0f };
    const float erosion[WX_MAX_SUBSTANCES] = { [WATER] = 0.5f, [DIRT] = 0.125f };
    for (int k = 0; k < WX_MAX_SUBSTANCES; ++k) {
        ENSURE(iron->initial[k] == initial[k]);
        ENSURE(iron->deposit[k] == deposit[k]);
        ENSURE(iron->erosion[k] == erosion[k]);
    }
    // The surface's own rules, in document order among its <Exchange>s.
    ENSURE(iron->rule_count == 3);
    ENSURE(rule_is(&iron->rules[0], WX_RULE_DECAY, RUST, -1, 0.0f, 0.0f, 20));
    ENSURE(rule_is(&iron->rules[1], WX_RULE_TRANSFER, WATER, RUST, 0.3f, 0.0f, 22));
    ENSURE(rule_is(&iron->rules[2], WX_RULE_GROW, MOSS, -1, 0.0f, 2.0f, 24));
    const wx_surface *rest = &s.meshes[0].surfaces[1];
    ENSURE(rest->rule_count == 0 && rest->rules == NULL);
    for (int k = 0; k < WX_MAX_SUBSTANCES; ++k) {
        ENSURE(rest->initial[k] == 0.0f && rest->deposit[k] == 0.0f && rest->erosion[k] == 0.0f);
    }
    ENSURE(s.cameras[s.output_index].every == 3);
    ENSURE(s.cameras[0].every == 0);
    wx_scene_free(&s);
    ENSURE(s.rules == NULL && s.rule_count == 0);
    ENSURE(have_xmllint_and_schema());
    {
        char out[8192];
        int status = ensure_shell(
            out, sizeof out, "xmllint --noout --schema xml_scenes/weathering.xsd '%s'", path);
        if (status != 0) {
            fprintf(stderr, "%s", out);
        }
        ENSURE(status == 0);
    }
}

/// Loads `text` written as `name`; says why when a scene that should load does not.
static wx_result load_text(const char *name, const char *text, wx_scene *s, wx_error *err,
                           bool should_load)
{
    const char *path = ensure_write_file(ensure_tmpdir(), name, text);
    memset(err, 0, sizeof *err);
    wx_result r = wx_scene_load(path, s, err);
    if ((r != WX_OK) == should_load) {
        fprintf(stderr, "(%s) %s\n", name, r != WX_OK ? err->message : "loads");
    }
    return r;
}

// Substance dirt anywhere in the list, or not declared at all.
TEST(substance_dirt_index_or_none)
{
    char text[65536];
    // "dirt" third: the dirt attributes go there, not to index 0.
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Substances><Substance name=\"a\"/><Substance name=\"b_2\"/>"
             "<Substance name=\"dirt\"/></Substances>\n"
             "  <Emitters><PointEmitter dirt=\"3\"/><PointEmitter/></Emitters>\n"
             "  <Geometry><Mesh file=\"%s\">\n"
             "    <Surface material=\"*\" dirt=\"4\" deposit=\"0.5\" erosion=\"0.25\"/>\n"
             "  </Mesh></Geometry>\n" VIEW_COLLIDER "</Weathering>\n",
             abs_data_path("box.obj"));
    wx_scene s;
    wx_error err;
    ENSURE(load_text("dirt_third.xml", text, &s, &err, true) == WX_OK);
    ENSURE(s.substance_count == 3 && s.dirt_substance == 2);
    ENSURE(s.emitters[0].load[0] == 0.0f && s.emitters[0].load[2] == 3.0f);
    ENSURE(s.emitters[1].load[0] == 0.0f && s.emitters[1].load[2] == 0.0f); // 0 with <Substances>
    const wx_surface *sf = &s.meshes[0].surfaces[0];
    ENSURE(sf->initial[2] == 4.0f && sf->deposit[2] == 0.5f && sf->erosion[2] == 0.25f);
    ENSURE(sf->initial[0] == 0.0f && sf->deposit[0] == 0.0f && sf->erosion[0] == 0.0f);
    wx_scene_free(&s);

    // No "dirt": dirt_substance -1, loads and exchanges only by name; a Surface
    // without the dirt attributes is fine.
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Substances><Substance name=\"water\"/></Substances>\n"
             "  <Emitters><PointEmitter><Load substance=\"water\" amount=\"0.5\"/>"
             "</PointEmitter></Emitters>\n"
             "  <Geometry><Mesh file=\"%s\">\n"
             "    <Surface material=\"*\" absorption=\"0.5\" vertexColors=\"impact\">"
             "<Exchange substance=\"water\" initial=\"1\"/></Surface>\n"
             "  </Mesh></Geometry>\n" VIEW_COLLIDER "</Weathering>\n",
             abs_data_path("box.obj"));
    ENSURE(load_text("no_dirt.xml", text, &s, &err, true) == WX_OK);
    ENSURE(s.substance_count == 1 && s.dirt_substance == -1 && s.substances_declared);
    ENSURE(strcmp(s.substances[0], "water") == 0 && s.emitters[0].load[0] == 0.5f);
    ENSURE(s.meshes[0].surfaces[0].initial[0] == 1.0f);
    ENSURE(s.meshes[0].surfaces[0].deposit[0] == 0.0f);
    ENSURE(wx_scene_has_ageing(&s) && !wx_scene_has_surface_rules(&s));
    wx_scene_free(&s);

    // Without <Substances>, "dirt" can be named too: <Load>, <Exchange>, rules.
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Emitters><PointEmitter><Load substance=\"dirt\" amount=\"2\"/>"
             "</PointEmitter></Emitters>\n"
             "  <Ageing><Decay substance=\"dirt\" rate=\"0.5\"/></Ageing>\n"
             "  <Geometry><Mesh file=\"%s\">\n"
             "    <Surface material=\"*\"><Exchange substance=\"dirt\" initial=\"1\" "
             "deposit=\"0.5\"/><Grow substance=\"dirt\" amount=\"1\"/></Surface>\n"
             "  </Mesh></Geometry>\n" VIEW_COLLIDER "</Weathering>\n",
             abs_data_path("box.obj"));
    ENSURE(load_text("dirt_by_name.xml", text, &s, &err, true) == WX_OK);
    ENSURE(!s.substances_declared && s.substance_count == 1 && s.dirt_substance == 0);
    ENSURE(s.emitters[0].load[0] == 2.0f);
    ENSURE(s.rule_count == 1 && s.rules[0].kind == WX_RULE_DECAY && s.rules[0].substance == 0);
    ENSURE(s.meshes[0].surfaces[0].initial[0] == 1.0f);
    ENSURE(s.meshes[0].surfaces[0].deposit[0] == 0.5f);
    ENSURE(s.meshes[0].surfaces[0].rule_count == 1);
    wx_scene_free(&s);
}

// The limits: 8 substances of up to 32 characters, names near the reserved ones,
// iterations up to 100000.
TEST(substance_limits_accepted)
{
    char text[65536];
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Substances>\n"
             "    <Substance name=\"a2345678901234567890123456789012\"/>\n"
             "    <Substance name=\"y\"/><Substance name=\"Ys\"/><Substance name=\"Seen\"/>\n"
             "    <Substance name=\"seen_2\"/><Substance name=\"see\"/>"
             "<Substance name=\"dirt\"/><Substance name=\"Z_\"/>\n"
             "  </Substances>\n"
             "  <Solver><Simulation steps=\"1\" iterations=\"100000\"/></Solver>\n"
             "%s</Weathering>\n",
             VIEW_COLLIDER);
    wx_scene s;
    wx_error err;
    ENSURE(load_text("limits.xml", text, &s, &err, true) == WX_OK);
    ENSURE(s.substance_count == WX_MAX_SUBSTANCES && s.dirt_substance == 6);
    ENSURE(strlen(s.substances[0]) == WX_SUBSTANCE_NAME_MAX);
    ENSURE(strcmp(s.substances[7], "Z_") == 0 && s.iterations == 100000);
    wx_scene_free(&s);
}

// Each bad input of issue 16 is refused at its element's line with its cause;
// tests/bad/ holds them as files (bad_scenes), these need a scene of their own.
TEST(substance_errors_at_their_line)
{
    char text[65536];
    wx_scene s;
    wx_error err;
    // Per-surface rules when an input camera's maps are given, even by a
    // <View> camera that names them: the bake does not record the surfaces.
    char map[8200];
    snprintf(map, sizeof map, "%s", abs_data_path("map8.exr"));
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Geometry><Mesh file=\"%s\">\n"
             "    <Surface material=\"*\">\n"
             "      <Grow substance=\"dirt\" amount=\"1\"/>\n"
             "    </Surface>\n"
             "  </Mesh></Geometry>\n"
             "  <Collider><ProjectedMaps>\n"
             "    <Ortho cameraName=\"baked\">\n"
             "      <View eye=\"0 10 0\" target=\"0 0 0\" up=\"0 0 -1\" width=\"4\" height=\"4\"\n"
             "            resolution=\"8\"/>\n"
             "    </Ortho>\n"
             "    <Ortho cameraName=\"given\">\n"
             "      <View eye=\"0 10 0\" target=\"0 0 0\" up=\"0 0 -1\" width=\"4\" height=\"4\"\n"
             "            resolution=\"8\"/>\n"
             "      <DepthMap file=\"%s\"/><NormalMap file=\"%s\"/>\n"
             "      <ImpactMap file=\"%s\"/><DirtMap file=\"%s\"/>\n"
             "    </Ortho>\n"
             "  </ProjectedMaps></Collider>\n"
             "</Weathering>\n",
             abs_data_path("box.obj"), map, map, map, map);
    ENSURE(load_text("view_maps_given.xml", text, &s, &err, false) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_SCENE);
    ENSURE(ensure_contains(err.message, "view_maps_given.xml:4: <Grow> in <Surface material=\"*\"> "
                                        "is a per-surface rule"));
    ENSURE(ensure_contains(err.message, "input camera 'given' (line 12) has pre-rendered maps"));
    ENSURE(s.meshes == NULL && s.rules == NULL);
    wx_scene_free(&s);

    // Global rules, exchanges and loads are fine with pre-rendered maps.
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Substances><Substance name=\"dirt\"/><Substance name=\"water\"/></Substances>\n"
             "  <Ageing><Decay substance=\"water\" rate=\"0.5\"/></Ageing>\n"
             "  <Emitters><PointEmitter><Load substance=\"water\" amount=\"1\"/></PointEmitter>"
             "</Emitters>\n"
             "  <Collider><ProjectedMaps>\n"
             "    <Ortho cameraName=\"given\">\n"
             "      <WTCMatrix matrix=\"0.25 0 0 0  0 0.25 0 0  0 0 -1 0  0.5 0.5 10 1\"/>\n"
             "      <DepthMap file=\"%s\"/><NormalMap file=\"%s\"/>\n"
             "      <ImpactMap file=\"%s\"/><DirtMap file=\"%s\"/>\n"
             "    </Ortho>\n"
             "  </ProjectedMaps></Collider>\n"
             "</Weathering>\n",
             map, map, map, map);
    ENSURE(load_text("global_rules_given_maps.xml", text, &s, &err, true) == WX_OK);
    ENSURE(s.rule_count == 1 && s.emitters[0].load[1] == 1.0f && s.emitters[0].load[0] == 0.0f);
    wx_scene_free(&s);

    // An error in <Substances> is found first, wherever it stands, and a
    // reference before the declaration is not an error.
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Emitters><PointEmitter><Load substance=\"rust\" amount=\"1\"/></PointEmitter>"
             "</Emitters>\n"
             "  <Substances>\n"
             "    <Substance name=\"rust\"/>\n"
             "    <Substance name=\"seen\"/>\n"
             "  </Substances>\n" VIEW_COLLIDER "</Weathering>\n");
    ENSURE(load_text("substances_last.xml", text, &s, &err, false) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_VALUE);
    ENSURE(ensure_contains(err.message, "substances_last.xml:5: <Substance> name=\"seen\" is "
                                        "reserved"));
    wx_scene_free(&s);
}

// --- texture maps (docs/design.md section 11) ---

// Two meshes with three <TextureMap>s: every default, a fixed radius with
// explicit values, the adaptive smoothing tuned. Line numbers matter.
static void texture_scene(char *text, size_t cap)
{
    snprintf(text, cap,
             "<Weathering>\n"                                                       // 1
             "  <Geometry>\n"                                                       // 2
             "    <Mesh file=\"%s\">\n"                                             // 3
             "      <Surface material=\"*\" deposit=\"0.5\"/>\n"                   // 4
             "      <TextureMap file=\"box.exr\"/>\n"                               // 5
             "    </Mesh>\n"                                                        // 6
             "    <Mesh file=\"%s\">\n"                                             // 7
             "      <TextureMap file=\"house_weathering.exr\" resolution=\"2048\"\n"  // 8
             "                  width=\"512\" padding=\"0\" uv=\"7\" every=\"5\" tiles=\" udim \"\n" // 9
             "                  radius=\"0.25\"/>\n"                                // 10
             "      <TextureMap file=\"tall.EXR\" resolution=\"64\" height=\"300\"\n" // 11
             "                  padding=\"1024\" uv=\"1\" noise=\"0.1\" maxRadius=\"2\"\n" // 12
             "                  tiles=\"clip\"/>\n"                                 // 13
             "    </Mesh>\n"                                                        // 14
             "  </Geometry>\n" VIEW_COLLIDER "</Weathering>\n",
             abs_data_path("box.obj"), abs_data_path("box.obj"));
}

static bool texture_is(const wx_texture_map *t, int mesh, const char *file, int width,
                       int height, int padding, int uv, int every, bool adaptive, float radius,
                       float noise, float max_radius, int line)
{
    bool ok = t->mesh == mesh && strcmp(t->file, file) == 0 && t->width == width &&
              t->height == height && t->padding == padding && t->uv == uv &&
              t->every == every && t->adaptive == adaptive && t->radius == radius &&
              t->noise == noise && t->max_radius == max_radius && t->line == line;
    if (!ok) {
        fprintf(stderr,
                "texture at line %d: mesh %d file %s %dx%d padding %d uv %d every %d adaptive %d "
                "radius %g noise %g maxRadius %g\n",
                t->line, t->mesh, t->file, t->width, t->height, t->padding, t->uv, t->every,
                (int)t->adaptive, (double)t->radius, (double)t->noise, (double)t->max_radius);
    }
    return ok;
}

TEST(texture_maps)
{
    char text[65536];
    texture_scene(text, sizeof text);
    wx_scene s;
    wx_error err;
    ENSURE(load_text("texture_maps.xml", text, &s, &err, true) == WX_OK);
    ENSURE(s.mesh_count == 2 && s.texture_count == 3);
    ENSURE(s.meshes[0].surface_count == 1 && s.meshes[1].surface_count == 0);
    // Defaults: 1024 x 1024, padding 8, channel 0, no frames, adaptive with the
    // default noise and max_radius 0 (16 texels of the camera, chosen later).
    ENSURE(texture_is(&s.textures[0], 0, "box.exr", 1024, 1024, 8, 0, 0, true, 0.0f,
                      WX_DEFAULT_NOISE, 0.0f, 5));
    ENSURE(WX_DEFAULT_TEXTURE_RESOLUTION == 1024 && WX_DEFAULT_TEXTURE_PADDING == 8);
    // width overrides resolution on its axis only; a radius: not adaptive.
    // (libxml2 gives an element the line where its start tag ends.)
    ENSURE(texture_is(&s.textures[1], 1, "house_weathering.exr", 512, 2048, 0, 7, 5, false,
                      0.25f, WX_DEFAULT_NOISE, 0.0f, 10));
    ENSURE(texture_is(&s.textures[2], 1, "tall.EXR", 64, 300, 1024, 1, 0, true, 0.0f, 0.1f,
                      2.0f, 13));
    // tiles: repeat by default (UVs outside [0,1] wrap), the keywords trimmed;
    // a UDIM texture's tiles are known only once its mesh is read.
    ENSURE(s.textures[0].tiles == WX_TILES_REPEAT && s.textures[1].tiles == WX_TILES_UDIM &&
           s.textures[2].tiles == WX_TILES_CLIP);
    ENSURE(!s.textures[1].udim_known && wx_texture_file_count(&s.textures[1]) == 0 &&
           wx_texture_file_count(&s.textures[0]) == 1);
    // The output camera is unchanged by them.
    ENSURE(s.output_index == 1 && strcmp(s.cameras[1].output_file, "mask.exr") == 0);
    wx_scene_free(&s);
    ENSURE(s.textures == NULL && s.texture_count == 0);

    // A scene with TextureMaps needs no output camera (nor does the loader ask
    // one of any scene: gather and run do, docs/design.md section 11).
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Geometry><Mesh file=\"%s\">\n"
             "    <TextureMap file=\"box.exr\" resolution=\"16\"/>\n"
             "  </Mesh></Geometry>\n"
             "  <Collider><ProjectedMaps>\n"
             "    <Ortho cameraName=\"top\">\n"
             "      <View eye=\"0 10 0\" target=\"0 0 0\" up=\"0 0 -1\" width=\"4\" height=\"4\"\n"
             "            resolution=\"8\"/>\n"
             "    </Ortho>\n"
             "  </ProjectedMaps></Collider>\n"
             "</Weathering>\n",
             abs_data_path("box.obj"));
    ENSURE(load_text("texture_no_output.xml", text, &s, &err, true) == WX_OK);
    ENSURE(s.output_index == -1 && s.input_count == 1 && s.texture_count == 1);
    ENSURE(texture_is(&s.textures[0], 0, "box.exr", 16, 16, 8, 0, 0, true, 0.0f,
                      WX_DEFAULT_NOISE, 0.0f, 3));
    wx_scene_free(&s);

    // Names the run does not write twice: a frame of another sequence is only a
    // clash when that frame is written (every 3 of 1 iteration writes none).
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Geometry><Mesh file=\"%s\">\n"
             "    <TextureMap file=\"mask.0003.exr\"/>\n"
             "    <TextureMap file=\"mask_out.exr\"/>\n"
             "    <TextureMap file=\"top_dirt.exr.exr\"/>\n"
             "  </Mesh></Geometry>\n" VIEW_COLLIDER "</Weathering>\n",
             abs_data_path("box.obj"));
    ENSURE(load_text("texture_near_names.xml", text, &s, &err, true) == WX_OK);
    ENSURE(s.texture_count == 3);
    wx_scene_free(&s);
    // With 3 iterations mask.exr every="3" writes mask.0003.exr.
    char *at = strstr(text, "<Geometry>");
    ENSURE(at != NULL);
    char more[65536];
    snprintf(more, sizeof more, "%.*s<Solver><Simulation iterations=\"3\"/></Solver>%s",
             (int)(at - text), text, at);
    ENSURE(load_text("texture_frame.xml", more, &s, &err, false) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_SCENE);
    ENSURE(ensure_contains(err.message, "texture_frame.xml:3: <TextureMap> file=\"mask.0003.exr\" "
                                        "is frame 3 of the image sequence of 'mask.exr'"));
    wx_scene_free(&s);
}

// --- derived masks (docs/design.md section 12) ---

static bool validates(const char *path);

/// `text`, written as `name`, validates against the schema.
static bool validates_text(const char *name, const char *text)
{
    return validates(ensure_write_file(ensure_tmpdir(), name, text));
}

static bool term_equals(const wx_term *got, const wx_term *want)
{
    return got->kind == want->kind && got->index == want->index &&
           got->constant == want->constant && got->weight == want->weight &&
           got->offset == want->offset && got->steepness == want->steepness &&
           got->line == want->line;
}

/// Every field of a mask, its terms included.
static bool mask_equals(const wx_mask_def *got, const wx_mask_def *want)
{
    bool ok = got->kind == want->kind && strcmp(got->name, want->name) == 0 &&
              got->rays == want->rays && got->distance == want->distance &&
              got->elevation == want->elevation && got->azimuth == want->azimuth &&
              got->side_weight == want->side_weight &&
              got->side_elevation == want->side_elevation &&
              got->side_spread == want->side_spread && got->radius == want->radius &&
              got->min == want->min && got->max == want->max && got->has_min == want->has_min &&
              got->has_max == want->has_max && got->scale == want->scale &&
              got->term_count == want->term_count && got->line == want->line;
    for (int i = 0; ok && i < WX_MAX_TERMS; ++i) {
        ok = term_equals(&got->terms[i], &want->terms[i]);
    }
    if (!ok) {
        fprintf(stderr,
                "mask '%s' at line %d: kind %d rays %d distance %g elevation %g azimuth %g side "
                "%g %g %g radius %g min %g (%d) max %g (%d) scale %g terms %d\n",
                got->name, got->line, (int)got->kind, got->rays, (double)got->distance,
                (double)got->elevation, (double)got->azimuth, (double)got->side_weight,
                (double)got->side_elevation, (double)got->side_spread, (double)got->radius,
                (double)got->min, got->has_min, (double)got->max, got->has_max,
                (double)got->scale, got->term_count);
        for (int i = 0; i < got->term_count && i < WX_MAX_TERMS; ++i) {
            const wx_term *t = &got->terms[i];
            fprintf(stderr,
                    "  term at line %d: kind %d index %d constant %g weight %g offset %g "
                    "steepness %g\n",
                    t->line, (int)t->kind, t->index, (double)t->constant, (double)t->weight,
                    (double)t->offset, (double)t->steepness);
        }
    }
    return ok;
}

// Every kind of mask with its defaults and with every attribute; <Masks>
// before the <Substances> its terms name. Line numbers matter.
static void masks_scene(char *text, size_t cap)
{
    snprintf(text, cap,
             "<Weathering>\n"                                                           // 1
             "  <Masks>\n"                                                              // 2
             "    <Accessibility name=\"ao\"/>\n"                                       // 3
             "    <Accessibility name=\"ao_far\" rays=\"4096\" distance=\"2.5\"/>\n"    // 4
             "    <Exposure name=\"sun\"/>\n"                                           // 5
             "    <Exposure name=\"low_sun\" elevation=\"-90\" azimuth=\"180\" "
             "sideWeight=\"0.5\"\n"                                                     // 6
             "              sideElevation=\"0.5\" sideSpread=\"60\"/>\n"                // 7
             "    <Curvature name=\"curvature\"/>\n"                                    // 8
             "    <Curvature name=\"Curv2\" radius=\"0.05\"/>\n"                        // 9
             "    <Height name=\"height\"/>\n"                                          // 10
             "    <Height name=\"above\" min=\"-1.5\"/>\n"                              // 11
             "    <Height name=\"below\" max=\"10\"/>\n"                                // 12
             "    <Height name=\"band\" min=\"0\" max=\"10\"/>\n"                       // 13
             "    <Combine name=\"moss\">\n"                                            // 14
             "      <Term mask=\"ao\" weight=\"1\" offset=\"0.5\" steepness=\"10\"/>\n" // 15
             "      <Term mask=\"sun\" weight=\"-1\"/>\n"                               // 16
             "      <Term substance=\"water\" weight=\"0.5\"/>\n"                       // 17
             "      <Term constant=\"0.2\"/>\n"                                         // 18
             "    </Combine>\n"                                                         // 19
             "    <Combine name=\"dry\" scale=\"-2\">\n"                                // 20
             "      <Term mask=\"moss\"/>\n"                                            // 21
             "      <Term substance=\"dirt\" offset=\"-3\" steepness=\"0\"/>\n"         // 22
             "      <Term constant=\"-1e3\" weight=\"0\"/>\n"                           // 23
             "    </Combine>\n"                                                         // 24
             "  </Masks>\n"                                                             // 25
             "  <Substances><Substance name=\"water\"/><Substance name=\"dirt\"/>"
             "</Substances>\n" VIEW_COLLIDER "</Weathering>\n");
}

TEST(masks_every_kind)
{
    char text[65536];
    masks_scene(text, sizeof text);
    wx_scene s;
    wx_error err;
    ENSURE(load_text("masks.xml", text, &s, &err, true) == WX_OK);
    enum { WATER, DIRT };
    ENSURE(s.substances_declared && s.substance_count == 2 && s.dirt_substance == DIRT);
    ENSURE(s.mask_count == 12);
    const wx_mask_def want[12] = {
        { .kind = WX_MASK_ACCESSIBILITY, .name = "ao", .rays = 64, .distance = 1.0f, .line = 3 },
        { .kind = WX_MASK_ACCESSIBILITY, .name = "ao_far", .rays = 4096, .distance = 2.5f,
          .line = 4 },
        { .kind = WX_MASK_EXPOSURE, .name = "sun", .elevation = 45.0f, .azimuth = 0.0f,
          .side_weight = 0.0f, .side_elevation = 1.0f, .side_spread = 0.0f, .line = 5 },
        { .kind = WX_MASK_EXPOSURE, .name = "low_sun", .elevation = -90.0f, .azimuth = 180.0f,
          .side_weight = 0.5f, .side_elevation = 0.5f, .side_spread = 60.0f, .line = 7 },
        { .kind = WX_MASK_CURVATURE, .name = "curvature", .radius = 0.0f, .line = 8 },
        { .kind = WX_MASK_CURVATURE, .name = "Curv2", .radius = 0.05f, .line = 9 },
        { .kind = WX_MASK_HEIGHT, .name = "height", .line = 10 },
        { .kind = WX_MASK_HEIGHT, .name = "above", .min = -1.5f, .has_min = true, .line = 11 },
        { .kind = WX_MASK_HEIGHT, .name = "below", .max = 10.0f, .has_max = true, .line = 12 },
        { .kind = WX_MASK_HEIGHT, .name = "band", .min = 0.0f, .max = 10.0f, .has_min = true,
          .has_max = true, .line = 13 },
        { .kind = WX_MASK_COMBINE, .name = "moss", .scale = 1.0f, .term_count = 4, .line = 14,
          .terms = {
              { .kind = WX_TERM_MASK, .index = 0, .weight = 1.0f, .offset = 0.5f,
                .steepness = 10.0f, .line = 15 },
              { .kind = WX_TERM_MASK, .index = 2, .weight = -1.0f, .line = 16 },
              { .kind = WX_TERM_SUBSTANCE, .index = WATER, .weight = 0.5f, .line = 17 },
              { .kind = WX_TERM_CONSTANT, .index = -1, .constant = 0.2f, .weight = 1.0f,
                .line = 18 },
          } },
        { .kind = WX_MASK_COMBINE, .name = "dry", .scale = -2.0f, .term_count = 3, .line = 20,
          .terms = {
              { .kind = WX_TERM_MASK, .index = 10, .weight = 1.0f, .line = 21 },
              { .kind = WX_TERM_SUBSTANCE, .index = DIRT, .weight = 1.0f, .offset = -3.0f,
                .line = 22 },
              { .kind = WX_TERM_CONSTANT, .index = -1, .constant = -1000.0f, .weight = 0.0f,
                .line = 23 },
          } },
    };
    for (int i = 0; i < 12; ++i) {
        ENSURE(mask_equals(&s.masks[i], &want[i]));
    }
    // Masks add no ageing: the substances do (design.md section 10 gives them channels).
    ENSURE(s.rule_count == 0);
    wx_scene_free(&s);
    ENSURE(s.mask_count == 0);
    ENSURE(have_xmllint_and_schema());
    {
        ENSURE(validates_text("masks_schema.xml", text));
    }
}

// Without <Substances> the one substance "dirt" is a term's substance too;
// no <Masks>, or an empty one, gives no mask.
TEST(masks_without_substances)
{
    char text[65536];
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Masks>\n"
             "    <Accessibility name=\"a2345678901234567890123456789012\"/>\n"
             "    <Combine name=\"grime\" scale=\"0.5\">\n"
             "      <Term substance=\"dirt\" weight=\"2\" steepness=\"4\"/>\n"
             "      <Term mask=\"a2345678901234567890123456789012\" weight=\"-1\"/>\n"
             "    </Combine>\n"
             "  </Masks>\n" VIEW_COLLIDER "</Weathering>\n");
    wx_scene s;
    wx_error err;
    ENSURE(load_text("masks_dirt.xml", text, &s, &err, true) == WX_OK);
    ENSURE(!s.substances_declared && s.substance_count == 1 && s.dirt_substance == 0);
    ENSURE(s.mask_count == 2);
    ENSURE(strlen(s.masks[0].name) == WX_SUBSTANCE_NAME_MAX);
    const wx_mask_def grime = {
        .kind = WX_MASK_COMBINE, .name = "grime", .scale = 0.5f, .term_count = 2, .line = 4,
        .terms = {
            { .kind = WX_TERM_SUBSTANCE, .index = 0, .weight = 2.0f, .steepness = 4.0f,
              .line = 5 },
            { .kind = WX_TERM_MASK, .index = 0, .weight = -1.0f, .line = 6 },
        },
    };
    ENSURE(mask_equals(&s.masks[1], &grime));
    ENSURE(!wx_scene_has_ageing(&s));
    wx_scene_free(&s);
    ENSURE(have_xmllint_and_schema());
    {
        ENSURE(validates_text("masks_dirt_schema.xml", text));
    }

    // An empty <Masks> is no mask (version 1's output); so is no <Masks>.
    snprintf(text, sizeof text, "<Weathering>\n  <Masks/>\n" VIEW_COLLIDER "</Weathering>\n");
    ENSURE(load_text("masks_empty.xml", text, &s, &err, true) == WX_OK);
    ENSURE(s.mask_count == 0);
    wx_scene_free(&s);
    ENSURE(wx_scene_load(data_path("full.xml"), &s, &err) == WX_OK);
    ENSURE(s.mask_count == 0);
    wx_scene_free(&s);

    // A term naming a substance the scene does not have, and a name too long.
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Masks><Combine name=\"c\">\n"
             "    <Term substance=\"water\"/>\n"
             "  </Combine></Masks>\n" VIEW_COLLIDER "</Weathering>\n");
    ENSURE(load_text("masks_water.xml", text, &s, &err, false) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_SCENE);
    ENSURE(ensure_contains(err.message, "masks_water.xml:3: <Term> substance=\"water\" names an "
                                        "undeclared substance (without <Substances> the scene "
                                        "has the one substance 'dirt')"));
    wx_scene_free(&s);
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Masks><Height name=\"a23456789012345678901234567890123\"/></Masks>\n"
             VIEW_COLLIDER "</Weathering>\n");
    ENSURE(load_text("masks_long.xml", text, &s, &err, false) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_VALUE);
    ENSURE(ensure_contains(err.message, "masks_long.xml:2: <Height> name is too long (at most 32 "
                                        "characters)"));
    wx_scene_free(&s);
}

// The limits: 8 substances and 24 masks, a Combine of 16 terms.
TEST(masks_limits_accepted)
{
    char text[65536];
    int n = snprintf(text, sizeof text, "<Weathering>\n  <Substances>");
    for (int k = 0; k < WX_MAX_SUBSTANCES; ++k) {
        n += snprintf(text + n, sizeof text - (size_t)n, "<Substance name=\"s%d\"/>", k);
    }
    n += snprintf(text + n, sizeof text - (size_t)n, "</Substances>\n  <Masks>\n");
    for (int m = 0; m < WX_MAX_MASKS - 1; ++m) {
        n += snprintf(text + n, sizeof text - (size_t)n, "    <Curvature name=\"m%d\"/>\n", m);
    }
    n += snprintf(text + n, sizeof text - (size_t)n, "    <Combine name=\"all\">\n");
    for (int t = 0; t < WX_MAX_TERMS; ++t) {
        n += snprintf(text + n, sizeof text - (size_t)n, "      <Term mask=\"m%d\"/>\n", t);
    }
    snprintf(text + n, sizeof text - (size_t)n, "    </Combine>\n  </Masks>\n" VIEW_COLLIDER
                                                "</Weathering>\n");
    wx_scene s;
    wx_error err;
    ENSURE(load_text("masks_limits.xml", text, &s, &err, true) == WX_OK);
    ENSURE(s.substance_count == WX_MAX_SUBSTANCES && s.mask_count == WX_MAX_MASKS);
    ENSURE(WX_MAX_SUBSTANCES + WX_MAX_MASKS <= WX_IMAGE_MAX_CHANNELS - 1);
    const wx_mask_def *all = &s.masks[WX_MAX_MASKS - 1];
    ENSURE(all->term_count == WX_MAX_TERMS);
    for (int t = 0; t < WX_MAX_TERMS; ++t) {
        ENSURE(all->terms[t].kind == WX_TERM_MASK && all->terms[t].index == t);
    }
    wx_scene_free(&s);
    ENSURE(have_xmllint_and_schema());
    {
        ENSURE(validates_text("masks_limits_schema.xml", text));
    }
}

// A mask is a channel of every output: its preview BASE_NAME.png must not be
// another output's (here the mask's mask_b_dirt.png, the TextureMap's mask_b_dirt.png).
TEST(masks_previews_are_outputs)
{
    char text[65536];
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Masks><Curvature name=\"b_dirt\"/></Masks>\n"
             "  <Geometry><Mesh file=\"%s\">\n"
             "    <TextureMap file=\"mask_b.exr\"/>\n"
             "  </Mesh></Geometry>\n" VIEW_COLLIDER "</Weathering>\n",
             abs_data_path("box.obj"));
    wx_scene s;
    wx_error err;
    ENSURE(load_text("masks_preview.xml", text, &s, &err, false) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, BAD_SCENE);
    ENSURE(ensure_contains(err.message, "masks_preview.xml:4: <TextureMap> file=\"mask_b.exr\" "
                                        "writes the preview 'mask_b_dirt.png'"));
    wx_scene_free(&s);
    // Without the mask the scene has the one channel Y: mask.png and mask_b.png.
    snprintf(text, sizeof text,
             "<Weathering>\n"
             "  <Geometry><Mesh file=\"%s\">\n"
             "    <TextureMap file=\"mask_b.exr\"/>\n"
             "  </Mesh></Geometry>\n" VIEW_COLLIDER "</Weathering>\n",
             abs_data_path("box.obj"));
    ENSURE(load_text("masks_no_preview.xml", text, &s, &err, true) == WX_OK);
    wx_scene_free(&s);
}

static double seconds_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

// "Billion laughs": refused at the first entity declaration, in well under 1 s.
TEST(entity_bomb_refused_quickly)
{
    char text[4096] = "<?xml version=\"1.0\"?>\n<!DOCTYPE Weathering [\n"
                      "  <!ENTITY lol \"lol\">\n";
    for (int i = 1; i <= 9; ++i) {
        char decl[256];
        snprintf(decl, sizeof decl, "  <!ENTITY lol%d \"", i);
        strcat(text, decl);
        for (int k = 0; k < 10; ++k) {
            if (i == 1) {
                snprintf(decl, sizeof decl, "&lol;");
            } else {
                snprintf(decl, sizeof decl, "&lol%d;", i - 1);
            }
            strcat(text, decl);
        }
        strcat(text, "\">\n");
    }
    strcat(text, "]>\n<Weathering><Solver>&lol9;</Solver>\n"
                 "<Emitters><PointEmitter name=\"&lol9;\"/></Emitters></Weathering>\n");
    const char *path = ensure_write_file(ensure_tmpdir(), "bomb.xml", text);
    wx_scene s;
    wx_error err;
    double t0 = seconds_now();
    wx_result r = wx_scene_load(path, &s, &err);
    double elapsed = seconds_now() - t0;
    ENSURE(r == WX_BAD_INPUT);
    ENSURE_CAUSE(err, XML_CONTENT);
    ENSURE(elapsed < 1.0);
    char expected[4200];
    snprintf(expected, sizeof expected, "%s:3: entity declarations are not allowed", path);
    ENSURE(strncmp(err.message, expected, strlen(expected)) == 0);
    ENSURE(!ensure_contains(err.message, "lollol"));
    wx_scene_free(&s);
}

// An external entity is refused and the file it names is never read.
TEST(external_entity_refused)
{
    const char *dir = ensure_tmpdir();
    const char *secret = ensure_write_file(dir, "secret.txt", "TOPSECRET-7f3a");
    char abs_secret[8192];
    if (secret[0] == '/') {
        snprintf(abs_secret, sizeof abs_secret, "%s", secret);
    } else {
        char cwd[4096];
        ENSURE(getcwd(cwd, sizeof cwd) != NULL);
        snprintf(abs_secret, sizeof abs_secret, "%s/%s", cwd, secret);
    }
    const char *forms[3] = {
        "<Weathering><Solver>&xxe;</Solver></Weathering>\n",
        "<Weathering><Emitters><PointEmitter name=\"&xxe;\"/></Emitters></Weathering>\n",
        "<Weathering>%xxe;</Weathering>\n",
    };
    for (int i = 0; i < 3; ++i) {
        char text[16384];
        snprintf(text, sizeof text,
                 "<?xml version=\"1.0\"?>\n<!DOCTYPE Weathering [\n"
                 "  <!ENTITY %sxxe SYSTEM \"file://%s\">\n]>\n%s",
                 i == 2 ? "% " : "", abs_secret, forms[i]);
        const char *path = ensure_write_file(dir, "xxe.xml", text);
        wx_scene s;
        wx_error err;
        memset(&err, 0, sizeof err);
        ENSURE(wx_scene_load(path, &s, &err) == WX_BAD_INPUT);
        ENSURE_CAUSE(err, XML_CONTENT);
        ENSURE(ensure_contains(err.message, "entity declarations are not allowed"));
        ENSURE(!ensure_contains(err.message, "TOPSECRET"));
        wx_scene_free(&s);
    }
    // /etc/passwd, as in the classic attack.
    const char *path = ensure_write_file(
        dir, "passwd.xml",
        "<!DOCTYPE Weathering [ <!ENTITY xxe SYSTEM \"file:///etc/passwd\"> ]>\n"
        "<Weathering><Solver>&xxe;</Solver></Weathering>\n");
    wx_scene s;
    wx_error err;
    ENSURE(wx_scene_load(path, &s, &err) == WX_BAD_INPUT);
    ENSURE(!ensure_contains(err.message, "root:"));
}

TEST(missing_scene_file)
{
    wx_scene s;
    wx_error err;
    ENSURE(wx_scene_load("tests/data/no_such_scene.xml", &s, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, FILE_MISSING);
    ENSURE(strcmp(err.message,
                  "tests/data/no_such_scene.xml: cannot open (No such file or directory)") == 0);
    ENSURE(s.cameras == NULL);
    wx_scene_free(&s);
    ENSURE(wx_scene_load(ensure_tmpdir(), &s, &err) == WX_BAD_INPUT); // a folder
    ENSURE_CAUSE(err, NOT_REGULAR_FILE);
    ENSURE(ensure_contains(err.message, "is not a regular file (a folder)"));
    // A FIFO with no writer is refused at once, never waited on (issue 13).
    char fifo[4200];
    snprintf(fifo, sizeof fifo, "%s/scene_fifo.xml", ensure_tmpdir());
    ENSURE(mkfifo(fifo, 0600) == 0);
    ENSURE(wx_scene_load(fifo, &s, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, NOT_REGULAR_FILE);
    ENSURE(ensure_contains(err.message, "scene_fifo.xml: is not a regular file (a FIFO)"));
}

// Absolute map paths stay as they are; relative ones resolve against the scene.
TEST(absolute_and_relative_paths)
{
    const char *dir = ensure_tmpdir();
    char cwd[4096];
    ENSURE(getcwd(cwd, sizeof cwd) != NULL);
    char abs_map[8400];
    snprintf(abs_map, sizeof abs_map, "%s/%s", cwd, data_path("map4.exr"));
    ENSURE(write_map(ensure_write_file(dir, "rel.exr", ""), 4, 4));
    char text[20000];
    snprintf(text, sizeof text,
             "<Weathering><Collider><ProjectedMaps><Ortho cameraName=\"c\">\n"
             "<WTCMatrix matrix=\"1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\"/>\n"
             "<DepthMap file=\"%s\"/><NormalMap file=\"rel.exr\"/>\n"
             "<ImpactMap file=\"./rel.exr\"/><DirtMap file=\"%s\"/>\n"
             "</Ortho></ProjectedMaps></Collider></Weathering>\n",
             abs_map, abs_map);
    const char *path = ensure_write_file(dir, "paths.scene.xml", text);
    wx_scene s;
    wx_error err;
    wx_result r = wx_scene_load(path, &s, &err);
    if (r != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
    }
    ENSURE(r == WX_OK);
    ENSURE(strcmp(s.name, "paths.scene") == 0);
    ENSURE(strcmp(s.cameras[0].depth_path, abs_map) == 0);
    char expected[8400];
    snprintf(expected, sizeof expected, "%s/rel.exr", dir);
    ENSURE(strcmp(s.cameras[0].normal_path, expected) == 0);
    snprintf(expected, sizeof expected, "%s/./rel.exr", dir);
    ENSURE(strcmp(s.cameras[0].impact_path, expected) == 0);
    wx_scene_free(&s);
}

// Every shipped scene loads.
TEST(shipped_scenes_load)
{
    DIR *dir = opendir("xml_scenes");
    ENSURE(dir != NULL);
    int failures = 0, count = 0;
    struct dirent *entry;
    while ((entry = readdir(dir)) != NULL) {
        size_t len = strlen(entry->d_name);
        if (len <= 4 || strcmp(entry->d_name + len - 4, ".xml") != 0) {
            continue;
        }
        char path[4200];
        snprintf(path, sizeof path, "xml_scenes/%s", entry->d_name);
        wx_scene s;
        wx_error err;
        if (wx_scene_load(path, &s, &err) != WX_OK) {
            fprintf(stderr, "%s\n", err.message);
            failures++;
        }
        wx_scene_free(&s);
        count++;
    }
    closedir(dir);
    ENSURE(count > 0); // the shipped scenes are part of the project
    ENSURE(failures == 0);
}

// xmllint (Debian's libxml2-utils, which `make deps` installs) and the schema
// it validates against: both must be there, or the schema tests fail.
static bool have_xmllint_and_schema(void)
{
    char out[256];
    if (ensure_shell(out, sizeof out, "command -v xmllint") != 0) {
        fprintf(stderr, "        xmllint is not installed (make deps installs libxml2-utils)\n");
        return false;
    }
    if (access("xml_scenes/weathering.xsd", R_OK) != 0) {
        fprintf(stderr, "        xml_scenes/weathering.xsd cannot be read\n");
        return false;
    }
    return true;
}

static bool validates(const char *path)
{
    char out[8192];
    int status = ensure_shell(out, sizeof out,
                              "xmllint --noout --schema xml_scenes/weathering.xsd '%s'", path);
    if (status != 0) {
        fprintf(stderr, "%s does not validate:\n%s", path, out);
    }
    return status == 0;
}

// Every shipped scene (xml_scenes/*.xml) and the good scenes of this test
// validate against the schema.
TEST(schema_accepts_good_scenes)
{
    ENSURE(have_xmllint_and_schema());
    char out[4096];
    ENSURE(ensure_shell(out, sizeof out, "xmllint --noout xml_scenes/weathering.xsd") == 0);
    int failures = 0, shipped = 0;
    DIR *dir = opendir("xml_scenes");
    ENSURE(dir != NULL);
    struct dirent *entry;
    while ((entry = readdir(dir)) != NULL) {
        size_t len = strlen(entry->d_name);
        if (len > 4 && strcmp(entry->d_name + len - 4, ".xml") == 0) {
            char path[4200];
            snprintf(path, sizeof path, "xml_scenes/%s", entry->d_name);
            failures += !validates(path);
            shipped++;
        }
    }
    closedir(dir);
    ENSURE(shipped >= 6); // the shipped scenes are part of the project
    static const char *const good[] = { "thesis_minimal.xml", "defaults.xml", "full.xml" };
    for (size_t i = 0; i < sizeof good / sizeof good[0]; ++i) {
        failures += !validates(data_path(good[i]));
    }
    // <TextureMap>s with every attribute (docs/design.md section 11).
    char text[65536];
    texture_scene(text, sizeof text);
    failures += !validates(ensure_write_file(ensure_tmpdir(), "texture_schema.xml", text));
    ENSURE(failures == 0);
}

// The schema also describes the ranges: some bad scenes fail validation too.
TEST(schema_rejects_bad_values)
{
    ENSURE(have_xmllint_and_schema());
    static const char *const invalid[] = {
        "unknown_element",    "unknown_attribute",      "not_a_number",
        "nan",                "inf",                    "negative_size",
        "matrix_15_numbers",  "camera_name_folder",     "probability_above_one",
        "duplicate_solver",   "text_content",           "missing_collider",
        "bad_boolean",        "octaves_out_of_range",   "steps_not_integer",
        "duplicate_camera",   "output_file_folder",     "resolution_too_large",
        "duplicate_material", "duplicate_emitter_name", "mass_zero",
        "wrong_root",         "missing_required_attribute",
        "collider_friction_above_one", "box_emitter_spread_90",
        "box_emitter_without_a_corner", "box_emitter_has_no_center",
        // docs/design.md sections 9 and 10 (issue 16).
        "substances_nine", "substances_empty", "substances_twice", "substance_duplicate_name",
        "substance_reserved_y", "substance_reserved_seen", "substance_name_starts_with_digit",
        "substance_name_with_a_dot", "substance_name_too_long", "load_amount_negative",
        "load_twice", "exchange_twice", "exchange_deposit_above_one", "exchange_initial_negative",
        "transfer_rate_above_one", "decay_rate_negative", "grow_amount_negative",
        "rule_without_rate", "iterations_zero", "iterations_too_many", "iterations_not_integer",
        "every_negative", "child_of_a_leaf_element",
        // docs/design.md section 11.
        "texture_map_not_exr", "texture_map_uv_too_large", "texture_map_padding_negative",
        "texture_map_zero_resolution", "texture_map_width_too_large", "texture_map_without_file",
        "texture_map_same_file_twice", "texture_map_outside_mesh", "texture_map_tiles_unknown",
        // docs/design.md section 12 (issue 18).
        "term_unknown_mask", "accessibility_rays_zero", "accessibility_rays_too_many",
        "accessibility_distance_zero", "exposure_elevation_above_90",
        "exposure_side_weight_negative", "curvature_radius_negative", "term_steepness_negative",
        "mask_name_clashes_with_substance", "mask_name_clashes_with_mask",
        "mask_name_reserved_seen", "mask_name_reserved_y", "mask_name_with_a_dot",
        "mask_without_name", "combine_without_terms", "combine_too_many_terms", "masks_too_many",
        "masks_twice", "mask_unknown_element",
        // docs/design.md section 15 (issue 28).
        "seed_density_negative", "seed_without_density", "spread_radius_zero",
        "spread_without_radius", "spread_probability_above_one", "spread_min_negative",
        "crack_radius_negative", "crack_strength_above_one", "crack_without_radius",
        "peel_without_from", "peel_probability_negative",
    };
    int failures = 0;
    for (size_t i = 0; i < sizeof invalid / sizeof invalid[0]; ++i) {
        char out[8192];
        int status =
            ensure_shell(out, sizeof out, "xmllint --noout --schema %s %s/bad/%s.xml",
                         "xml_scenes/weathering.xsd", ensure_tests_dir(), invalid[i]);
        // Rejected means xmllint read the schema and the file and found the
        // file invalid (exit status 3, "fails to validate"), not that it
        // could not read one of them.
        if (status != 3 || strstr(out, "fails to validate") == NULL) {
            fprintf(stderr, "tests/bad/%s.xml: %s\n", invalid[i],
                    status == 0 ? "validates against the schema" : out);
            failures++;
        }
    }
    ENSURE(failures == 0);
}

// The fuzzer's dictionary (tests/fuzz/fuzz_scene.dict) holds every element
// and attribute the schema has, so that a new one cannot be left out of the
// fuzzing: "<Name" and " name=\"" for each.
TEST(fuzz_dictionary_knows_every_element_and_attribute)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/../xml_scenes/weathering.xsd", ensure_tests_dir());
    char *xsd = ensure_read_file(path);
    snprintf(path, sizeof path, "%s/fuzz/fuzz_scene.dict", ensure_tests_dir());
    char *dict = ensure_read_file(path);
    ENSURE(xsd != NULL && dict != NULL);
    static const char *const kinds[2] = { "<xs:element name=\"", "<xs:attribute name=\"" };
    int checked = 0, missing = 0;
    for (int k = 0; k < 2; ++k) {
        for (const char *c = strstr(xsd, kinds[k]); c != NULL; c = strstr(c + 1, kinds[k])) {
            const char *name = c + strlen(kinds[k]);
            int len = (int)strcspn(name, "\"");
            char word[160];
            snprintf(word, sizeof word, k == 0 ? "\"<%.*s\"" : "\" %.*s=\\\"\"", len, name);
            if (strstr(dict, word) == NULL) {
                fprintf(stderr, "        fuzz_scene.dict lacks %s\n", word);
                missing++;
            }
            checked++;
        }
    }
    free(xsd);
    free(dict);
    ENSURE(checked > 100);
    ENSURE(missing == 0);
}

int main(void)
{
    RUN(data_maps);
    RUN(fuzz_dictionary_knows_every_element_and_attribute);
    RUN(thesis_minimal_defaults);
    RUN(element_defaults);
    RUN(full_scene);
    RUN(view_camera_matrices);
    RUN(ctw_derived_when_absent);
    RUN(ctw_not_inverse_is_an_error);
    RUN(version1_scene_has_substance_dirt);
    RUN(substances_loads_exchanges_rules);
    RUN(substance_dirt_index_or_none);
    RUN(substance_limits_accepted);
    RUN(substance_errors_at_their_line);
    RUN(texture_maps);
    RUN(masks_every_kind);
    RUN(masks_without_substances);
    RUN(masks_limits_accepted);
    RUN(masks_previews_are_outputs);
    RUN(bad_scenes);
    RUN(entity_bomb_refused_quickly);
    RUN(external_entity_refused);
    RUN(missing_scene_file);
    RUN(absolute_and_relative_paths);
    RUN(shipped_scenes_load);
    RUN(schema_accepts_good_scenes);
    RUN(schema_rejects_bad_values);
    return ensure_summary();
}
