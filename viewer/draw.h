// draw.h: draws a world with OpenGL 3.3 core (thesis 4.8.5): camera frames,
// emitters and bounding box from a static buffer; depth samples (with
// <Substances>, tinted by the shown substance on their surface; while a
// derived mask is shown, coloured by its value instead), live particles
// (coloured by their load of the shown substance) and recent hit points from
// buffers refilled as needed. Depth samples and particles are one-pixel points, reduced on the CPU
// to the nearest per pixel before upload (points.h).
#ifndef VW_DRAW_H
#define VW_DRAW_H

#include <stdbool.h>
#include <stdint.h>

#include "gl.h"
#include "points.h"
#include "sim/simulate.h"
#include "world.h"

/// What to show.
typedef struct vw_show {
    const bool *cameras; ///< per scene camera: frame and depth samples
    /// The layer whose depth samples and hits are shown (docs/design.md
    /// section 14): -1 every layer's, else layer k's only (key L).
    int layer;
    bool depth_samples;
    bool particles;
    bool hits;
} vw_show;

typedef struct vw_draw {
    GLuint color_program;
    GLint color_mvp;
    GLuint particle_program;
    GLint particle_mvp, particle_load_scale, particle_clean, particle_dirty;

    GLuint line_vao, line_vbo;     ///< the world's lines, uploaded once

    GLuint depth_vao, depth_vbo;   ///< depth samples nearest per pixel
    int depth_count;
    bool depth_valid;              ///< depth_vbo matches the key below
    float depth_mvp[16];           ///< the view the depth samples were picked for
    int depth_width, depth_height;
    bool *depth_cameras;           ///< cameras shown when they were picked
    int depth_layer;               ///< the layer shown when they were picked
    int depth_mask;                ///< the world's mask shown when they were coloured
    uint32_t *depth_picked;        ///< the picked samples (indices into world->points)
    int camera_count;

    GLuint particle_vao, particle_vbo; ///< x, y, z, load per particle
    int64_t particle_count;

    GLuint hit_vao, hit_vbo;
    int hit_capacity;
    int hit_count;
    wx_hit_sample *hits;
    vw_vertex *hit_vertices;

    vw_point_filter filter;
    float *staging;                ///< four floats per point kept
    vw_vertex *vertices;           ///< depth samples kept
    size_t staging_capacity;       ///< points (one per pixel) the two hold
} vw_draw;

/// Compiles the shaders and creates the buffers (a GL context must be current).
wx_result vw_draw_init(vw_draw *draw, int hit_capacity, wx_error *err);

/// Uploads a world's lines (after loading or reloading it).
wx_result vw_draw_set_world(vw_draw *draw, const vw_world *world, wx_error *err);

/// Refills the buffers for a frame seen through `mvp` on fb_width x fb_height
/// pixels: the depth samples when the view, the shown cameras or layer or the
/// world's shown mask changed, the live particles, and the recent hits of shown
/// cameras and layer.
wx_result vw_draw_update(vw_draw *draw, const vw_world *world, const vw_show *show,
                         const float mvp[16], int fb_width, int fb_height, wx_error *err);

/// Clears the framebuffer and draws everything shown, seen through `mvp`.
void vw_draw_frame(const vw_draw *draw, const vw_world *world, const vw_show *show,
                   const float mvp[16]);

/// Deletes every GL object and buffer.
void vw_draw_free(vw_draw *draw);

#endif
