// overlay.h: text drawn over the 3D view (status, messages, key help) with a
// built-in 5x7 pixel font, so the viewer needs no font files.
#ifndef VW_OVERLAY_H
#define VW_OVERLAY_H

#include "gl.h"

/// One character cell at scale 1, in pixels (glyph 5 x 7 plus spacing).
enum { VW_CELL_W = 6, VW_CELL_H = 10 };

typedef struct vw_overlay {
    GLuint program, vao, vbo, texture;
    GLint u_viewport, u_font;
    float *vertices; ///< x, y, u, v, r, g, b, a per vertex
    int vertex_count;
    int vertex_capacity;
    int scale;       ///< pixels per font pixel
} vw_overlay;

/// Creates the font texture, the shader and the buffers.
wx_result vw_overlay_init(vw_overlay *overlay, wx_error *err);

/// Starts a new frame of text at the given pixel scale (1, 2, ...).
void vw_overlay_begin(vw_overlay *overlay, int scale);

/// A filled rectangle, pixels from the top-left corner of the window.
void vw_overlay_box(vw_overlay *overlay, float x, float y, float w, float h, const float rgba[4]);

/// One line of text with its top-left corner at (x, y); characters outside
/// printable ASCII show as '?'.
void vw_overlay_text(vw_overlay *overlay, float x, float y, const float rgba[4], const char *text);

/// Draws what was added since vw_overlay_begin over the framebuffer.
void vw_overlay_end(vw_overlay *overlay, int fb_width, int fb_height);

void vw_overlay_free(vw_overlay *overlay);

#endif
