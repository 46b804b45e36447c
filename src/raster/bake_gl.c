// bake_gl.c: the GL side of the bake: the OSMesa context, the shaders and the
// float framebuffer, the meshes on the GPU, drawing one camera's layer and
// reading its targets back (the only place that flips rows). bake.c decides
// what to draw; everything that calls GL or OSMesa is here.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "raster/baker_internal.h"
#include "core/matrix.h"
#include "shaders.h"

// ---------------------------------------------------------------------------
// Messages.

static wx_result gl_check(const char *what, wx_error *err)
{
    GLenum e = glGetError();
    if (e == GL_NO_ERROR) {
        return WX_OK;
    }
    while (glGetError() != GL_NO_ERROR) {
    }
    const char *name = e == GL_OUT_OF_MEMORY                   ? "out of memory"
                       : e == GL_INVALID_VALUE                 ? "invalid value"
                       : e == GL_INVALID_OPERATION             ? "invalid operation"
                       : e == GL_INVALID_ENUM                  ? "invalid enum"
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

wx_result bake_create_context(baker *b, wx_error *err)
{
    // llvmpipe takes its thread count from the environment when it starts.
    // With rasteriser threads it starts a new scene (its binned triangles,
    // up to 36 MiB each) whenever drawing outruns them and keeps each one
    // until the context ends: 110 to 180 MiB more on the shipped scenes, and
    // a count that depends on the threads' timing, so no estimate bounds it.
    // Rasterising on the calling thread keeps one scene; on two cores the
    // bake takes about as long (docs/reliability.md, "What the renderer keeps").
    // A user's LP_NUM_THREADS wins.
    setenv("LP_NUM_THREADS", "0", 0);
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
        GLenum attachment =
            t < TARGET_COUNT ? (GLenum)(GL_COLOR_ATTACHMENT0 + t) : GL_DEPTH_ATTACHMENT;
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, attachment, GL_RENDERBUFFER, b->renderbuffers[t]);
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

void bake_set_region(baker *b, int x0, int y0, int x1, int y1)
{
    b->region_x0 = x0;
    b->region_y0 = y0;
    b->region_x1 = x1;
    b->region_y1 = y1;
}

// The region in GL's window coordinates (rows bottom-up) for a frame of
// width x height: x, y, w, h.
static void region_gl(const baker *b, int width, int height, int rect[4])
{
    bool whole = b->region_x1 <= 0;
    int x0 = whole ? 0 : b->region_x0, x1 = whole ? width : b->region_x1;
    int y0 = whole ? 0 : b->region_y0, y1 = whole ? height : b->region_y1;
    rect[0] = x0;
    rect[1] = height - y1;
    rect[2] = x1 - x0;
    rect[3] = y1 - y0;
}

// Copies attachment 0 (d, normal) of the layer just drawn (within the region)
// into the `previous` texture the next peeling pass reads (made, or remade, at the framebuffer's
// size: 16 bytes a texel more while a layered camera bakes).
wx_result bake_keep_previous_layer(baker *b, wx_error *err)
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
    int rect[4];
    region_gl(b, width, height, rect);
    glCopyImageSubData(b->renderbuffers[TARGET_DEPTH_NORMAL], GL_RENDERBUFFER, 0, rect[0], rect[1],
                       0, b->previous, GL_TEXTURE_2D, 0, rect[0], rect[1], 0, rect[2], rect[3], 1);
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
wx_result bake_upload_mesh(baker *b, wx_mesh_data *mesh, const float *props, gpu_mesh *g,
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
    g->indices = upload_and_free(GL_ELEMENT_ARRAY_BUFFER, nt * 3 * sizeof(uint32_t), mesh->indices);
    mesh->indices = NULL;
    g->index_count = (GLsizei)(nt * 3);
    glBindVertexArray(0);

    g->material_props =
        upload_buffer(GL_TEXTURE_BUFFER, (size_t)mesh->material_count * 8 * sizeof(float), props);
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

// ---------------------------------------------------------------------------
// Rendering and readback.

// Draws layer `layer` of camera c into the framebuffer (the first `targets`
// colour targets), within the region (bake_set_region). A layer after the
// first keeps the crossings behind the layer in the `previous` texture
// (bake_keep_previous_layer).
wx_result bake_draw_camera(baker *b, int c, int targets, int layer, wx_error *err)
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
    // The region: the clears and the fragments outside it are scissored away.
    int rect[4];
    region_gl(b, width, height, rect);
    glEnable(GL_SCISSOR_TEST);
    glScissor(rect[0], rect[1], rect[2], rect[3]);
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
    glUniform1i(b->loc_outward, bake_cam_layers(sc) > 1);
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

// Reads colour target `target` (`channels` floats per texel) of the region
// (bake_set_region) in strips and scatters its channels into planes, flipping
// rows: GL row y is EXR row H-1-y. The planes' texels outside the region are
// left as they are.
wx_result bake_read_target(baker *b, int target, int channels, const plane_out *out, wx_error *err)
{
    int width = b->fb_width, height = b->fb_height;
    int rect[4];
    region_gl(b, width, height, rect);
    const int x0 = rect[0], w = rect[2], y_end = rect[1] + rect[3];
    size_t row_floats = (size_t)w * (size_t)channels;
    int rows = (int)((size_t)(1 << 20) / (row_floats > 0 ? row_floats : 1));
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
    for (int y0 = rect[1]; y0 < y_end; y0 += rows) {
        int n = y_end - y0 < rows ? y_end - y0 : rows;
        glReadPixels(x0, y0, w, n, format, GL_FLOAT, b->strip);
        for (int k = 0; k < n; ++k) {
            const float *src = b->strip + (size_t)k * row_floats;
            size_t row = (size_t)(height - 1 - (y0 + k)) * (size_t)width + (size_t)x0;
            for (int c = 0; c < channels; ++c) {
                float *dst = out[c].plane;
                size_t stride = out[c].stride > 0 ? out[c].stride : 1;
                if (dst == NULL) {
                    continue;
                }
                dst += row * stride;
                if (stride == 1) {
                    for (int i = 0; i < w; ++i) {
                        dst[i] = src[(size_t)i * (size_t)channels + (size_t)c];
                    }
                    continue;
                }
                for (int i = 0; i < w; ++i) {
                    dst[(size_t)i * stride] = src[(size_t)i * (size_t)channels + (size_t)c];
                }
            }
        }
    }
    return gl_check("reading the maps back", err);
}

// Deletes the GL objects (while the context is current) and the context.
void bake_release_gl(baker *b)
{
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
}
