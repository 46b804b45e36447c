// scene_xml_cameras.c: <Collider>, <ProjectedMaps> and their <Ortho> cameras
// (docs/design.md sections 3 and 10): matrices, views, the maps a camera names
// (their files and sizes, read from the EXR headers), the output camera's
// <OutputMap> and the layers.
#include "io/scene_xml_internal.h"

#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/input_file.h"
#include "core/matrix.h"
#include "io/exr.h"
#include "model/image.h"
#include "model/naming.h"

/// The elements of a camera's maps, in model/naming.h's order of the kinds.
static const char *const map_elements[WX_MAP_KINDS] = { "DepthMap", "NormalMap", "ImpactMap",
                                                        "DirtMap" };

// ---------------------------------------------------------------------------
// <Collider>, <ProjectedMaps>, <Ortho>

static const attr_spec collider_attrs[] = {
    { "resilience", T_FLOAT, offsetof(wx_collider_def, resilience), .range = R_UNIT },
    { "friction", T_FLOAT, offsetof(wx_collider_def, friction), .range = R_UNIT },
    { "adherence", T_FLOAT, offsetof(wx_collider_def, adherence), .range = R_NONNEG },
    { "deposit", T_FLOAT, offsetof(wx_collider_def, deposit), .range = R_NONNEG },
    { "erosion", T_FLOAT, offsetof(wx_collider_def, erosion), .range = R_NONNEG },
};

typedef struct ortho_attrs_def {
    char name[64];
    bool out;
    int layers;
} ortho_attrs_def;

static const attr_spec ortho_attrs[] = {
    { "cameraName", T_NAME, offsetof(ortho_attrs_def, name),
      .size = sizeof(((ortho_attrs_def *)0)->name), .required = true },
    { "out", T_BOOL, offsetof(ortho_attrs_def, out), .range = R_FINITE },
    // docs/design.md section 14: the crossings each texel records.
    { "layers", T_INT, offsetof(ortho_attrs_def, layers), .lo = 1, .hi = WX_MAX_LAYERS },
};

typedef struct matrix_def {
    float m[16];
} matrix_def;

static const attr_spec matrix_attrs[] = {
    { "matrix", T_MATRIX, offsetof(matrix_def, m), .required = true },
};

static const attr_spec map_attrs[] = {
    { "file", T_STRING, offsetof(map_def, file), .size = WX_PATH_MAX, .required = true },
};

typedef struct output_def {
    char file[256];
    int width, height;
    float radius;
    int second_pass;
    bool normalize;
    float noise, max_radius;
    int every;
} output_def;

static const char *const second_pass_names[] = { "mean", "sum", NULL };

enum { OUT_FILE, OUT_WIDTH, OUT_HEIGHT, OUT_RADIUS, OUT_SECOND_PASS, OUT_NORMALIZE, OUT_NOISE,
       OUT_MAX_RADIUS, OUT_EVERY }; // bits of `present`

static const attr_spec output_attrs[] = {
    [OUT_FILE] = { "file", T_NAME, offsetof(output_def, file),
                   .size = sizeof(((output_def *)0)->file) },
    [OUT_WIDTH] = { "width", T_INT, offsetof(output_def, width), .lo = 1, .hi = WX_MAP_MAX_SIDE },
    [OUT_HEIGHT] = { "height", T_INT, offsetof(output_def, height), .lo = 1,
                     .hi = WX_MAP_MAX_SIDE },
    [OUT_RADIUS] = { "radius", T_FLOAT, offsetof(output_def, radius), .range = R_NONNEG },
    [OUT_SECOND_PASS] = { "secondPass", T_ENUM, offsetof(output_def, second_pass),
                          .choices = second_pass_names },
    [OUT_NORMALIZE] = { "normalize", T_BOOL, offsetof(output_def, normalize) },
    [OUT_NOISE] = { "noise", T_FLOAT, offsetof(output_def, noise), .range = R_POSITIVE },
    [OUT_MAX_RADIUS] = { "maxRadius", T_FLOAT, offsetof(output_def, max_radius),
                         .range = R_POSITIVE },
    // docs/design.md section 10: BASE.NNNN.exr after every k-th iteration (0: none).
    [OUT_EVERY] = { "every", T_INT, offsetof(output_def, every), .lo = 0,
                    .hi = SCENE_MAX_ITERATIONS },
};

typedef struct view_def {
    float eye[3], target[3], up[3];
    float width, height;
    int resolution[2];
} view_def;

static const attr_spec view_attrs[] = {
    { "eye", T_VEC3, offsetof(view_def, eye), .required = true },
    { "target", T_VEC3, offsetof(view_def, target), .required = true },
    { "up", T_VEC3, offsetof(view_def, up), .range = R_FINITE },
    { "width", T_FLOAT, offsetof(view_def, width), .range = R_POSITIVE, .required = true },
    { "height", T_FLOAT, offsetof(view_def, height), .range = R_POSITIVE, .required = true },
    { "resolution", T_RESOLUTION, offsetof(view_def, resolution), .lo = 1,
      .hi = WX_MAP_MAX_SIDE, .required = true },
};

/// What one <Ortho> says, before it is checked as a whole.
typedef struct ortho_def {
    wx_scene_camera *cam;
    const xmlNode *ctw_node, *wtc_node, *view_node, *output_node;
    float ctw[16], wtc[16];
    const xmlNode *map_nodes[WX_MAP_KINDS];
    char *map_files[WX_MAP_KINDS]; ///< as written in the scene (owned)
    unsigned output_present;
} ortho_def;

static wx_result parse_matrix(parser *p, const xmlNode *node, void *user)
{
    ortho_def *o = user;
    bool is_ctw = strcmp(name_of(node), "CTWMatrix") == 0;
    matrix_def m;
    wx_result r = LEAF(matrix_attrs, &m, NULL);
    if (r != WX_OK) {
        return r;
    }
    memcpy(is_ctw ? o->ctw : o->wtc, m.m, sizeof m.m);
    *(is_ctw ? &o->ctw_node : &o->wtc_node) = node;
    return WX_OK;
}

static wx_result parse_map(parser *p, const xmlNode *node, void *user)
{
    ortho_def *o = user;
    int k = 0;
    while (k < WX_MAP_KINDS && strcmp(map_elements[k], name_of(node)) != 0) {
        ++k;
    }
    map_def m = { NULL };
    wx_result r = LEAF(map_attrs, &m, NULL);
    if (r == WX_OK) {
        free(o->map_files[k]);
        o->map_files[k] = m.file;
        o->map_nodes[k] = node;
    } else {
        free(m.file);
    }
    return r;
}

static wx_result parse_output_map(parser *p, const xmlNode *node, void *user)
{
    ortho_def *o = user;
    wx_scene_camera *cam = o->cam;
    output_def out = { .second_pass = WX_SECOND_PASS_MEAN, .noise = WX_DEFAULT_NOISE };
    snprintf(out.file, sizeof out.file, "mask.exr");
    wx_result r = LEAF(output_attrs, &out, &o->output_present);
    if (r != WX_OK) {
        return r;
    }
    size_t len = strlen(out.file);
    if (len < 5 || strcasecmp(out.file + len - 4, ".exr") != 0) {
        return fail(p, node, WX_CAUSE_BAD_VALUE, "<OutputMap> file=\"%s\" must end in .exr",
                    out.file);
    }
    memcpy(cam->output_file, out.file, sizeof out.file);
    cam->output_width = out.width;
    cam->output_height = out.height;
    cam->radius = out.radius;
    cam->noise = out.noise;
    cam->max_radius = out.max_radius;
    cam->second_pass = out.second_pass == 1 ? WX_SECOND_PASS_SUM : WX_SECOND_PASS_MEAN;
    cam->normalize = out.normalize;
    cam->every = out.every;
    o->output_node = node;
    if (cam->is_output) {
        p->output_map_line = line_of(node);
    }
    return WX_OK;
}

static wx_result parse_view(parser *p, const xmlNode *node, void *user)
{
    ortho_def *o = user;
    view_def v = { .up = { 0.0f, 1.0f, 0.0f } };
    wx_result r = LEAF(view_attrs, &v, NULL);
    if (r != WX_OK) {
        return r;
    }
    wx_view *view = &o->cam->view;
    memcpy(view->eye, v.eye, sizeof v.eye);
    memcpy(view->target, v.target, sizeof v.target);
    memcpy(view->up, v.up, sizeof v.up);
    view->width_ws = v.width;
    view->height_ws = v.height;
    view->width_px = v.resolution[0];
    view->height_px = v.resolution[1];
    o->cam->has_view = true;
    o->view_node = node;
    return WX_OK;
}

static const child_spec ortho_children[] = {
    { "CTWMatrix", parse_matrix, false }, { "WTCMatrix", parse_matrix, false },
    { "DepthMap", parse_map, false },     { "NormalMap", parse_map, false },
    { "ImpactMap", parse_map, false },    { "DirtMap", parse_map, false },
    { "OutputMap", parse_output_map, false }, { "View", parse_view, false },
};

/// Every later phase can use the camera's matrices (the collider's and the
/// gather's tests, made here so that a bad camera is refused at its line).
static wx_result check_camera(parser *p, const xmlNode *node, const wx_scene_camera *cam)
{
    const char *problem = wx_camera_problem(&cam->camera);
    if (problem != NULL) {
        return fail(p, node, WX_CAUSE_BAD_CAMERA, "camera '%s': %s", cam->name, problem);
    }
    return WX_OK;
}

/// The matrices of a camera: from its <View>, or both given (and checked), or
/// one given and the other its inverse.
static wx_result camera_matrices(parser *p, const xmlNode *node, ortho_def *o)
{
    wx_scene_camera *cam = o->cam;
    if (o->view_node != NULL) {
        if (o->ctw_node != NULL || o->wtc_node != NULL) {
            return fail(p, o->view_node, WX_CAUSE_BAD_SCENE,
                        "camera '%s' has both a <View> and a %s (ambiguous): give one or the other",
                        cam->name, o->wtc_node != NULL ? "<WTCMatrix>" : "<CTWMatrix>");
        }
        wx_error view_err;
        if (wx_camera_from_view(&cam->view, &cam->camera, &view_err) != WX_OK) {
            return fail(p, o->view_node, WX_CAUSE_BAD_CAMERA, "camera '%s': %s", cam->name,
                        view_err.message);
        }
        return check_camera(p, o->view_node, cam);
    }
    if (o->wtc_node == NULL && o->ctw_node == NULL) {
        return fail(p, node, WX_CAUSE_MISSING,
                    "camera '%s' needs a <WTCMatrix> (and/or <CTWMatrix>) or a <View>", cam->name);
    }
    if (o->wtc_node != NULL && o->ctw_node != NULL) {
        float error = wx_matrix_inverse_error(o->wtc, o->ctw);
        if (!(error <= SCENE_INVERSE_TOLERANCE)) {
            return fail(p, o->ctw_node, WX_CAUSE_BAD_CAMERA,
                        "<CTWMatrix> of camera '%s' is not the inverse of its <WTCMatrix> "
                        "(error %.3g, tolerance %g)",
                        cam->name, (double)error, (double)SCENE_INVERSE_TOLERANCE);
        }
        memcpy(cam->camera.wtc, o->wtc, sizeof o->wtc);
        memcpy(cam->camera.ctw, o->ctw, sizeof o->ctw);
    } else if (o->wtc_node != NULL) {
        memcpy(cam->camera.wtc, o->wtc, sizeof o->wtc);
        if (!wx_matrix_invert(o->wtc, cam->camera.ctw)) {
            return fail(p, o->wtc_node, WX_CAUSE_BAD_CAMERA,
                        "<WTCMatrix> of camera '%s' is singular", cam->name);
        }
    } else {
        memcpy(cam->camera.ctw, o->ctw, sizeof o->ctw);
        if (!wx_matrix_invert(o->ctw, cam->camera.wtc)) {
            return fail(p, o->ctw_node, WX_CAUSE_BAD_CAMERA,
                        "<CTWMatrix> of camera '%s' is singular", cam->name);
        }
    }
    return check_camera(p, o->wtc_node != NULL ? o->wtc_node : o->ctw_node, cam);
}

/// Which maps a camera must name, the ones it names, and their sizes.
static wx_result camera_maps(parser *p, const xmlNode *node, ortho_def *o)
{
    wx_scene_camera *cam = o->cam;
    char **paths[WX_MAP_KINDS] = { &cam->depth_path, &cam->normal_path, &cam->impact_path,
                                   &cam->dirt_path };
    int needed = cam->is_output ? 2 : 4; // depth, normal (+ impact, dirt for inputs)
    int named = 0;
    for (int k = 0; k < needed; ++k) {
        named += o->map_nodes[k] != NULL;
    }
    if (named < needed && (o->view_node == NULL || named > 0)) {
        int k = 0;
        while (o->map_nodes[k] != NULL) {
            ++k;
        }
        if (o->view_node == NULL) {
            return fail(p, node, WX_CAUSE_MISSING,
                        "camera '%s' needs a <%s> (or a <View> so that bake makes it)", cam->name,
                        map_elements[k]);
        }
        return fail(p, node, WX_CAUSE_MISSING,
                    "camera '%s' names some of its maps but not <%s>: with a <View>, name all "
                    "of them or none (bake writes them)",
                    cam->name, map_elements[k]);
    }
    const char *first_file = NULL;
    for (int k = 0; k < WX_MAP_KINDS; ++k) {
        const xmlNode *map = o->map_nodes[k];
        if (map == NULL) {
            continue;
        }
        const char *file = o->map_files[k];
        wx_result r = xml_resolve_path(p, map, file, paths[k]);
        const char *path = *paths[k];
        if (r != WX_OK) {
            return r;
        }
        char why[WX_INPUT_WHY_MAX];
        wx_cause cause = WX_CAUSE_NONE;
        if (!wx_is_regular_file(path, why, &cause)) {
            return fail(p, map, cause, "map file '%s' %s", file,
                        cause == WX_CAUSE_FILE_MISSING ? "not found" : why);
        }
        wx_image header;
        wx_error exr_err;
        memset(&header, 0, sizeof header);
        r = wx_exr_read_header(path, &header, &exr_err);
        int w = header.width, h = header.height;
        wx_image_free(&header);
        if (r != WX_OK) {
            return fail(p, map, exr_err.cause, "%s map of camera '%s': %s", wx_map_kind_name(k),
                        cam->name, exr_err.message);
        }
        if (o->view_node != NULL) {
            if (w != cam->view.width_px || h != cam->view.height_px) {
                return fail(p, map, WX_CAUSE_MAP_SIZE,
                            "map file '%s' is %dx%d but the <View> resolution of camera '%s' is "
                            "%dx%d",
                            file, w, h, cam->name, cam->view.width_px, cam->view.height_px);
            }
        } else if (first_file == NULL) {
            cam->camera.width = w;
            cam->camera.height = h;
            first_file = file;
        } else if (w != cam->camera.width || h != cam->camera.height) {
            return fail(p, map, WX_CAUSE_MAP_SIZE,
                        "map file '%s' is %dx%d but '%s' is %dx%d: the maps of camera '%s' "
                        "must agree in size",
                        file, w, h, first_file, cam->camera.width, cam->camera.height, cam->name);
        }
    }
    return WX_OK;
}

/// The <OutputMap> of the output camera, with its defaults.
static wx_result camera_output(parser *p, const xmlNode *node, ortho_def *o)
{
    wx_scene_camera *cam = o->cam;
    if (!cam->is_output) {
        if (o->output_node != NULL) {
            return fail(p, o->output_node, WX_CAUSE_BAD_SCENE,
                        "<OutputMap> in camera '%s', which is not the output camera (out=\"true\")",
                        cam->name);
        }
        return WX_OK;
    }
    if (o->output_node == NULL) {
        if (o->view_node == NULL) {
            return fail(p, node, WX_CAUSE_MISSING, "output camera '%s' needs an <OutputMap>",
                        cam->name);
        }
        snprintf(cam->output_file, sizeof cam->output_file, "mask.exr");
        cam->second_pass = WX_SECOND_PASS_MEAN;
        cam->noise = WX_DEFAULT_NOISE;
    }
    unsigned given = o->output_present;
    int w = cam->camera.width, h = cam->camera.height;
    if (!(given & (1u << OUT_WIDTH))) {
        cam->output_width = w;
    }
    if (!(given & (1u << OUT_HEIGHT))) {
        cam->output_height = h;
    }
    if (cam->output_width != w || cam->output_height != h) {
        return fail(p, o->output_node, WX_CAUSE_MAP_SIZE,
                    "<OutputMap> size %dx%d differs from the %dx%d maps of output camera '%s'",
                    cam->output_width, cam->output_height, w, h, cam->name);
    }
    // No radius: the adaptive smoothing, which noise and maxRadius tune.
    cam->adaptive = !(given & (1u << OUT_RADIUS));
    if (!cam->adaptive && (given & ((1u << OUT_NOISE) | (1u << OUT_MAX_RADIUS)))) {
        return fail(p, o->output_node, WX_CAUSE_BAD_SCENE,
                    "<OutputMap> gives a radius and %s: %s tunes the adaptive smoothing, which a "
                    "radius replaces; give one or the other",
                    given & (1u << OUT_NOISE) ? "noise" : "maxRadius",
                    given & (1u << OUT_NOISE) ? "noise" : "maxRadius");
    }
    if (cam->adaptive && cam->second_pass == WX_SECOND_PASS_SUM) {
        return fail(p, o->output_node, WX_CAUSE_BAD_SCENE,
                    "<OutputMap> secondPass=\"sum\" needs a radius (the thesis' unnormalised "
                    "sum is defined over a fixed radius)");
    }
    if (cam->adaptive && !(given & (1u << OUT_MAX_RADIUS))) {
        float frame_w, frame_h;
        wx_camera_frame_size(&cam->camera, &frame_w, &frame_h);
        cam->max_radius = WX_DEFAULT_MAX_RADIUS_TEXELS * frame_w / (float)cam->output_width;
    }
    return WX_OK;
}

/// `layers` (docs/design.md section 14) is for input cameras that bake peels:
/// the maps a scene names hold one layer, and the mask shows the first surface
/// the output camera sees.
static wx_result camera_layers(parser *p, const xmlNode *node, ortho_def *o)
{
    const wx_scene_camera *cam = o->cam;
    if (cam->layers <= 1) {
        return WX_OK;
    }
    if (cam->is_output) {
        return fail(p, node, WX_CAUSE_BAD_SCENE,
                    "output camera '%s' has layers=\"%d\": layers are for input cameras (the "
                    "mask shows the first surface the output camera sees); remove it",
                    cam->name, cam->layers);
    }
    for (int k = 0; k < WX_MAP_KINDS; ++k) {
        if (o->map_nodes[k] != NULL) {
            return fail(p, node, WX_CAUSE_BAD_SCENE,
                        "camera '%s' has layers=\"%d\" and names its map files: maps given as "
                        "files hold one layer; give it a <View> without map files so that "
                        "bake peels %d layers",
                        cam->name, cam->layers, cam->layers);
        }
    }
    return WX_OK;
}

static wx_result parse_ortho(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    wx_scene *s = p->scene;
    ortho_attrs_def attrs = { .out = false, .layers = 1 };
    wx_result r = ATTRS(ortho_attrs, &attrs, NULL);
    if (r != WX_OK) {
        return r;
    }
    for (int i = 0; i < s->camera_count; ++i) {
        if (strcmp(s->cameras[i].name, attrs.name) == 0) {
            return fail(p, node, WX_CAUSE_DUPLICATE,
                        "camera name '%s' is used twice (first at line %d)", attrs.name,
                        s->cameras[i].line);
        }
    }
    if (attrs.out && s->output_index >= 0) {
        const wx_scene_camera *first = &s->cameras[s->output_index];
        return fail(p, node, WX_CAUSE_DUPLICATE,
                    "camera '%s' is a second output camera (the first is '%s' at line %d); a scene "
                    "has at most one",
                    attrs.name, first->name, first->line);
    }
    if (s->camera_count < SCENE_MAX_CAMERAS && !attrs.out &&
        s->input_count >= WX_MAX_INPUT_CAMERAS) {
        return fail(p, node, WX_CAUSE_TOO_MANY,
                    "too many input cameras (the collider takes at most %d)",
                    WX_MAX_INPUT_CAMERAS);
    }
    r = xml_grow_list(p, node, (void **)&s->cameras, s->camera_count, &p->camera_cap,
                      sizeof *s->cameras, SCENE_MAX_CAMERAS, "cameras");
    if (r != WX_OK) {
        return r;
    }
    wx_scene_camera *cam = &s->cameras[s->camera_count];
    memset(cam, 0, sizeof *cam);
    memcpy(cam->name, attrs.name, sizeof attrs.name);
    cam->is_output = attrs.out;
    cam->layers = attrs.layers;
    cam->line = line_of(node);
    if (attrs.out) {
        s->output_index = s->camera_count;
    } else {
        s->input_count++;
    }
    s->camera_count++;

    ortho_def o = { .cam = cam };
    if ((r = CHILDREN(ortho_children, &o, NULL)) == WX_OK &&
        (r = camera_matrices(p, node, &o)) == WX_OK && (r = camera_maps(p, node, &o)) == WX_OK &&
        (r = camera_layers(p, node, &o)) == WX_OK) {
        r = camera_output(p, node, &o);
    }
    for (int k = 0; k < WX_MAP_KINDS; ++k) {
        free(o.map_files[k]);
    }
    return r;
}

static const child_spec projected_maps_children[] = {
    { "Ortho", parse_ortho, true },
};

static wx_result parse_projected_maps(parser *p, const xmlNode *node, void *user)
{
    wx_result r = NO_ATTRS();
    if (r != WX_OK || (r = CHILDREN(projected_maps_children, user, NULL)) != WX_OK) {
        return r;
    }
    if (p->scene->input_count == 0) {
        return fail(p, node, WX_CAUSE_MISSING,
                    "no input camera: at least one <Ortho> must not be out=\"true\"");
    }
    return WX_OK;
}

static const child_spec collider_children[] = {
    { "ProjectedMaps", parse_projected_maps, false },
};

wx_result xml_parse_collider(parser *p, const xmlNode *node, void *user)
{
    p->collider = node;
    const xmlNode *seen[1];
    wx_result r = ATTRS(collider_attrs, &p->scene->collider, NULL);
    if (r != WX_OK || (r = CHILDREN(collider_children, user, seen)) != WX_OK) {
        return r;
    }
    if (seen[0] == NULL) {
        return fail(p, node, WX_CAUSE_MISSING,
                    "<Collider> needs a <ProjectedMaps> with the cameras");
    }
    return WX_OK;
}
