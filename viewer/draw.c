// draw.c: the viewer's OpenGL drawing (draw.h). Shaders are GLSL 330 core
// strings here; buffers hold world-space vertices, so one projection * view
// matrix serves everything.
#include "draw.h"

#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "palette.h"
#include "sim/simulate.h"

// Static geometry and hit points: position and colour per vertex.
static const char *const COLOR_VS =
    "#version 330 core\n"
    "layout(location = 0) in vec3 position;\n"
    "layout(location = 1) in vec3 color;\n"
    "uniform mat4 mvp;\n"
    "out vec3 v_color;\n"
    "void main() {\n"
    "    gl_Position = mvp * vec4(position, 1.0);\n"
    "    v_color = color;\n"
    "}\n";

static const char *const COLOR_FS =
    "#version 330 core\n"
    "in vec3 v_color;\n"
    "out vec4 frag;\n"
    "void main() { frag = vec4(v_color, 1.0); }\n";

// Particles: x, y, z and load (of the shown substance) interleaved; the colour
// goes from clean to the substance's colour with the load.
static const char *const PARTICLE_VS =
    "#version 330 core\n"
    "layout(location = 0) in vec4 particle;\n" // x, y, z, load
    "uniform mat4 mvp;\n"
    "uniform float load_scale;\n"
    "flat out float v_t;\n"
    "void main() {\n"
    "    gl_Position = mvp * vec4(particle.xyz, 1.0);\n"
    "    v_t = sqrt(clamp(particle.w / load_scale, 0.0, 1.0));\n"
    "}\n";

static const char *const PARTICLE_FS =
    "#version 330 core\n"
    "flat in float v_t;\n"
    "uniform vec3 clean_color;\n"
    "uniform vec3 dirty_color;\n"
    "out vec4 frag;\n"
    "void main() { frag = vec4(mix(clean_color, dirty_color, v_t), 1.0); }\n";

enum {
    PARTICLE_POINT_SIZE = 1,
    HIT_POINT_SIZE = 2,
    DEPTH_POINT_SIZE = 1,
};

static wx_result compile(GLenum kind, const char *name, const char *src, GLuint *out,
                         wx_error *err)
{
    GLuint shader = glCreateShader(kind);
    glShaderSource(shader, 1, &src, NULL);
    glCompileShader(shader);
    GLint ok = GL_FALSE;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (ok != GL_TRUE) {
        char log[1024] = "";
        glGetShaderInfoLog(shader, sizeof log, NULL, log);
        glDeleteShader(shader);
        return wx_fail(err, WX_CAUSE_RENDERER, "GL: %s %s shader does not compile: %s", name,
                            kind == GL_VERTEX_SHADER ? "vertex" : "fragment", log);
    }
    *out = shader;
    return WX_OK;
}

wx_result vw_gl_program(const char *name, const char *vertex_src, const char *fragment_src,
                        GLuint *program, wx_error *err)
{
    GLuint vs = 0, fs = 0;
    wx_result r = compile(GL_VERTEX_SHADER, name, vertex_src, &vs, err);
    if (r == WX_OK) {
        r = compile(GL_FRAGMENT_SHADER, name, fragment_src, &fs, err);
    }
    if (r != WX_OK) {
        if (vs != 0) {
            glDeleteShader(vs);
        }
        return r;
    }
    GLuint p = glCreateProgram();
    glAttachShader(p, vs);
    glAttachShader(p, fs);
    glLinkProgram(p);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = GL_FALSE;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (ok != GL_TRUE) {
        char log[1024] = "";
        glGetProgramInfoLog(p, sizeof log, NULL, log);
        glDeleteProgram(p);
        return wx_fail(err, WX_CAUSE_RENDERER, "GL: %s program does not link: %s", name, log);
    }
    *program = p;
    return WX_OK;
}

static void vertex_layout(void)
{
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(vw_vertex),
                          (const void *)offsetof(vw_vertex, position));
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(vw_vertex),
                          (const void *)offsetof(vw_vertex, color));
}

// A vertex array whose buffer holds vw_vertex (or, for particles, vec4).
static void make_vertex_array(GLuint *vao, GLuint *vbo, bool particles)
{
    glGenVertexArrays(1, vao);
    glGenBuffers(1, vbo);
    glBindVertexArray(*vao);
    glBindBuffer(GL_ARRAY_BUFFER, *vbo);
    if (particles) {
        glEnableVertexAttribArray(0);
        glVertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, 4 * sizeof(float), (const void *)0);
    } else {
        vertex_layout();
    }
    glBindVertexArray(0);
}

wx_result vw_draw_init(vw_draw *draw, int hit_capacity, wx_error *err)
{
    memset(draw, 0, sizeof *draw);
    wx_result r = vw_gl_program("colour", COLOR_VS, COLOR_FS, &draw->color_program, err);
    if (r == WX_OK) {
        r = vw_gl_program("particle", PARTICLE_VS, PARTICLE_FS, &draw->particle_program, err);
    }
    if (r != WX_OK) {
        vw_draw_free(draw);
        return r;
    }
    draw->color_mvp = glGetUniformLocation(draw->color_program, "mvp");
    draw->particle_mvp = glGetUniformLocation(draw->particle_program, "mvp");
    draw->particle_load_scale = glGetUniformLocation(draw->particle_program, "load_scale");
    draw->particle_clean = glGetUniformLocation(draw->particle_program, "clean_color");
    draw->particle_dirty = glGetUniformLocation(draw->particle_program, "dirty_color");

    make_vertex_array(&draw->line_vao, &draw->line_vbo, false);
    make_vertex_array(&draw->depth_vao, &draw->depth_vbo, false);
    make_vertex_array(&draw->particle_vao, &draw->particle_vbo, true);
    make_vertex_array(&draw->hit_vao, &draw->hit_vbo, false);

    draw->hit_capacity = hit_capacity > 0 ? hit_capacity : 1;
    draw->hits = malloc((size_t)draw->hit_capacity * sizeof *draw->hits);
    draw->hit_vertices = malloc((size_t)draw->hit_capacity * sizeof *draw->hit_vertices);
    if (draw->hits == NULL || draw->hit_vertices == NULL) {
        vw_draw_free(draw);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (hit points)");
    }
    GLenum gl_err = glGetError();
    if (gl_err != GL_NO_ERROR) {
        vw_draw_free(draw);
        return wx_fail(err, WX_CAUSE_RENDERER, "GL error 0x%x while creating buffers", gl_err);
    }
    return WX_OK;
}

wx_result vw_draw_set_world(vw_draw *draw, const vw_world *world, wx_error *err)
{
    glBindBuffer(GL_ARRAY_BUFFER, draw->line_vbo);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)((size_t)world->line_count * sizeof(vw_vertex)),
                 world->lines, GL_STATIC_DRAW);
    int n = world->scene.camera_count;
    bool *cameras = realloc(draw->depth_cameras, (size_t)(n > 0 ? n : 1) * sizeof *cameras);
    if (cameras == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (viewer)");
    }
    draw->depth_cameras = cameras;
    draw->camera_count = n;
    draw->depth_valid = false;
    draw->depth_count = 0;
    draw->particle_count = 0;
    draw->hit_count = 0;
    return WX_OK;
}

// Room for one point per pixel (there are never more).
static bool reserve_staging(vw_draw *draw, int width, int height)
{
    size_t pixels = (size_t)(width > 1 ? width : 1) * (size_t)(height > 1 ? height : 1);
    if (pixels <= draw->staging_capacity) {
        return true;
    }
    float *staging = realloc(draw->staging, pixels * 4 * sizeof *staging);
    if (staging == NULL) {
        return false;
    }
    draw->staging = staging;
    vw_vertex *vertices = realloc(draw->vertices, pixels * sizeof *vertices);
    if (vertices == NULL) {
        return false;
    }
    draw->vertices = vertices;
    uint32_t *picked = realloc(draw->depth_picked, pixels * sizeof *picked);
    if (picked == NULL) {
        return false;
    }
    draw->depth_picked = picked;
    draw->staging_capacity = pixels;
    return true;
}

static void upload(GLuint vbo, const void *data, size_t size)
{
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    // A new store each time: the driver need not wait for the last frame's draw.
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)size, data, GL_STREAM_DRAW);
}

static bool depth_samples_current(const vw_draw *draw, const vw_world *world, const vw_show *show,
                                  const float mvp[16], int width, int height)
{
    if (!draw->depth_valid || width != draw->depth_width || height != draw->depth_height ||
        draw->depth_mask != world->mask || draw->depth_layer != show->layer ||
        memcmp(mvp, draw->depth_mvp, sizeof draw->depth_mvp) != 0) {
        return false;
    }
    for (int c = 0; c < draw->camera_count; ++c) {
        if (show->cameras[c] != draw->depth_cameras[c]) {
            return false;
        }
    }
    return true;
}

// The depth samples of the shown cameras and layer, nearest per pixel: picked
// again only when the view, the shown cameras or layer or the shown mask change; coloured again
// every frame when they show deposits, which change with every step (a mask
// shown instead stays as it is).
static wx_result update_depth_samples(vw_draw *draw, const vw_world *world, const vw_show *show,
                                      const float mvp[16], int width, int height, wx_error *err)
{
    bool mask = world->mask >= 0;
    bool deposits = !mask && vw_world_shows_deposits(world);
    if (depth_samples_current(draw, world, show, mvp, width, height)) {
        if (deposits) {
            vw_world_deposit_colors(world, draw->depth_picked, (size_t)draw->depth_count,
                                    draw->staging, draw->vertices);
            upload(draw->depth_vbo, draw->vertices, (size_t)draw->depth_count * sizeof(vw_vertex));
        }
        return WX_OK;
    }
    vw_point_filter *f = &draw->filter;
    if (!vw_points_begin(f, mvp, width, height, (size_t)world->point_count)) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (depth samples)");
    }
    for (int c = 0; c < world->scene.camera_count; ++c) {
        vw_range r = vw_world_layer_points(world, c, show->layer);
        for (int i = r.first; show->cameras[c] && i < r.first + r.count; ++i) {
            const float *p = world->points[i].position;
            float index; // the sample's index travels as the fourth float's bits
            uint32_t bits = (uint32_t)i;
            memcpy(&index, &bits, sizeof index);
            vw_points_offer(f, p[0], p[1], p[2], p[0], p[1], p[2], index);
        }
    }
    size_t n = vw_points_winners(f, draw->staging);
    for (size_t k = 0; k < n; ++k) {
        uint32_t i;
        memcpy(&i, &draw->staging[4 * k + 3], sizeof i);
        draw->depth_picked[k] = i;
        draw->vertices[k] = world->points[i];
    }
    if (mask) {
        vw_world_mask_colors(world, draw->depth_picked, n, draw->vertices);
    } else if (deposits) {
        vw_world_deposit_colors(world, draw->depth_picked, n, draw->staging, draw->vertices);
    }
    upload(draw->depth_vbo, draw->vertices, n * sizeof(vw_vertex));
    draw->depth_count = (int)n;
    memcpy(draw->depth_mvp, mvp, sizeof draw->depth_mvp);
    draw->depth_width = width;
    draw->depth_height = height;
    memcpy(draw->depth_cameras, show->cameras, (size_t)draw->camera_count * sizeof(bool));
    draw->depth_mask = world->mask;
    draw->depth_layer = show->layer;
    draw->depth_valid = true;
    return WX_OK;
}

// The live particles, nearest per pixel, as x, y, z and load of the shown
// substance.
static wx_result update_particles(vw_draw *draw, const vw_world *world, const float mvp[16],
                                  int width, int height, wx_error *err)
{
    wx_particle_view view;
    wx_sim_particles(world->sim, &view);
    if (view.count > (int64_t)UINT32_MAX) {
        view.count = (int64_t)UINT32_MAX; // more than memory allows anyway
    }
    vw_point_filter *f = &draw->filter;
    if (!vw_points_begin(f, mvp, width, height, (size_t)view.count)) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (%lld particles to draw)",
                            (long long)view.count);
    }
    for (int64_t i = 0; i < view.count; ++i) {
        float x = view.x[i], y = view.y[i], z = view.z[i];
        vw_points_offer(f, x, y, z, x, y, z, (float)vw_particle_load(world, &view, i));
    }
    size_t n = vw_points_winners(f, draw->staging);
    upload(draw->particle_vbo, draw->staging, n * 4 * sizeof(float));
    draw->particle_count = (int64_t)n;
    return WX_OK;
}

static void update_hits(vw_draw *draw, const vw_world *world, const vw_show *show)
{
    int n = wx_sim_recent_hits(world->sim, draw->hits, draw->hit_capacity);
    draw->hit_count = 0;
    for (int k = 0; k < n; ++k) {
        const wx_hit_sample *h = &draw->hits[k];
        // h->camera is a view: a camera and one of its layers.
        int layer = 0;
        int c = vw_world_view_camera(world, h->camera, &layer);
        if (c >= 0 && (!show->cameras[c] || (show->layer >= 0 && layer != show->layer))) {
            continue;
        }
        int kind = h->impact >= WX_IMPACT_ABSORB && h->impact <= WX_IMPACT_SLIDE ? (int)h->impact
                                                                                 : 0;
        vw_vertex *v = &draw->hit_vertices[draw->hit_count++];
        memcpy(v->position, h->position, sizeof v->position);
        for (int a = 0; a < 3; ++a) {
            v->color[a] = (float)VW_HIT_COLORS[kind][a] / 255.0f;
        }
    }
    upload(draw->hit_vbo, draw->hit_vertices, (size_t)draw->hit_count * sizeof(vw_vertex));
}

wx_result vw_draw_update(vw_draw *draw, const vw_world *world, const vw_show *show,
                         const float mvp[16], int fb_width, int fb_height, wx_error *err)
{
    if (!reserve_staging(draw, fb_width, fb_height)) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (%dx%d window)", fb_width,
                       fb_height);
    }
    wx_result r = WX_OK;
    if (show->depth_samples) {
        r = update_depth_samples(draw, world, show, mvp, fb_width, fb_height, err);
    }
    draw->particle_count = 0;
    if (r == WX_OK && show->particles) {
        r = update_particles(draw, world, mvp, fb_width, fb_height, err);
    }
    draw->hit_count = 0;
    if (r == WX_OK && show->hits) {
        update_hits(draw, world, show);
    }
    return r;
}

static void draw_range(GLenum mode, vw_range range)
{
    if (range.count > 0) {
        glDrawArrays(mode, range.first, range.count);
    }
}

static void uniform_color(GLint location, const uint8_t rgb[3])
{
    glUniform3f(location, (float)rgb[0] / 255.0f, (float)rgb[1] / 255.0f, (float)rgb[2] / 255.0f);
}

void vw_draw_frame(const vw_draw *draw, const vw_world *world, const vw_show *show,
                   const float mvp[16])
{
    glClearColor((float)VW_BACKGROUND_COLOR[0] / 255.0f, (float)VW_BACKGROUND_COLOR[1] / 255.0f,
                 (float)VW_BACKGROUND_COLOR[2] / 255.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_BLEND);

    glUseProgram(draw->color_program);
    glUniformMatrix4fv(draw->color_mvp, 1, GL_FALSE, mvp);
    glBindVertexArray(draw->line_vao);
    for (int c = 0; c < world->scene.camera_count; ++c) {
        if (show->cameras[c]) {
            draw_range(GL_LINES, world->camera_lines[c]);
        }
    }
    draw_range(GL_LINES, world->emitter_lines);
    draw_range(GL_LINES, world->bbox_lines);
    if (show->depth_samples && draw->depth_count > 0) {
        glPointSize(DEPTH_POINT_SIZE);
        glBindVertexArray(draw->depth_vao);
        glDrawArrays(GL_POINTS, 0, draw->depth_count);
    }
    if (show->hits && draw->hit_count > 0) {
        glPointSize(HIT_POINT_SIZE);
        glBindVertexArray(draw->hit_vao);
        glDrawArrays(GL_POINTS, 0, draw->hit_count);
    }
    if (show->particles && draw->particle_count > 0) {
        glUseProgram(draw->particle_program);
        glUniformMatrix4fv(draw->particle_mvp, 1, GL_FALSE, mvp);
        glUniform1f(draw->particle_load_scale, world->load_scale);
        uniform_color(draw->particle_clean, VW_PARTICLE_CLEAN_COLOR);
        float dirty[3];
        vw_world_substance_color(world, world->substance, dirty);
        glUniform3f(draw->particle_dirty, dirty[0], dirty[1], dirty[2]);
        glPointSize(PARTICLE_POINT_SIZE);
        glBindVertexArray(draw->particle_vao);
        glDrawArrays(GL_POINTS, 0, (GLsizei)draw->particle_count);
    }
    glBindVertexArray(0);
    glUseProgram(0);
}

void vw_draw_free(vw_draw *draw)
{
    GLuint programs[2] = { draw->color_program, draw->particle_program };
    for (int k = 0; k < 2; ++k) {
        if (programs[k] != 0) {
            glDeleteProgram(programs[k]);
        }
    }
    GLuint vaos[4] = { draw->line_vao, draw->depth_vao, draw->particle_vao, draw->hit_vao };
    GLuint vbos[4] = { draw->line_vbo, draw->depth_vbo, draw->particle_vbo, draw->hit_vbo };
    glDeleteVertexArrays(4, vaos);
    glDeleteBuffers(4, vbos);
    vw_points_free(&draw->filter);
    free(draw->staging);
    free(draw->vertices);
    free(draw->depth_cameras);
    free(draw->depth_picked);
    free(draw->hits);
    free(draw->hit_vertices);
    memset(draw, 0, sizeof *draw);
}
