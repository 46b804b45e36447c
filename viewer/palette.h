// palette.h: the viewer's colours, as 8-bit sRGB triples so that a screenshot
// holds them exactly (tests/test_viewer.c looks for the camera colours).
//
// Input camera k is drawn in VW_CAMERA_COLORS[k % VW_CAMERA_COLOR_COUNT]: its
// frame rectangle exactly, its depth samples shaded by their normal. The output
// camera is white. Depth samples of a layered camera's deeper layers (docs/
// design.md section 14) are darker: layer k's times VW_LAYER_SHADE[k].
#ifndef VW_PALETTE_H
#define VW_PALETTE_H

#include <stdint.h>

enum { VW_CAMERA_COLOR_COUNT = 8 };

static const uint8_t VW_CAMERA_COLORS[VW_CAMERA_COLOR_COUNT][3] = {
    { 77, 153, 255 },  // blue
    { 77, 217, 77 },   // green
    { 242, 89, 204 },  // magenta
    { 242, 230, 77 },  // yellow
    { 77, 230, 230 },  // cyan
    { 255, 128, 51 },  // orange
    { 179, 128, 255 }, // violet
    { 153, 204, 102 }, // olive
};

/// Depth samples of layer k are drawn in their camera's colour times this
/// (and their normal shading): the first surface in full colour, each deeper
/// one darker, so that front and back surfaces are told apart.
enum { VW_LAYER_SHADE_COUNT = 8 };
static const float VW_LAYER_SHADE[VW_LAYER_SHADE_COUNT] = { 1.0f,  0.7f, 0.5f,  0.4f,
                                                            0.34f, 0.3f, 0.27f, 0.25f };

/// The darkening of layer k (the last entry beyond the table).
static inline float vw_layer_shade(int layer)
{
    int k = layer < VW_LAYER_SHADE_COUNT ? layer : VW_LAYER_SHADE_COUNT - 1;
    return VW_LAYER_SHADE[k > 0 ? k : 0];
}

static const uint8_t VW_OUTPUT_COLOR[3] = { 255, 255, 255 };
static const uint8_t VW_BACKGROUND_COLOR[3] = { 20, 23, 28 };
static const uint8_t VW_BBOX_COLOR[3] = { 110, 110, 125 };
static const uint8_t VW_EMITTER_COLOR[3] = { 255, 160, 160 };

/// Particles: clean (load 0) to dirty (load >= the largest emitter dirt).
static const uint8_t VW_PARTICLE_CLEAN_COLOR[3] = { 190, 225, 255 };
static const uint8_t VW_PARTICLE_DIRTY_COLOR[3] = { 150, 100, 50 };

/// The colour of the shown substance (docs/design.md section 9): particles go
/// from the clean colour to it with their load, depth samples towards it with
/// the amount on their surface. Substance "dirt" (the one substance of a scene
/// without <Substances>) is VW_PARTICLE_DIRTY_COLOR; substance s otherwise
/// VW_SUBSTANCE_COLORS[s] (in xml_scenes/rusty_tank.xml: water blue, rust,
/// moss green).
static const uint8_t VW_SUBSTANCE_COLORS[8][3] = {
    { 25, 75, 215 },   // deep blue
    { 200, 30, 60 },   // crimson
    { 185, 75, 20 },   // rust
    { 50, 130, 30 },   // moss green
    { 40, 40, 40 },    // soot
    { 245, 245, 245 }, // white
    { 110, 40, 160 },  // purple
    { 0, 120, 120 },   // teal
};

/// Depth samples while a derived mask is shown (M, docs/viewer.md): a mask
/// in [0, 1] along VW_MASK_RAMP, 0 dark violet through crimson and orange to
/// 1 pale yellow (stops at 0, 1/4, 1/2, 3/4, 1, linear between), dark enough
/// at 0 to stand out from the background; Curvature (signed) along
/// VW_CURVATURE_RAMP, concave blue at -scale, flat grey at 0, convex red at
/// +scale.
enum { VW_MASK_RAMP_COUNT = 5, VW_CURVATURE_RAMP_COUNT = 3 };
static const uint8_t VW_MASK_RAMP[VW_MASK_RAMP_COUNT][3] = {
    { 48, 18, 86 },    // 0: dark violet
    { 120, 28, 109 },  // plum
    { 190, 55, 82 },   // crimson
    { 240, 120, 40 },  // orange
    { 250, 235, 150 }, // 1: pale yellow
};
static const uint8_t VW_CURVATURE_RAMP[VW_CURVATURE_RAMP_COUNT][3] = {
    { 40, 100, 230 },  // concave (-scale and below)
    { 190, 190, 190 }, // flat (0)
    { 230, 60, 40 },   // convex (+scale and above)
};

/// Hit points by what the particle did: absorbed, bounced, slid.
static const uint8_t VW_HIT_COLORS[3][3] = {
    { 255, 40, 40 },   // absorbed (or settled)
    { 255, 255, 170 }, // bounced
    { 170, 255, 200 }, // slid
};

#endif
