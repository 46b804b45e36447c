// bake.c: meshes and orthographic cameras to depth, normal, impact and dirt
// EXR maps, rendered offscreen with OSMesa (thesis 4.9.2, docs/design.md sections 1-3).
//
// One GL 4.5 core context renders into a float framebuffer with three colour
// targets in one pass (shaders/bake_*.glsl). Each mesh is imported, mapped onto
// the scene's <Surface>s, uploaded once (its CPU arrays freed on the way) and
// drawn for every camera. The projection is the camera's WTCMatrix itself: clip
// x, y = 2u-1, 2v-1, and clip z maps d over the depth range of the geometry,
// clipped at the eye plane (d = 0). The stored d is computed per fragment from
// the interpolated position, not from the depth buffer. glReadPixels returns
// rows bottom-up; read_target() flips them, the only place that does. Initial
// dirt is given to the input camera that sees each patch most head-on
// (compute_initial_dirt). Each camera's maps go to def->on_maps (the pipeline
// writes them, its files compressed in parallel) before the next camera renders,
// so one set of images is alive. docs/cameras.md describes the choices.
//
// A layered input camera (docs/design.md section 14) is drawn once per layer,
// depth peeling: after layer k is read back, attachment 0 is copied into the
// `previous` texture, and the next pass keeps only the crossings behind it
// (bake_frag.glsl). Its normals are then the mesh's own, out of the solid, and
// every (camera, layer) is a view of the initial-dirt ownership.
#define GL_GLEXT_PROTOTYPES 1
#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include "raster/bake.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model/maps.h"
#include "model/scene.h"
#include "model/geometry.h"
#include "model/ownership.h"
#include "model/mesh.h"
#include "core/matrix.h"
#include "core/progress.h"
#include "shaders.h"

enum {
    TARGET_DEPTH_NORMAL, // RGBA32F: d, normal
    TARGET_IMPACT_DIRT,  // RGBA32F: absorption, bounce, deposit, erosion
    TARGET_DENSITY,      // RG32F: initial dirt per square metre, <Surface> index + 1
    TARGET_COUNT,
};

/// Smallest |N.view| used when dividing by it (a surface seen edge-on).
#define MIN_COSINE 1e-3f

typedef struct gpu_mesh {
    GLuint vao;
    GLuint positions, normals, colors, materials, indices; // vertex and index buffers
    GLuint material_props; // behind props_texture
    GLuint props_texture;
    GLsizei index_count;
    double origin[3];
} gpu_mesh;

// What the bake knows of one scene camera.
typedef struct cam_state {
    bool bake;         // rendered here
    double d_min;      // depth range of all vertices
    double d_max;
    int layers;        // the layers baked (cam_layers), or those of the given depth
    float *depth;      // depth planes (one per layer, one after the other) kept for the
                       // initial-dirt visibility test, or NULL
    float *normal;     // with more than one layer: each layer's outward normals,
                       // 3 interleaved floats per texel, one layer after the other
    int depth_width;
    int depth_height;
} cam_state;

// The images of the camera being baked (reused while the size stays).
typedef struct map_set {
    int count; // 4 for an input camera, 2 (depth, normal) for the output camera
    wx_image maps[4];
} map_set;

typedef struct baker {
    const wx_scene *scene;
    const wx_bake_def *def;
    wx_bake_stats *stats;
    OSMesaContext context;
    bool current;    // the context is current: GL objects may be deleted
    unsigned char context_buffer[16 * 16 * 4];
    GLuint program;
    GLint loc_wtc, loc_depth_range, loc_depth_row, loc_view_dir, loc_outward, loc_peel;
    GLuint fbo;
    GLuint renderbuffers[TARGET_COUNT + 1]; // colour targets, then depth
    int fb_width, fb_height;
    GLuint previous; // depth peeling: the layer before's attachment 0 (0: none yet)
    int previous_width, previous_height;
    GLint max_side;
    GLint max_texture_buffer;
    gpu_mesh *meshes;
    int mesh_count;
    cam_state *cams; // one per scene camera
    bool has_dirt;   // some surface starts with dirt
    float *strip;    // readback buffer
    size_t strip_floats;
    map_set set;
} baker;

// ---------------------------------------------------------------------------
// Messages.

#define warn(b, ...) wx_warn((b)->def->quiet, __VA_ARGS__)

static wx_result gl_check(const char *what, wx_error *err)
{
    GLenum e = glGetError();
    if (e == GL_NO_ERROR) {
        return WX_OK;
    }
    while (glGetError() != GL_NO_ERROR) {
    }
    const char *name = e == GL_OUT_OF_MEMORY          ? "out of memory"
                       : e == GL_INVALID_VALUE         ? "invalid value"
                       : e == GL_INVALID_OPERATION     ? "invalid operation"
                       : e == GL_INVALID_ENUM          ? "invalid enum"
                       : e == GL_INVALID_FRAMEBUFFER_OPERATION ? "invalid framebuffer operation"
                                                               : "error";
    return wx_fail(err, WX_CAUSE_RENDERER, "bake: OpenGL %s (0x%04x) while %s", name, (unsigned)e,
                        what);
}

// ---------------------------------------------------------------------------
// GL context, program, framebuffer.

static wx_result compile_shader(GLenum kind, const char *source, const char *name, GLuint *out,
                                wx_error *err)
{
    GLuint shader = glCreateShader(kind);
    glShaderSource(shader, 1, &source, NULL);
    glCompileShader(shader);
    GLint ok = GL_FALSE;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (ok != GL_TRUE) {
        char log[768] = "";
        glGetShaderInfoLog(shader, sizeof log, NULL, log);
        glDeleteShader(shader);
        return wx_fail(err, WX_CAUSE_RENDERER, "bake: shader %s does not compile: %s", name, log);
    }
    *out = shader;
    return WX_OK;
}

static wx_result create_program(baker *b, wx_error *err)
{
    GLuint vs = 0, fs = 0;
    wx_result r = compile_shader(GL_VERTEX_SHADER, wx_shader_bake_vert, "bake_vert.glsl", &vs, err);
    if (r == WX_OK) {
        r = compile_shader(GL_FRAGMENT_SHADER, wx_shader_bake_frag, "bake_frag.glsl", &fs, err);
    }
    if (r != WX_OK) {
        glDeleteShader(vs);
        return r;
    }
    b->program = glCreateProgram();
    glAttachShader(b->program, vs);
    glAttachShader(b->program, fs);
    glLinkProgram(b->program);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = GL_FALSE;
    glGetProgramiv(b->program, GL_LINK_STATUS, &ok);
    if (ok != GL_TRUE) {
        char log[768] = "";
        glGetProgramInfoLog(b->program, sizeof log, NULL, log);
        return wx_fail(err, WX_CAUSE_RENDERER, "bake: shaders do not link: %s", log);
    }
    b->loc_wtc = glGetUniformLocation(b->program, "u_wtc");
    b->loc_depth_range = glGetUniformLocation(b->program, "u_depth_range");
    b->loc_depth_row = glGetUniformLocation(b->program, "u_depth_row");
    b->loc_view_dir = glGetUniformLocation(b->program, "u_view_dir");
    b->loc_outward = glGetUniformLocation(b->program, "u_outward");
    b->loc_peel = glGetUniformLocation(b->program, "u_peel");
    glUseProgram(b->program);
    glUniform1i(glGetUniformLocation(b->program, "u_material_props"), 0);
    glUniform1i(glGetUniformLocation(b->program, "u_previous"), 1);
    return gl_check("setting up the bake shaders", err);
}

static wx_result create_context(baker *b, wx_error *err)
{
    // llvmpipe takes its thread count from the environment when it starts.
    if (b->def->threads > 0 && getenv("LP_NUM_THREADS") == NULL) {
        char n[16];
        snprintf(n, sizeof n, "%d", b->def->threads);
        setenv("LP_NUM_THREADS", n, 0);
    }
    const int attribs[] = { OSMESA_FORMAT,
                            OSMESA_RGBA,
                            OSMESA_DEPTH_BITS,
                            0,
                            OSMESA_STENCIL_BITS,
                            0,
                            OSMESA_ACCUM_BITS,
                            0,
                            OSMESA_PROFILE,
                            OSMESA_CORE_PROFILE,
                            OSMESA_CONTEXT_MAJOR_VERSION,
                            4,
                            OSMESA_CONTEXT_MINOR_VERSION,
                            5,
                            0 };
    b->context = OSMesaCreateContextAttribs(attribs, NULL);
    if (b->context == NULL) {
        return wx_fail(err, WX_CAUSE_RENDERER,
                       "bake: cannot create an OSMesa OpenGL 4.5 core context (is Mesa's "
                       "llvmpipe available? try GALLIUM_DRIVER=llvmpipe)");
    }
    if (!OSMesaMakeCurrent(b->context, b->context_buffer, GL_UNSIGNED_BYTE, 16, 16)) {
        return wx_fail(err, WX_CAUSE_RENDERER, "bake: cannot make the OSMesa context current");
    }
    b->current = true;
    GLint rb = 0, tex = 0, vp[2] = { 0, 0 };
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &rb);
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &tex);
    glGetIntegerv(GL_MAX_VIEWPORT_DIMS, vp);
    glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &b->max_texture_buffer);
    GLint side = rb;
    side = tex < side ? tex : side;
    side = vp[0] < side ? vp[0] : side;
    side = vp[1] < side ? vp[1] : side;
    b->max_side = side < WX_MAP_MAX_SIDE ? side : WX_MAP_MAX_SIDE;
    GLint draw_buffers = 0;
    glGetIntegerv(GL_MAX_DRAW_BUFFERS, &draw_buffers);
    if (draw_buffers < TARGET_COUNT) {
        return wx_fail(err, WX_CAUSE_RENDERER, "bake: the GL driver has %d draw buffers, %d needed",
                            (int)draw_buffers, TARGET_COUNT);
    }
    wx_result r = create_program(b, err);
    if (r != WX_OK) {
        return r;
    }
    glGenFramebuffers(1, &b->fbo);
    glGenRenderbuffers(TARGET_COUNT + 1, b->renderbuffers);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    glDisable(GL_DITHER);
    glVertexAttrib4f(2, 0.0f, 0.0f, 0.0f, 1.0f); // colour of meshes without colours
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    return gl_check("creating the GL context", err);
}

static wx_result ensure_framebuffer(baker *b, int width, int height, wx_error *err)
{
    if (b->fb_width == width && b->fb_height == height) {
        return WX_OK;
    }
    static const GLenum formats[TARGET_COUNT + 1] = { GL_RGBA32F, GL_RGBA32F, GL_RG32F,
                                                      GL_DEPTH_COMPONENT32F };
    glBindFramebuffer(GL_FRAMEBUFFER, b->fbo);
    for (int t = 0; t <= TARGET_COUNT; ++t) {
        glBindRenderbuffer(GL_RENDERBUFFER, b->renderbuffers[t]);
        glRenderbufferStorage(GL_RENDERBUFFER, formats[t], width, height);
        GLenum attachment = t < TARGET_COUNT ? (GLenum)(GL_COLOR_ATTACHMENT0 + t)
                                             : GL_DEPTH_ATTACHMENT;
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, attachment, GL_RENDERBUFFER,
                                  b->renderbuffers[t]);
    }
    wx_result r = gl_check("allocating the float framebuffer", err);
    if (r != WX_OK) {
        wx_error_prefix(err, "%d x %d maps", width, height);
        b->fb_width = b->fb_height = 0;
        return r;
    }
    GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
        // llvmpipe reports a storage it could not allocate as an incomplete
        // attachment, not as GL_OUT_OF_MEMORY: every format here is renderable.
        b->fb_width = b->fb_height = 0;
        double mib = (double)width * (double)height * 40.0 / (1024.0 * 1024.0);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY,
                       "bake: out of memory for the %d x %d float framebuffer (about %.0f "
                       "MiB; OpenGL status 0x%04x)",
                       width, height, mib, (unsigned)status);
    }
    b->fb_width = width;
    b->fb_height = height;
    return WX_OK;
}

// Copies attachment 0 (d, normal) of the layer just drawn into the `previous`
// texture the next peeling pass reads (made, or remade, at the framebuffer's
// size: 16 bytes a texel more while a layered camera bakes).
static wx_result keep_previous_layer(baker *b, wx_error *err)
{
    int width = b->fb_width, height = b->fb_height;
    if (b->previous == 0 || b->previous_width != width || b->previous_height != height) {
        glDeleteTextures(1, &b->previous);
        glGenTextures(1, &b->previous);
        glBindTexture(GL_TEXTURE_2D, b->previous);
        glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA32F, width, height);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glBindTexture(GL_TEXTURE_2D, 0);
        b->previous_width = width;
        b->previous_height = height;
        wx_result r = gl_check("allocating the depth peeling texture", err);
        if (r != WX_OK) {
            wx_error_prefix(err, "%d x %d maps", width, height);
            glDeleteTextures(1, &b->previous);
            b->previous = 0;
            return r;
        }
    }
    glCopyImageSubData(b->renderbuffers[TARGET_DEPTH_NORMAL], GL_RENDERBUFFER, 0, 0, 0, 0,
                       b->previous, GL_TEXTURE_2D, 0, 0, 0, 0, width, height, 1);
    return gl_check("keeping a layer for depth peeling", err);
}

// ---------------------------------------------------------------------------
// Meshes.

static void delete_gpu_mesh(gpu_mesh *m)
{
    GLuint buffers[6] = { m->positions, m->normals, m->colors,
                          m->materials, m->indices, m->material_props };
    glDeleteBuffers(6, buffers);
    glDeleteTextures(1, &m->props_texture);
    glDeleteVertexArrays(1, &m->vao);
    memset(m, 0, sizeof *m);
}

static GLuint upload_buffer(GLenum target, size_t bytes, const void *data)
{
    GLuint buffer = 0;
    glGenBuffers(1, &buffer);
    glBindBuffer(target, buffer);
    glBufferData(target, (GLsizeiptr)bytes, data, GL_STATIC_DRAW);
    return buffer;
}

// Moves one CPU array into a new GL buffer: the copy is freed as soon as GL
// holds its own, so that a mesh exists about once in memory.
static GLuint upload_and_free(GLenum target, size_t bytes, void *data)
{
    GLuint buffer = upload_buffer(target, bytes, data);
    free(data);
    return buffer;
}

// Uploads the mesh (freeing its arrays on the way) and its per-material
// properties (2 RGBA texels per material). The per-triangle material becomes a
// per-vertex attribute: every vertex belongs to triangles of one material
// (mesh.h).
static wx_result upload_mesh(baker *b, wx_mesh_data *mesh, const float *props, gpu_mesh *g,
                             wx_error *err)
{
    size_t nv = (size_t)mesh->vertex_count, nt = (size_t)mesh->triangle_count;
    if (nt * 3 > (size_t)INT32_MAX) {
        return wx_fail(err, WX_CAUSE_BAD_MESH,
                       "%lld triangles are more than one draw takes (%d); split the mesh",
                       (long long)nt, INT32_MAX / 3);
    }
    if ((size_t)mesh->material_count * 2 > (size_t)b->max_texture_buffer) {
        return wx_fail(err, WX_CAUSE_BAD_MESH, "%d materials are more than the renderer takes",
                            mesh->material_count);
    }
    uint16_t *vertex_material = malloc((nv > 0 ? nv : 1) * sizeof *vertex_material);
    if (vertex_material == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
    }
    for (size_t t = 0; t < nt; ++t) {
        for (int k = 0; k < 3; ++k) {
            vertex_material[mesh->indices[3 * t + (size_t)k]] = mesh->materials[t];
        }
    }
    free(mesh->materials);
    mesh->materials = NULL;
    memcpy(g->origin, mesh->origin, sizeof g->origin);
    glGenVertexArrays(1, &g->vao);
    glBindVertexArray(g->vao);
    g->positions = upload_and_free(GL_ARRAY_BUFFER, nv * 3 * sizeof(float), mesh->positions);
    mesh->positions = NULL;
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, NULL);
    glEnableVertexAttribArray(0);
    g->normals = upload_and_free(GL_ARRAY_BUFFER, nv * 3 * sizeof(float), mesh->normals);
    mesh->normals = NULL;
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, NULL);
    glEnableVertexAttribArray(1);
    if (mesh->colors != NULL) {
        g->colors = upload_and_free(GL_ARRAY_BUFFER, nv * 4 * sizeof(float), mesh->colors);
        mesh->colors = NULL;
        glVertexAttribPointer(2, 4, GL_FLOAT, GL_FALSE, 0, NULL);
        glEnableVertexAttribArray(2);
    }
    g->materials = upload_and_free(GL_ARRAY_BUFFER, nv * sizeof(uint16_t), vertex_material);
    glVertexAttribIPointer(3, 1, GL_UNSIGNED_SHORT, 0, NULL);
    glEnableVertexAttribArray(3);
    g->indices = upload_and_free(GL_ELEMENT_ARRAY_BUFFER, nt * 3 * sizeof(uint32_t),
                                 mesh->indices);
    mesh->indices = NULL;
    g->index_count = (GLsizei)(nt * 3);
    glBindVertexArray(0);

    g->material_props = upload_buffer(GL_TEXTURE_BUFFER,
                                      (size_t)mesh->material_count * 8 * sizeof(float), props);
    glGenTextures(1, &g->props_texture);
    glBindTexture(GL_TEXTURE_BUFFER, g->props_texture);
    glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, g->material_props);
    glBindTexture(GL_TEXTURE_BUFFER, 0);
    glBindBuffer(GL_TEXTURE_BUFFER, 0);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    return gl_check("uploading the mesh", err);
}

// The camera's WTCMatrix with the mesh origin folded into its translation row,
// so that [p - origin, 1] * m = [p, 1] * wtc (computed in double).
static void local_matrix(const float wtc[16], const double origin[3], float out[16])
{
    double folded[16];
    wx_matrix_fold_origin(wtc, origin, folded);
    for (int k = 0; k < 16; ++k) {
        out[k] = (float)folded[k];
    }
}

// The substance the renderer's dirt target carries (the one vertex colours may
// give): "dirt", or the first substance of a scene without it. The others are
// looked up from each texel's <Surface> (fill_substances).
static int rendered_substance(const wx_scene *scene)
{
    return scene->dirt_substance >= 0 ? scene->dirt_substance : 0;
}

// Fills 2 RGBA texels per material of a mesh from its matched <Surface>:
// (absorption, bounce, dirt, deposit), (erosion, colour use, surface index + 1, 0).
static void material_props(const wx_scene *scene, int mesh_index, const wx_geometry_mesh *g,
                           float *props)
{
    const wx_mesh *mesh = &scene->meshes[mesh_index];
    int base = wx_scene_surface_base(scene, mesh_index);
    int s = rendered_substance(scene);
    for (int m = 0; m < g->data.material_count; ++m) {
        const wx_surface *match = &mesh->surfaces[g->surface[m]];
        float *p = &props[8 * m];
        p[0] = match->absorption;
        p[1] = match->bounce;
        p[2] = match->initial[s];
        p[3] = match->deposit[s];
        p[4] = match->erosion[s];
        p[5] = (float)match->colors; // 0 none, 1 impact, 2 dirt (bake_frag.glsl)
        p[6] = (float)(base + g->surface[m] + 1);
        p[7] = 0.0f;
    }
}

// Projects every vertex into every camera to bake: depth range, and warnings for
// vertices outside the frame or behind the eye.
static void survey_vertices(baker *b, const wx_mesh *mesh, const wx_mesh_data *data)
{
    const wx_scene *scene = b->scene;
    for (int c = 0; c < scene->camera_count; ++c) {
        cam_state *cs = &b->cams[c];
        if (!cs->bake) {
            continue;
        }
        const wx_scene_camera *sc = &scene->cameras[c];
        double m[16];
        wx_matrix_fold_origin(sc->camera.wtc, data->origin, m);
        int64_t outside = 0, behind = 0;
        double d_min = cs->d_min, d_max = cs->d_max;
        const float *p = data->positions;
        for (int64_t v = 0; v < data->vertex_count; ++v, p += 3) {
            double u = p[0] * m[0] + p[1] * m[4] + p[2] * m[8] + m[12];
            double w = p[0] * m[1] + p[1] * m[5] + p[2] * m[9] + m[13];
            double d = p[0] * m[2] + p[1] * m[6] + p[2] * m[10] + m[14];
            outside += u < 0.0 || u > 1.0 || w < 0.0 || w > 1.0;
            behind += d < 0.0;
            d_min = d < d_min ? d : d_min;
            d_max = d > d_max ? d : d_max;
        }
        cs->d_min = d_min;
        cs->d_max = d_max;
        if (outside > 0) {
            warn(b, "%s: camera '%s': %lld of %lld vertices of mesh '%s' fall outside its frame",
                 scene->path, sc->name, (long long)outside, (long long)data->vertex_count,
                 wx_mesh_display_name(scene, mesh));
        }
        if (behind > 0) {
            warn(b,
                 "%s: camera '%s': %lld of %lld vertices of mesh '%s' lie behind its eye (d < 0) "
                 "and are not seen",
                 scene->path, sc->name, (long long)behind, (long long)data->vertex_count,
                 wx_mesh_display_name(scene, mesh));
        }
    }
}

// The smallest texel (world units) of the cameras this bake draws.
static double finest_texel(const baker *b)
{
    double finest = INFINITY;
    for (int c = 0; c < b->scene->camera_count; ++c) {
        const wx_camera *cam = &b->scene->cameras[c].camera;
        if (!b->cams[c].bake || cam->width <= 0 || cam->height <= 0) {
            continue;
        }
        float w, h;
        wx_camera_frame_size(cam, &w, &h);
        finest = fmin(finest, fmin((double)w / cam->width, (double)h / cam->height));
    }
    return finest;
}

// How finely the triangles of a smooth-shaded mesh are cut so that the maps
// record the smooth surface its normals describe (wx_mesh_smooth_subdivide,
// docs/cameras.md): pieces of about SMOOTH_PIECE_TEXELS of the finest camera's
// texels along the longest curved edges (the 90th percentile: a few long
// edges do not cut every triangle), at most SMOOTH_MAX_LEVEL, and at most
// WX_SMOOTH_MAX_TRIANGLES triangles in all (a dense scan stays as it is).
enum { SMOOTH_MAX_LEVEL = 8 };
#define SMOOTH_PIECE_TEXELS 4.0

static int smooth_level(const baker *b, const wx_mesh_data *data)
{
    double edge = wx_mesh_curved_edge_length(data, 0.9), texel = finest_texel(b);
    if (!(edge > 0.0) || !isfinite(texel) || !(texel > 0.0)) {
        return 1;
    }
    double level = fmin(ceil(edge / (SMOOTH_PIECE_TEXELS * texel)), SMOOTH_MAX_LEVEL);
    double curved = (double)wx_mesh_curved_triangles(data);
    while (level > 1.0 && curved * level * level > WX_SMOOTH_MAX_TRIANGLES) {
        level -= 1.0;
    }
    return level > 1.0 ? (int)level : 1;
}

// Uploads every mesh of the geometry (its arrays are released on the way).
static wx_result load_meshes(baker *b, wx_geometry *geometry, wx_error *err)
{
    const wx_scene *scene = b->scene;
    b->meshes = calloc(scene->mesh_count > 0 ? (size_t)scene->mesh_count : 1, sizeof *b->meshes);
    if (b->meshes == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
    }
    b->stats->import_s += geometry->import_s;
    for (int i = 0; i < geometry->count; ++i) {
        const wx_mesh *mesh = &scene->meshes[i];
        wx_geometry_mesh *g = &geometry->meshes[i];
        wx_mesh_data *data = &g->data;
        if (data->triangle_count == 0) {
            continue;
        }
        double t1 = wx_now_s();
        // The mesh as the file has it (the smooth surface may cut it finer).
        b->stats->triangles += data->triangle_count;
        b->stats->vertices += data->vertex_count;
        float *props = malloc((size_t)data->material_count * 8 * sizeof(float));
        wx_result r = WX_OK;
        if (props == NULL) {
            r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
        } else {
            material_props(scene, i, g, props);
            r = wx_mesh_smooth_subdivide(data, smooth_level(b, data), err);
            if (r == WX_OK) {
                survey_vertices(b, mesh, data);
                r = upload_mesh(b, data, props, &b->meshes[b->mesh_count], err);
            }
            b->mesh_count++; // counted even when incomplete, so that it is deleted
            if (r != WX_OK) {
                wx_error_prefix(err, "%s:%d: mesh '%s'", scene->path, mesh->line,
                                wx_mesh_display_name(scene, mesh));
            }
        }
        free(props);
        wx_mesh_data_release_arrays(data);
        b->stats->setup_s += wx_now_s() - t1;
        if (r != WX_OK) {
            return r;
        }
    }
    if (b->stats->triangles == 0) {
        return wx_fail(err, WX_CAUSE_BAD_MESH,
                       "%s: the meshes of <Geometry> hold no triangles to bake the cameras "
                       "given by <View> from",
                       scene->path);
    }
    b->has_dirt = geometry->has_dirt;
    return WX_OK;
}

// ---------------------------------------------------------------------------
// Rendering and readback.

// The layers camera c records: the scene's (0 read as 1, at most
// WX_MAX_LAYERS); one for the output camera.
static int cam_layers(const wx_scene_camera *sc)
{
    if (sc->is_output || sc->layers <= 1) {
        return 1;
    }
    return sc->layers < WX_MAX_LAYERS ? sc->layers : WX_MAX_LAYERS;
}

// Draws layer `layer` of camera c into the framebuffer (the first `targets`
// colour targets). A layer after the first keeps the crossings behind the
// layer in the `previous` texture (keep_previous_layer).
static wx_result draw_camera(baker *b, int c, int targets, int layer, wx_error *err)
{
    const wx_scene_camera *sc = &b->scene->cameras[c];
    const cam_state *cs = &b->cams[c];
    int width = sc->camera.width, height = sc->camera.height;
    wx_result r = ensure_framebuffer(b, width, height, err);
    if (r != WX_OK) {
        return r;
    }
    // Depth range: every vertex, with a margin, clipped at the eye plane.
    double d_min = cs->d_min, d_max = cs->d_max;
    double margin = 1e-3 * (d_max - d_min) + 1e-5 * (fabs(d_min) + fabs(d_max)) + 1e-6;
    double near = d_min - margin > 0.0 ? d_min - margin : 0.0;
    double far = d_max + margin;
    if (!(far > near + 1e-6 * (fabs(near) + 1.0))) {
        far = near + 1.0; // nothing in front of the eye
    }

    glBindFramebuffer(GL_FRAMEBUFFER, b->fbo);
    static const GLenum all[TARGET_COUNT] = { GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1,
                                              GL_COLOR_ATTACHMENT2 };
    glDrawBuffers(TARGET_COUNT, all);
    glViewport(0, 0, width, height);
    const float background[4] = { INFINITY, 0.0f, 0.0f, 0.0f };
    const float zero[4] = { 0.0f, 0.0f, 0.0f, 0.0f };
    glClearBufferfv(GL_COLOR, 0, background);
    glClearBufferfv(GL_COLOR, 1, zero);
    glClearBufferfv(GL_COLOR, 2, zero);
    const float far_depth = 1.0f;
    glClearBufferfv(GL_DEPTH, 0, &far_depth);
    glDrawBuffers(targets, all);

    glUseProgram(b->program);
    float view[3];
    wx_camera_view_dir(&sc->camera, view);
    glUniform3f(b->loc_view_dir, view[0], view[1], view[2]);
    glUniform2f(b->loc_depth_range, (float)near, (float)far);
    glUniform1i(b->loc_outward, cam_layers(sc) > 1);
    glUniform1i(b->loc_peel, layer > 0);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, layer > 0 ? b->previous : 0);
    for (int i = 0; i < b->mesh_count; ++i) {
        const gpu_mesh *g = &b->meshes[i];
        float m[16];
        local_matrix(sc->camera.wtc, g->origin, m);
        glUniformMatrix4fv(b->loc_wtc, 1, GL_FALSE, m);
        glUniform4f(b->loc_depth_row, m[2], m[6], m[10], m[14]);
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_BUFFER, g->props_texture);
        glBindVertexArray(g->vao);
        glDrawElements(GL_TRIANGLES, g->index_count, GL_UNSIGNED_INT, NULL);
    }
    glBindVertexArray(0);
    return gl_check("drawing", err);
}

// Destination of one channel of a colour target: a plane in EXR row order.
typedef struct plane_out {
    float *plane;  // NULL: channel not wanted
    size_t stride; // floats from one texel to the next (0: 1; 3: interleaved normals)
} plane_out;

// Reads colour target `target` (`channels` floats per texel) in strips and
// scatters its channels into planes, flipping rows: GL row y is EXR row H-1-y.
static wx_result read_target(baker *b, int target, int channels, const plane_out *out,
                             wx_error *err)
{
    int width = b->fb_width, height = b->fb_height;
    size_t row_floats = (size_t)width * (size_t)channels;
    int rows = (int)((size_t)(1 << 20) / row_floats);
    rows = rows < 1 ? 1 : rows > height ? height : rows;
    size_t need = row_floats * (size_t)rows;
    if (b->strip_floats < need) {
        free(b->strip);
        b->strip = malloc(need * sizeof(float));
        b->strip_floats = b->strip != NULL ? need : 0;
        if (b->strip == NULL) {
            return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory for the readback");
        }
    }
    glReadBuffer((GLenum)(GL_COLOR_ATTACHMENT0 + target));
    GLenum format = channels == 4 ? GL_RGBA : channels == 2 ? GL_RG : GL_RED;
    for (int y0 = 0; y0 < height; y0 += rows) {
        int n = height - y0 < rows ? height - y0 : rows;
        glReadPixels(0, y0, width, n, format, GL_FLOAT, b->strip);
        for (int k = 0; k < n; ++k) {
            const float *src = b->strip + (size_t)k * row_floats;
            size_t row = (size_t)(height - 1 - (y0 + k)) * (size_t)width;
            for (int c = 0; c < channels; ++c) {
                float *dst = out[c].plane;
                size_t stride = out[c].stride > 0 ? out[c].stride : 1;
                if (dst == NULL) {
                    continue;
                }
                dst += row * stride;
                if (stride == 1) {
                    for (int i = 0; i < width; ++i) {
                        dst[i] = src[(size_t)i * (size_t)channels + (size_t)c];
                    }
                    continue;
                }
                for (int i = 0; i < width; ++i) {
                    dst[(size_t)i * stride] = src[(size_t)i * (size_t)channels + (size_t)c];
                }
            }
        }
    }
    return gl_check("reading the maps back", err);
}

// ---------------------------------------------------------------------------
// Initial dirt (docs/design.md section 3): stored once, in the input camera that sees the
// patch most head-on. Every layer of a layered camera is a view of its own.

// The depth map of an input camera that the scene gives as files (read by the
// caller), for the visibility test: copied, "no surface" as +inf. Its layers
// count when the caller read their normals too, else its layer 0 alone.
static wx_result take_given_depth(baker *b, int c, wx_error *err)
{
    const wx_maps *given = b->def->given_depth != NULL ? &b->def->given_depth[c] : NULL;
    if (given == NULL || given->depth == NULL) {
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "bake: no depth map given for camera '%s'",
                       b->scene->cameras[c].name);
    }
    cam_state *cs = &b->cams[c];
    int layers = wx_maps_layers(given) > 1 && given->normal != NULL ? wx_maps_layers(given) : 1;
    size_t n = (size_t)given->width * (size_t)given->height * (size_t)layers;
    cs->depth = malloc((n > 0 ? n : 1) * sizeof *cs->depth);
    if (cs->depth == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
    }
    if (layers > 1) {
        cs->normal = malloc(3 * n * sizeof *cs->normal);
        if (cs->normal == NULL) {
            return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
        }
        memcpy(cs->normal, given->normal, 3 * n * sizeof *cs->normal);
    }
    cs->layers = layers;
    cs->depth_width = given->width;
    cs->depth_height = given->height;
    for (size_t k = 0; k < n; ++k) {
        cs->depth[k] = wx_depth_is_empty(given->depth[k]) ? INFINITY : given->depth[k];
    }
    return WX_OK;
}

// The views of the initial-dirt ownership while camera c bakes: one per layer
// of every input camera whose depth is known, in scene order, each camera's
// layers nearest first; a layered camera's views carry its outward normals.
// Camera c's are its planes just baked: depth[l] per layer and, layered,
// `normal` (3 interleaved floats per texel, one layer after the other).
// *self is the index of c's layer 0. NULL when out of memory.
static wx_owner_view *owner_views(const baker *b, int c, float *const *depth, const float *normal,
                                  int *count, int *self)
{
    const wx_scene *scene = b->scene;
    int total = 0;
    for (int k = 0; k < scene->camera_count; ++k) {
        if (scene->cameras[k].is_output || (k != c && b->cams[k].depth == NULL)) {
            continue;
        }
        total += k == c ? cam_layers(&scene->cameras[k]) : b->cams[k].layers;
    }
    wx_owner_view *views = malloc((total > 0 ? (size_t)total : 1) * sizeof *views);
    if (views == NULL) {
        return NULL;
    }
    int n = 0;
    for (int k = 0; k < scene->camera_count; ++k) {
        const wx_scene_camera *sk = &scene->cameras[k];
        const cam_state *ks = &b->cams[k];
        if (sk->is_output || (k != c && ks->depth == NULL)) {
            continue;
        }
        int layers = k == c ? cam_layers(sk) : ks->layers;
        int w = k == c ? sk->camera.width : ks->depth_width;
        int h = k == c ? sk->camera.height : ks->depth_height;
        size_t texels = (size_t)w * (size_t)h;
        const float *normals = k == c ? normal : ks->normal;
        if (k == c) {
            *self = n;
        }
        for (int l = 0; l < layers; ++l) {
            const float *d = k == c ? depth[l] : ks->depth + (size_t)l * texels;
            wx_owner_view_init(&views[n], &sk->camera, d, w, h);
            if (layers > 1) {
                views[n].normal = normals + 3 * (size_t)l * texels;
            }
            ++n;
        }
    }
    *count = n;
    return views;
}

// Turns the density planes of view `self` (a layer of camera c; one per
// substance) into amounts: density x texel area / |N.view| x the share of the
// texel's surface the view owns (model/ownership.h: the view that sees a point
// most head-on holds what lies there, so every amount is stored once and a
// border between two views' parts is shared as the gather reads it); `area`
// (may be NULL) receives texel area / |N.view| x that share (what Grow
// multiplies). `normal`: the layer's x, y, z planes.
static wx_result compute_initial_dirt(baker *b, int c, const wx_owner_view *views, int count,
                                      int self, float *const *normal, float *const *planes,
                                      int planes_count, float *area, wx_error *err)
{
    const wx_scene_camera *sc = &b->scene->cameras[c];
    int width = sc->camera.width, height = sc->camera.height;
    float view[3], frame_w, frame_h;
    wx_camera_view_dir(&sc->camera, view);
    wx_camera_frame_size(&sc->camera, &frame_w, &frame_h);
    float texel_area = (frame_w / (float)width) * (frame_h / (float)height);

    size_t texels = (size_t)width * (size_t)height;
    float *share = malloc((texels > 0 ? texels : 1) * sizeof *share);
    if (share == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
    }
    wx_result r = wx_owned_fraction(views, count, self, normal[0], normal[1], normal[2], 1,
                                    b->def->threads > 0 ? b->def->threads : 1, share, err);
    if (r != WX_OK) {
        free(share);
        return r;
    }
    for (size_t t = 0; t < texels; ++t) {
        float cos_c = fabsf(normal[0][t] * view[0] + normal[1][t] * view[1] +
                            normal[2][t] * view[2]);
        float owned_area = share[t] * texel_area / fmaxf(cos_c, MIN_COSINE);
        for (int s = 0; s < planes_count; ++s) {
            planes[s][t] = owned_area > 0.0f ? planes[s][t] * owned_area : 0.0f;
        }
        if (area != NULL) {
            area[t] = owned_area;
        }
    }
    free(share);
    return WX_OK;
}

// ---------------------------------------------------------------------------
// The images handed to the caller.

// Makes the set's images W x H: depth (R), normal, impact (R, G, B), dirt (the
// scene's layout, model/maps.h: R, G, B for version 1's one substance), each
// channel once per layer: layer 0's as they are, then layer 1's named
// "layer1.R"... (wx_layer_channel), and so on.
static wx_result size_set(const wx_scene *scene, map_set *set, int width, int height, int count,
                          int layers, wx_error *err)
{
    static const char *const rgb[3] = { "R", "G", "B" };
    // The names (2 x 20 KiB): not on the stack.
    char (*dirt_names)[WX_NAME_MAX] = malloc(2 * WX_IMAGE_MAX_CHANNELS * sizeof *dirt_names);
    if (dirt_names == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
    }
    char (*names)[WX_NAME_MAX] = dirt_names + WX_IMAGE_MAX_CHANNELS;
    const char *base[WX_IMAGE_MAX_CHANNELS];
    const char *layered[WX_IMAGE_MAX_CHANNELS];
    int dirt_count = wx_dirt_channels(scene, false, dirt_names);
    wx_result r = WX_OK;
    set->count = count;
    for (int k = 0; k < count && r == WX_OK; ++k) {
        int per = k == 0 ? 1 : k < 3 ? 3 : dirt_count;
        for (int i = 0; i < per; ++i) {
            base[i] = k < 3 ? rgb[i] : dirt_names[i];
        }
        if (per * layers > WX_IMAGE_MAX_CHANNELS) {
            r = wx_fail(err, WX_CAUSE_BAD_SCENE,
                        "bake: %d layers of %d channels are more than an image holds (%d)",
                        layers, per, WX_IMAGE_MAX_CHANNELS);
            break;
        }
        for (int l = 0; l < layers && r == WX_OK; ++l) {
            for (int i = 0; i < per && r == WX_OK; ++i) {
                int at = l * per + i;
                if (!wx_layer_channel(names[at], l, base[i])) {
                    r = wx_fail(err, WX_CAUSE_BAD_SCENE,
                                "bake: channel '%s' of layer %d has too long a name", base[i], l);
                }
                layered[at] = names[at];
            }
        }
        if (r != WX_OK) {
            break;
        }
        wx_image *img = &set->maps[k];
        bool same = img->width == width && img->height == height &&
                    img->channel_count == per * layers;
        for (int i = 0; same && i < per * layers; ++i) {
            same = strcmp(img->channel_names[i], layered[i]) == 0;
        }
        if (same) {
            continue; // every plane read back or filled is overwritten; impact B stays 0
        }
        wx_image_free(img);
        r = wx_image_alloc(img, width, height, per * layers, layered, err);
    }
    free(dirt_names);
    return r;
}

// Index of the channel called `name` in `image`, or -1.
static int channel_index(const wx_image *image, const char *name)
{
    for (int c = 0; c < image->channel_count; ++c) {
        if (strcmp(image->channel_names[c], name) == 0) {
            return c;
        }
    }
    return -1;
}

// The substances the renderer does not carry, from each texel's <Surface>
// (surface index + 1 in `surface`): their initial density (turned into amounts
// with the rendered one), deposit and erosion, into one layer's dirt planes
// (substance s at 3s, 3s+1, 3s+2).
static wx_result fill_substances(const wx_scene *scene, const float *surface,
                                 float *const *dirt, size_t texels, wx_error *err)
{
    const wx_surface **by_index = wx_scene_surfaces_by_index(scene);
    if (by_index == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory (surfaces)");
    }
    const int known = wx_scene_surface_count(scene);
    int rendered = rendered_substance(scene);
    for (int s = 0; s < scene->substance_count; ++s) {
        if (s == rendered) {
            continue;
        }
        float *amount = dirt[3 * s], *deposit = dirt[3 * s + 1], *erosion = dirt[3 * s + 2];
        for (size_t t = 0; t < texels; ++t) {
            int id = (int)surface[t] - 1;
            const wx_surface *sf = id >= 0 && id < known ? by_index[id] : NULL;
            amount[t] = sf != NULL ? sf->initial[s] : 0.0f;
            deposit[t] = sf != NULL ? sf->deposit[s] : 0.0f;
            erosion[t] = sf != NULL ? sf->erosion[s] : 0.0f;
        }
    }
    free(by_index);
    return WX_OK;
}

// ---------------------------------------------------------------------------
// One camera.

// Whether a depth plane just read back holds some surface (a finite d): when
// layer k holds none, no layer after it does, and they are not drawn.
static bool any_surface(const float *depth, size_t texels)
{
    for (size_t t = 0; t < texels; ++t) {
        if (depth[t] < INFINITY) {
            return true;
        }
    }
    return false;
}

// Renders camera c and keeps only its depth planes and, layered, its outward
// normals (for the visibility test).
static wx_result render_depth_only(baker *b, int c, wx_error *err)
{
    const wx_scene_camera *sc = &b->scene->cameras[c];
    cam_state *cs = &b->cams[c];
    int layers = cam_layers(sc);
    size_t n = (size_t)sc->camera.width * (size_t)sc->camera.height;
    cs->depth = malloc(n * (size_t)layers * sizeof(float));
    if (cs->depth == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
    }
    if (layers > 1) {
        cs->normal = malloc(3 * n * (size_t)layers * sizeof(float));
        if (cs->normal == NULL) {
            return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
        }
    }
    cs->layers = layers;
    cs->depth_width = sc->camera.width;
    cs->depth_height = sc->camera.height;
    double t0 = wx_now_s();
    wx_result r = WX_OK;
    for (int l = 0; l < layers && r == WX_OK; ++l) {
        float *depth = cs->depth + (size_t)l * n;
        float *normal = layers > 1 ? cs->normal + 3 * (size_t)l * n : NULL;
        if (l > 0 && !any_surface(depth - n, n)) {
            for (size_t t = 0; t < n; ++t) {
                depth[t] = INFINITY;
            }
            memset(normal, 0, 3 * n * sizeof *normal);
            continue;
        }
        r = draw_camera(b, c, 1, l, err);
        if (r == WX_OK) {
            plane_out out[4] = { { depth, 1 },
                                 { normal, 3 },
                                 { normal != NULL ? normal + 1 : NULL, 3 },
                                 { normal != NULL ? normal + 2 : NULL, 3 } };
            r = read_target(b, TARGET_DEPTH_NORMAL, 4, out, err);
        }
        if (r == WX_OK && l + 1 < layers) {
            r = keep_previous_layer(b, err);
        }
    }
    b->stats->render_s += wx_now_s() - t0;
    return r;
}

// Layer `layer` of the set as the background: depth +inf, every other plane 0.
static void clear_layer(map_set *set, int layers, int layer, size_t texels)
{
    for (int k = 0; k < set->count; ++k) {
        wx_image *img = &set->maps[k];
        int per = img->channel_count / layers;
        for (int i = 0; i < per; ++i) {
            float *plane = img->channels[layer * per + i];
            if (k == 0) {
                for (size_t t = 0; t < texels; ++t) {
                    plane[t] = INFINITY;
                }
            } else {
                memset(plane, 0, texels * sizeof *plane);
            }
        }
    }
}

// The outward normals of the set's layers, interleaved (3 floats a texel, one
// layer after the other), as the ownership views of a layered camera read them.
static float *interleaved_normals(const wx_image *normal, int layers, size_t texels)
{
    float *out = malloc(3 * texels * (size_t)layers * sizeof *out);
    for (int l = 0; out != NULL && l < layers; ++l) {
        float *dst = out + 3 * texels * (size_t)l;
        for (size_t t = 0; t < texels; ++t) {
            for (int q = 0; q < 3; ++q) {
                dst[3 * t + (size_t)q] = normal->channels[3 * l + q][t];
            }
        }
    }
    return out;
}

static wx_result bake_camera(baker *b, int c, wx_error *err)
{
    const wx_scene *scene = b->scene;
    const wx_scene_camera *sc = &scene->cameras[c];
    bool input = !sc->is_output;
    int layers = cam_layers(sc);
    char label[sizeof sc->name + 8];
    snprintf(label, sizeof label, "bake %s", sc->name);
    wx_progress progress;
    wx_progress_begin(&progress, label, 2 * layers + 2, b->def->quiet);

    map_set *set = &b->set;
    size_t texels = (size_t)sc->camera.width * (size_t)sc->camera.height;
    wx_result r = size_set(scene, set, sc->camera.width, sc->camera.height, input ? 4 : 2,
                           layers, err);
    wx_image *maps = set->maps;
    // The dirt image's planes, per layer (`per` of them, layer l's from l*per):
    // the rendered substance's at 3g (3g+1, 3g+2), the surface record and
    // Grow's area when the scene's layout has them.
    int g = scene->substances_declared ? rendered_substance(scene) : 0;
    int S = scene->substances_declared ? scene->substance_count : 1;
    int per = r == WX_OK && input ? maps[3].channel_count / layers : 0;
    int surface_channel = r == WX_OK && input ? channel_index(&maps[3], WX_SURFACE_CHANNEL) : -1;
    int area_channel = r == WX_OK && input ? channel_index(&maps[3], WX_AREA_CHANNEL) : -1;
    // Every layer's surface record: the dirt map's own planes, or a scratch.
    float *scratch = NULL;
    float *surface[WX_MAX_LAYERS] = { NULL };
    if (r == WX_OK && input && (S > 1 || surface_channel >= 0)) {
        if (surface_channel < 0) {
            scratch = malloc(texels * (size_t)layers * sizeof *scratch);
            if (scratch == NULL) {
                r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
            }
        }
        for (int l = 0; l < layers && r == WX_OK; ++l) {
            surface[l] = scratch != NULL ? scratch + (size_t)l * texels
                                         : maps[3].channels[l * per + surface_channel];
        }
    }
    double t0 = wx_now_s();
    int drawn = 0; // layers drawn; those after them hold no crossing
    for (int l = 0; l < layers && r == WX_OK; ++l) {
        if (l > 0 && !any_surface(maps[0].channels[l - 1], texels)) {
            clear_layer(set, layers, l, texels);
            if (scratch != NULL) {
                memset(surface[l], 0, texels * sizeof *surface[l]);
            }
            continue;
        }
        r = draw_camera(b, c, input ? TARGET_COUNT : 1, l, err);
        wx_progress_update(&progress, 2 * l + 1);
        if (r == WX_OK) {
            plane_out out[4] = { { maps[0].channels[l], 1 },
                                 { maps[1].channels[3 * l], 1 },
                                 { maps[1].channels[3 * l + 1], 1 },
                                 { maps[1].channels[3 * l + 2], 1 } };
            r = read_target(b, TARGET_DEPTH_NORMAL, 4, out, err);
        }
        if (r == WX_OK && input) {
            float *const *dirt = &maps[3].channels[l * per];
            plane_out out[4] = { { maps[2].channels[3 * l], 1 },
                                 { maps[2].channels[3 * l + 1], 1 },
                                 { dirt[3 * g + 1], 1 },
                                 { dirt[3 * g + 2], 1 } };
            r = read_target(b, TARGET_IMPACT_DIRT, 4, out, err);
            if (r == WX_OK && surface[l] == NULL) {
                plane_out density[1] = { { dirt[3 * g], 1 } };
                r = read_target(b, TARGET_DENSITY, 1, density, err);
            } else if (r == WX_OK) {
                plane_out density[2] = { { dirt[3 * g], 1 }, { surface[l], 1 } };
                r = read_target(b, TARGET_DENSITY, 2, density, err);
            }
        }
        if (r == WX_OK && l + 1 < layers) {
            r = keep_previous_layer(b, err);
        }
        drawn = l + 1;
        wx_progress_update(&progress, 2 * l + 2);
    }
    double t1 = wx_now_s();
    b->stats->render_s += t1 - t0;
    if (r == WX_OK && input) {
        // Every (camera, layer) is a view of the ownership; a layer with no
        // crossing holds no dirt (its planes are already the background's).
        float *normal = layers > 1 ? interleaved_normals(&maps[1], layers, texels) : NULL;
        int count = 0, self = 0;
        wx_owner_view *views = layers == 1 || normal != NULL
                                   ? owner_views(b, c, maps[0].channels, normal, &count, &self)
                                   : NULL;
        if (views == NULL) {
            r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
        }
        for (int l = 0; l < drawn && r == WX_OK; ++l) {
            float *const *dirt = &maps[3].channels[l * per];
            if (S > 1) {
                r = fill_substances(scene, surface[l], dirt, texels, err);
            }
            float *planes[WX_MAX_SUBSTANCES];
            for (int s = 0; s < S; ++s) {
                planes[s] = dirt[3 * s];
            }
            if (r == WX_OK) {
                r = compute_initial_dirt(b, c, views, count, self + l, &maps[1].channels[3 * l],
                                         planes, S, area_channel >= 0 ? dirt[area_channel] : NULL,
                                         err);
            }
        }
        free(views);
        free(normal);
    }
    free(scratch);
    b->stats->dirt_s += wx_now_s() - t1;
    wx_progress_update(&progress, 2 * layers + 1);
    if (r == WX_OK) {
        double t2 = wx_now_s();
        r = b->def->on_maps(c, set->maps, set->count, b->def->user, err);
        b->stats->write_s += wx_now_s() - t2;
        b->stats->cameras += r == WX_OK;
    }
    wx_progress_end(&progress);
    return r;
}

// ---------------------------------------------------------------------------
// The scene.

static void baker_free(baker *b)
{
    for (int f = 0; f < 4; ++f) {
        wx_image_free(&b->set.maps[f]);
    }
    if (b->current) {
        for (int i = 0; i < b->mesh_count; ++i) {
            delete_gpu_mesh(&b->meshes[i]);
        }
        if (b->fbo != 0) {
            glDeleteFramebuffers(1, &b->fbo);
            glDeleteRenderbuffers(TARGET_COUNT + 1, b->renderbuffers);
        }
        glDeleteTextures(1, &b->previous);
        if (b->program != 0) {
            glDeleteProgram(b->program);
        }
        OSMesaMakeCurrent(NULL, NULL, 0, 0, 0);
    }
    if (b->context != NULL) {
        OSMesaDestroyContext(b->context);
    }
    free(b->meshes);
    if (b->cams != NULL) {
        for (int c = 0; c < b->scene->camera_count; ++c) {
            free(b->cams[c].depth);
            free(b->cams[c].normal);
        }
    }
    free(b->cams);
    free(b->strip);
    free(b);
}

static wx_result check_cameras(baker *b, int *bake_count, wx_error *err)
{
    const wx_scene *scene = b->scene;
    *bake_count = 0;
    for (int c = 0; c < scene->camera_count; ++c) {
        const wx_scene_camera *sc = &scene->cameras[c];
        cam_state *cs = &b->cams[c];
        cs->bake = sc->has_view && !wx_has_path(sc->depth_path);
        cs->d_min = INFINITY;
        cs->d_max = -INFINITY;
        if (!cs->bake) {
            continue;
        }
        ++*bake_count;
        int w = sc->camera.width, h = sc->camera.height;
        if (w < 1 || h < 1) {
            return wx_fail(err, WX_CAUSE_BAD_SCENE, "%s:%d: camera '%s' has no map size",
                                scene->path, sc->line, sc->name);
        }
    }
    return WX_OK;
}

static wx_result check_sizes(baker *b, wx_error *err)
{
    const wx_scene *scene = b->scene;
    for (int c = 0; c < scene->camera_count; ++c) {
        const wx_scene_camera *sc = &scene->cameras[c];
        if (!b->cams[c].bake) {
            continue;
        }
        if (sc->camera.width > b->max_side || sc->camera.height > b->max_side) {
            return wx_fail(err, WX_CAUSE_MAP_SIZE,
                           "%s:%d: camera '%s' asks for %d x %d maps; the renderer bakes at "
                           "most %d x %d",
                           scene->path, sc->line, sc->name, sc->camera.width, sc->camera.height,
                           (int)b->max_side, (int)b->max_side);
        }
    }
    return WX_OK;
}

wx_bake_def wx_default_bake_def(void)
{
    wx_bake_def def;
    memset(&def, 0, sizeof def);
    def.threads = 1;
    def.quiet = true;
    return def;
}

wx_result wx_bake_render(const wx_bake_def *def, wx_bake_stats *stats, wx_error *err)
{
    const wx_scene *scene = def->scene;
    wx_geometry *geometry = def->geometry;
    wx_bake_stats local;
    if (stats == NULL) {
        stats = &local;
    }
    memset(stats, 0, sizeof *stats);
    double start = wx_now_s();
    baker *b = calloc(1, sizeof *b); // large (image sets): not on the stack
    if (b == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
    }
    b->scene = scene;
    b->def = def;
    b->stats = stats;
    b->cams = calloc(scene->camera_count > 0 ? (size_t)scene->camera_count : 1, sizeof *b->cams);
    if (b->cams == NULL) {
        baker_free(b);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory");
    }
    int bake_count = 0;
    wx_result r = check_cameras(b, &bake_count, err);
    if (r != WX_OK || bake_count == 0) {
        baker_free(b);
        return r;
    }
    if (geometry == NULL || geometry->count != scene->mesh_count || scene->mesh_count == 0) {
        baker_free(b); // wx_geometry_load refuses a scene without meshes to bake from
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "bake: the scene's meshes were not imported");
    }
    double t0 = wx_now_s();
    r = create_context(b, err);
    if (r == WX_OK) {
        r = check_sizes(b, err);
    }
    stats->setup_s += wx_now_s() - t0;
    if (r == WX_OK) {
        r = load_meshes(b, geometry, err);
    }

    // Initial dirt needs every input camera's depth before any dirt map is final.
    int input_cameras = 0;
    for (int c = 0; c < scene->camera_count; ++c) {
        input_cameras += !scene->cameras[c].is_output;
    }
    bool visibility = (b->has_dirt || wx_scene_has_grow(scene)) && input_cameras > 1;
    double cameras_start = wx_now_s();
    for (int c = 0; c < scene->camera_count && r == WX_OK && visibility; ++c) {
        if (scene->cameras[c].is_output) {
            continue;
        }
        r = b->cams[c].bake ? render_depth_only(b, c, err) : take_given_depth(b, c, err);
    }
    for (int c = 0; c < scene->camera_count && r == WX_OK; ++c) {
        if (b->cams[c].bake) {
            r = bake_camera(b, c, err);
        }
    }
    stats->cameras_s = wx_now_s() - cameras_start;
    baker_free(b);
    stats->total_s = wx_now_s() - start;
    return r;
}

