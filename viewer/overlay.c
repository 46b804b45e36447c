// overlay.c: text over the 3D view (overlay.h). The font is a 5x7 pixel font
// drawn for this viewer, one glyph per printable ASCII character, packed into
// a one-row texture atlas; a solid glyph at the end fills background boxes.
#include "overlay.h"

#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

enum {
    GLYPH_W = 5,
    GLYPH_H = 7,
    FIRST_CHAR = 32,
    CHAR_COUNT = 95,         // ' ' .. '~'
    SOLID = CHAR_COUNT,      // the block glyph after them
    ATLAS_W = (CHAR_COUNT + 1) * (GLYPH_W + 1),
    ATLAS_H = GLYPH_H,
    FLOATS_PER_VERTEX = 8,
};

// Rows top to bottom, '#' set. Glyph k is character FIRST_CHAR + k. The
// letters with a descender (DESCENDERS) are drawn two rows lower: their first
// five rows sit on the x-height, the last two below the line.
static const char *const FONT[CHAR_COUNT] = {
    "....." "....." "....." "....." "....." "....." ".....", // space
    "..#.." "..#.." "..#.." "..#.." "..#.." "....." "..#..", // !
    ".#.#." ".#.#." "....." "....." "....." "....." ".....", // "
    ".#.#." ".#.#." "#####" ".#.#." "#####" ".#.#." ".#.#.", // #
    "..#.." ".####" "#.#.." ".###." "..#.#" "####." "..#..", // $
    "##..." "##..#" "...#." "..#.." ".#..." "#..##" "...##", // %
    ".##.." "#..#." "#.#.." ".#..." "#.#.#" "#..#." ".##.#", // &
    "..#.." "..#.." "....." "....." "....." "....." ".....", // '
    "...#." "..#.." ".#..." ".#..." ".#..." "..#.." "...#.", // (
    ".#..." "..#.." "...#." "...#." "...#." "..#.." ".#...", // )
    "....." "..#.." "#.#.#" ".###." "#.#.#" "..#.." ".....", // *
    "....." "..#.." "..#.." "#####" "..#.." "..#.." ".....", // +
    "....." "....." "....." "....." ".##.." "..#.." ".#...", // ,
    "....." "....." "....." "#####" "....." "....." ".....", // -
    "....." "....." "....." "....." "....." ".##.." ".##..", // .
    "....." "....#" "...#." "..#.." ".#..." "#...." ".....", // /
    ".###." "#...#" "#..##" "#.#.#" "##..#" "#...#" ".###.", // 0
    "..#.." ".##.." "..#.." "..#.." "..#.." "..#.." ".###.", // 1
    ".###." "#...#" "....#" "...#." "..#.." ".#..." "#####", // 2
    "#####" "...#." "..#.." "...#." "....#" "#...#" ".###.", // 3
    "...#." "..##." ".#.#." "#..#." "#####" "...#." "...#.", // 4
    "#####" "#...." "####." "....#" "....#" "#...#" ".###.", // 5
    "..##." ".#..." "#...." "####." "#...#" "#...#" ".###.", // 6
    "#####" "....#" "...#." "..#.." ".#..." ".#..." ".#...", // 7
    ".###." "#...#" "#...#" ".###." "#...#" "#...#" ".###.", // 8
    ".###." "#...#" "#...#" ".####" "....#" "...#." ".##..", // 9
    "....." ".##.." ".##.." "....." ".##.." ".##.." ".....", // :
    "....." ".##.." ".##.." "....." ".##.." "..#.." ".#...", // ;
    "...#." "..#.." ".#..." "#...." ".#..." "..#.." "...#.", // <
    "....." "....." "#####" "....." "#####" "....." ".....", // =
    ".#..." "..#.." "...#." "....#" "...#." "..#.." ".#...", // >
    ".###." "#...#" "....#" "...#." "..#.." "....." "..#..", // ?
    ".###." "#...#" "....#" ".##.#" "#.#.#" "#.#.#" ".###.", // @
    ".###." "#...#" "#...#" "#####" "#...#" "#...#" "#...#", // A
    "####." "#...#" "#...#" "####." "#...#" "#...#" "####.", // B
    ".###." "#...#" "#...." "#...." "#...." "#...#" ".###.", // C
    "###.." "#..#." "#...#" "#...#" "#...#" "#..#." "###..", // D
    "#####" "#...." "#...." "####." "#...." "#...." "#####", // E
    "#####" "#...." "#...." "####." "#...." "#...." "#....", // F
    ".###." "#...#" "#...." "#.###" "#...#" "#...#" ".####", // G
    "#...#" "#...#" "#...#" "#####" "#...#" "#...#" "#...#", // H
    ".###." "..#.." "..#.." "..#.." "..#.." "..#.." ".###.", // I
    "..###" "...#." "...#." "...#." "...#." "#..#." ".##..", // J
    "#...#" "#..#." "#.#.." "##..." "#.#.." "#..#." "#...#", // K
    "#...." "#...." "#...." "#...." "#...." "#...." "#####", // L
    "#...#" "##.##" "#.#.#" "#.#.#" "#...#" "#...#" "#...#", // M
    "#...#" "#...#" "##..#" "#.#.#" "#..##" "#...#" "#...#", // N
    ".###." "#...#" "#...#" "#...#" "#...#" "#...#" ".###.", // O
    "####." "#...#" "#...#" "####." "#...." "#...." "#....", // P
    ".###." "#...#" "#...#" "#...#" "#.#.#" "#..#." ".##.#", // Q
    "####." "#...#" "#...#" "####." "#.#.." "#..#." "#...#", // R
    ".####" "#...." "#...." ".###." "....#" "....#" "####.", // S
    "#####" "..#.." "..#.." "..#.." "..#.." "..#.." "..#..", // T
    "#...#" "#...#" "#...#" "#...#" "#...#" "#...#" ".###.", // U
    "#...#" "#...#" "#...#" "#...#" "#...#" ".#.#." "..#..", // V
    "#...#" "#...#" "#...#" "#.#.#" "#.#.#" "#.#.#" ".#.#.", // W
    "#...#" "#...#" ".#.#." "..#.." ".#.#." "#...#" "#...#", // X
    "#...#" "#...#" ".#.#." "..#.." "..#.." "..#.." "..#..", // Y
    "#####" "....#" "...#." "..#.." ".#..." "#...." "#####", // Z
    ".###." ".#..." ".#..." ".#..." ".#..." ".#..." ".###.", // [
    "....." "#...." ".#..." "..#.." "...#." "....#" ".....", // backslash
    ".###." "...#." "...#." "...#." "...#." "...#." ".###.", // ]
    "..#.." ".#.#." "#...#" "....." "....." "....." ".....", // ^
    "....." "....." "....." "....." "....." "....." "#####", // _
    ".#..." "..#.." "....." "....." "....." "....." ".....", // `
    "....." "....." ".###." "....#" ".####" "#...#" ".####", // a
    "#...." "#...." "#.##." "##..#" "#...#" "#...#" "####.", // b
    "....." "....." ".###." "#...." "#...." "#...#" ".###.", // c
    "....#" "....#" ".##.#" "#..##" "#...#" "#...#" ".####", // d
    "....." "....." ".###." "#...#" "#####" "#...." ".###.", // e
    "..##." ".#..#" ".#..." "###.." ".#..." ".#..." ".#...", // f
    ".####" "#...#" "#...#" "#...#" ".####" "....#" ".###.", // g
    "#...." "#...." "#.##." "##..#" "#...#" "#...#" "#...#", // h
    "..#.." "....." ".##.." "..#.." "..#.." "..#.." ".###.", // i
    "...#." "....." "..##." "...#." "...#." "#..#." ".##..", // j
    "#...." "#...." "#..#." "#.#.." "##..." "#.#.." "#..#.", // k
    ".##.." "..#.." "..#.." "..#.." "..#.." "..#.." ".###.", // l
    "....." "....." "##.#." "#.#.#" "#.#.#" "#...#" "#...#", // m
    "....." "....." "#.##." "##..#" "#...#" "#...#" "#...#", // n
    "....." "....." ".###." "#...#" "#...#" "#...#" ".###.", // o
    "####." "#...#" "#...#" "#...#" "####." "#...." "#....", // p
    ".####" "#...#" "#...#" "#...#" ".####" "....#" "....#", // q
    "....." "....." "#.##." "##..#" "#...." "#...." "#....", // r
    "....." "....." ".###." "#...." ".###." "....#" "####.", // s
    ".#..." ".#..." "###.." ".#..." ".#..." ".#..#" "..##.", // t
    "....." "....." "#...#" "#...#" "#...#" "#..##" ".##.#", // u
    "....." "....." "#...#" "#...#" "#...#" ".#.#." "..#..", // v
    "....." "....." "#...#" "#...#" "#.#.#" "#.#.#" ".#.#.", // w
    "....." "....." "#...#" ".#.#." "..#.." ".#.#." "#...#", // x
    "#...#" "#...#" "#...#" "#...#" ".####" "....#" ".###.", // y
    "....." "....." "#####" "...#." "..#.." ".#..." "#####", // z
    "...#." "..#.." "..#.." ".#..." "..#.." "..#.." "...#.", // {
    "..#.." "..#.." "..#.." "..#.." "..#.." "..#.." "..#..", // |
    ".#..." "..#.." "..#.." "...#." "..#.." "..#.." ".#...", // }
    "....." "....." ".#..." "#.#.#" "...#." "....." ".....", // ~
};

static const char DESCENDERS[] = "gpqy";

static const char *const OVERLAY_VS =
    "#version 330 core\n"
    "layout(location = 0) in vec2 position;\n" // pixels from the top-left corner
    "layout(location = 1) in vec2 uv;\n"
    "layout(location = 2) in vec4 color;\n"
    "uniform vec2 viewport;\n"
    "out vec2 v_uv;\n"
    "out vec4 v_color;\n"
    "void main() {\n"
    "    vec2 ndc = 2.0 * position / viewport - 1.0;\n"
    "    gl_Position = vec4(ndc.x, -ndc.y, 0.0, 1.0);\n"
    "    v_uv = uv;\n"
    "    v_color = color;\n"
    "}\n";

static const char *const OVERLAY_FS =
    "#version 330 core\n"
    "in vec2 v_uv;\n"
    "in vec4 v_color;\n"
    "uniform sampler2D font;\n"
    "out vec4 frag;\n"
    "void main() { frag = vec4(v_color.rgb, v_color.a * texture(font, v_uv).r); }\n";

wx_result vw_overlay_init(vw_overlay *overlay, wx_error *err)
{
    memset(overlay, 0, sizeof *overlay);
    overlay->scale = 1;
    wx_result r = vw_gl_program("overlay", OVERLAY_VS, OVERLAY_FS, &overlay->program, err);
    if (r != WX_OK) {
        return r;
    }
    overlay->u_viewport = glGetUniformLocation(overlay->program, "viewport");
    overlay->u_font = glGetUniformLocation(overlay->program, "font");

    static uint8_t atlas[ATLAS_H][ATLAS_W];
    memset(atlas, 0, sizeof atlas);
    for (int g = 0; g <= CHAR_COUNT; ++g) {
        for (int y = 0; y < GLYPH_H; ++y) {
            for (int x = 0; x < GLYPH_W; ++x) {
                bool on = g == SOLID || FONT[g][y * GLYPH_W + x] == '#';
                atlas[y][g * (GLYPH_W + 1) + x] = on ? 255 : 0;
            }
        }
        if (g == SOLID) { // the block also covers its spacing column
            for (int y = 0; y < GLYPH_H; ++y) {
                atlas[y][g * (GLYPH_W + 1) + GLYPH_W] = 255;
            }
        }
    }
    glGenTextures(1, &overlay->texture);
    glBindTexture(GL_TEXTURE_2D, overlay->texture);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_R8, ATLAS_W, ATLAS_H, 0, GL_RED, GL_UNSIGNED_BYTE, atlas);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glBindTexture(GL_TEXTURE_2D, 0);

    glGenVertexArrays(1, &overlay->vao);
    glGenBuffers(1, &overlay->vbo);
    glBindVertexArray(overlay->vao);
    glBindBuffer(GL_ARRAY_BUFFER, overlay->vbo);
    GLsizei stride = FLOATS_PER_VERTEX * sizeof(float);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, stride, (const void *)0);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, stride, (const void *)(2 * sizeof(float)));
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(2, 4, GL_FLOAT, GL_FALSE, stride, (const void *)(4 * sizeof(float)));
    glBindVertexArray(0);
    return WX_OK;
}

void vw_overlay_begin(vw_overlay *overlay, int scale)
{
    overlay->vertex_count = 0;
    overlay->scale = scale > 0 ? scale : 1;
}

// A rectangle of the atlas [u0,u1] x [v0,v1] (texels) onto pixels [x,x+w] x [y,y+h].
static void quad(vw_overlay *overlay, float x, float y, float w, float h, float u0, float v0,
                 float u1, float v1, const float rgba[4])
{
    if (overlay->vertex_count + 6 > overlay->vertex_capacity) {
        int capacity = overlay->vertex_capacity > 0 ? 2 * overlay->vertex_capacity : 6 * 1024;
        float *bigger = realloc(overlay->vertices,
                                (size_t)capacity * FLOATS_PER_VERTEX * sizeof *bigger);
        if (bigger == NULL) {
            return; // text is a convenience: drop it rather than fail the frame
        }
        overlay->vertices = bigger;
        overlay->vertex_capacity = capacity;
    }
    const float corners[6][4] = {
        { x, y, u0, v0 },         { x + w, y, u1, v0 }, { x + w, y + h, u1, v1 },
        { x, y, u0, v0 },         { x + w, y + h, u1, v1 }, { x, y + h, u0, v1 },
    };
    for (int k = 0; k < 6; ++k) {
        float *v = &overlay->vertices[(size_t)overlay->vertex_count++ * FLOATS_PER_VERTEX];
        v[0] = corners[k][0];
        v[1] = corners[k][1];
        v[2] = corners[k][2] / (float)ATLAS_W;
        v[3] = corners[k][3] / (float)ATLAS_H;
        memcpy(&v[4], rgba, 4 * sizeof(float));
    }
}

void vw_overlay_box(vw_overlay *overlay, float x, float y, float w, float h, const float rgba[4])
{
    // Sample the middle of the solid glyph: every texel there is set.
    float u = (float)(SOLID * (GLYPH_W + 1)) + 2.5f, v = 3.5f;
    quad(overlay, x, y, w, h, u, v, u, v, rgba);
}

void vw_overlay_text(vw_overlay *overlay, float x, float y, const float rgba[4], const char *text)
{
    float s = (float)overlay->scale;
    for (const char *c = text; *c != '\0'; ++c, x += VW_CELL_W * s) {
        int g = (unsigned char)*c;
        if (g == ' ') {
            continue;
        }
        g = g > FIRST_CHAR && g < FIRST_CHAR + CHAR_COUNT ? g - FIRST_CHAR : '?' - FIRST_CHAR;
        float u0 = (float)(g * (GLYPH_W + 1));
        float top = strchr(DESCENDERS, *c) != NULL ? y + 3.0f * s : y + s;
        quad(overlay, x, top, GLYPH_W * s, GLYPH_H * s, u0, 0.0f, u0 + GLYPH_W, (float)GLYPH_H,
             rgba);
    }
}

void vw_overlay_end(vw_overlay *overlay, int fb_width, int fb_height)
{
    if (overlay->vertex_count == 0) {
        return;
    }
    glDisable(GL_DEPTH_TEST);
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glUseProgram(overlay->program);
    glUniform2f(overlay->u_viewport, (float)fb_width, (float)fb_height);
    glUniform1i(overlay->u_font, 0);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, overlay->texture);
    glBindVertexArray(overlay->vao);
    glBindBuffer(GL_ARRAY_BUFFER, overlay->vbo);
    glBufferData(GL_ARRAY_BUFFER,
                 (GLsizeiptr)((size_t)overlay->vertex_count * FLOATS_PER_VERTEX * sizeof(float)),
                 overlay->vertices, GL_STREAM_DRAW);
    glDrawArrays(GL_TRIANGLES, 0, overlay->vertex_count);
    glBindVertexArray(0);
    glBindTexture(GL_TEXTURE_2D, 0);
    glUseProgram(0);
    glDisable(GL_BLEND);
    glEnable(GL_DEPTH_TEST);
}

void vw_overlay_free(vw_overlay *overlay)
{
    if (overlay->program != 0) {
        glDeleteProgram(overlay->program);
    }
    glDeleteTextures(1, &overlay->texture);
    glDeleteVertexArrays(1, &overlay->vao);
    glDeleteBuffers(1, &overlay->vbo);
    free(overlay->vertices);
    memset(overlay, 0, sizeof *overlay);
}
