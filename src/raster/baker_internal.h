// baker_internal.h: what the two files of the bake share: the baker's state
// (its GL objects among it, hence the GL headers) and the GL side's functions
// (bake_gl.c: the OSMesa context, the shaders, the framebuffer, the meshes on
// the GPU, drawing and readback), which bake.c's logic calls. Private to
// src/raster/.
#ifndef WX_BAKER_INTERNAL_H
#define WX_BAKER_INTERNAL_H

#define GL_GLEXT_PROTOTYPES 1
#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include <stdbool.h>
#include <stddef.h>

#include "raster/bake.h"
#include "model/mesh.h"
#include "model/scene.h"
#include "core/limits.h"

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
    GLuint material_props;                                 // behind props_texture
    GLuint props_texture;
    GLsizei index_count;
    double origin[3];
} gpu_mesh;

// What the bake knows of one scene camera.
typedef struct cam_state {
    bool bake;    // rendered here
    double d_min; // depth range of all vertices
    double d_max;
    int layers;    // the layers baked (cam_layers), or those of the given depth
    float *depth;  // depth planes (one per layer, one after the other) kept for the
                   // initial-dirt visibility test, or NULL
    float *normal; // with more than one layer: each layer's outward normals,
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
    bool current; // the context is current: GL objects may be deleted
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
    // The texels drawn, read back and kept for the next peeling pass: columns
    // [x0, x1), rows [y0, y1) in EXR row order; x1 = 0: the whole frame.
    int region_x0, region_y0, region_x1, region_y1;
    map_set set;
} baker;

// Destination of one channel of a colour target: a plane in EXR row order.
typedef struct plane_out {
    float *plane;  // NULL: channel not wanted
    size_t stride; // floats from one texel to the next (0: 1; 3: interleaved normals)
} plane_out;

// The layers camera c records: the scene's (0 read as 1, at most
// WX_MAX_LAYERS); one for the output camera.
static inline int bake_cam_layers(const wx_scene_camera *sc)
{
    if (sc->is_output || sc->layers <= 1) {
        return 1;
    }
    return sc->layers < WX_MAX_LAYERS ? sc->layers : WX_MAX_LAYERS;
}

// The planes of one peeling pass, as read back: d, the outward normal, and for
// an input camera absorption, bounce, deposit, erosion, initial density and
// <Surface> index + 1 (the three colour targets, shaders/bake_frag.glsl).
enum {
    PASS_D,
    PASS_NX,
    PASS_NY,
    PASS_NZ,
    PASS_ABSORPTION,
    PASS_BOUNCE,
    PASS_DEPOSIT,
    PASS_EROSION,
    PASS_DENSITY,
    PASS_SURFACE,
    PASS_PLANES,
    PASS_DEPTH_PLANES = PASS_NZ + 1, // a camera baked for its depth alone
};

// bake_peel.c: draws layered camera c by depth peeling into the kept layers
// `dst` (`planes` of PASS_*: PASS_PLANES for an input camera,
// PASS_DEPTH_PLANES for its depth alone), contacts giving way where the
// crossings outnumber the layers; *drawn: the most crossings a texel kept.
wx_result bake_peel_camera(baker *b, int c, int layers, int planes, plane_out (*dst)[PASS_PLANES],
                           int *drawn, wx_error *err);

// bake_gl.c: the GL 4.5 core context, its program and the framebuffer's
// limits (b->max_side).
wx_result bake_create_context(baker *b, wx_error *err);

// bake_gl.c: uploads one mesh (its CPU arrays freed on the way).
wx_result bake_upload_mesh(baker *b, wx_mesh_data *mesh, const float *props, gpu_mesh *g,
                           wx_error *err);

// bake_gl.c: the region later draws, readbacks and kept layers cover: columns
// [x0, x1), rows [y0, y1) in EXR row order (x1 = 0: the whole frame). The
// texels outside it keep what the framebuffer held.
void bake_set_region(baker *b, int x0, int y0, int x1, int y1);

// bake_gl.c: draws layer `layer` of camera c (the first `targets` colour targets).
wx_result bake_draw_camera(baker *b, int c, int targets, int layer, wx_error *err);

// bake_gl.c: keeps the layer just drawn for the next depth-peeling pass.
wx_result bake_keep_previous_layer(baker *b, wx_error *err);

// bake_gl.c: reads colour target `target` back into planes, in EXR row order.
wx_result bake_read_target(baker *b, int target, int channels, const plane_out *out, wx_error *err);

// bake_gl.c: deletes the GL objects and the context.
void bake_release_gl(baker *b);

#endif
