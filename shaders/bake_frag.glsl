// bake_frag.glsl: the four maps of docs/design.md section 2 in one pass (src/raster/bake.c).
//   attachment 0 (RGBA32F): d, world normal x y z (unit, facing the camera; for
//                           a layered camera the mesh's own, out of the solid)
//   attachment 1 (RGBA32F): absorption, bounce, deposit, erosion
//   attachment 2 (RG32F):   initial dirt density per square metre, <Surface> index + 1
// d is computed here from the interpolated position, in float, not read back
// from the depth buffer.
//
// Depth peeling (docs/design.md section 14, raster/bake.c): layer k >= 1 of a
// layered camera keeps only the crossings after layer k-1's (u_previous) at
// each texel, ordered by peel_key: d, plus a tie step for a crossing entering
// a solid, so where solids touch the leaving face comes first and both stay.
// The key is the fragment's depth there; one-layer cameras keep the
// rasterised depth.
#version 450 core

in vec3 v_position;
in vec3 v_normal;
in vec4 v_color;
flat in vec4 v_material_a; // absorption, bounce, dirt, deposit
flat in vec3 v_material_b; // erosion, vertex colour use, surface index + 1

uniform vec4 u_depth_row;  // d = dot(position, xyz) + w
uniform vec3 u_view_dir;   // unit viewing direction (towards larger d)
uniform bool u_outward;    // a layered camera: keep the mesh's normal, never flip it
uniform bool u_peel;       // layer k >= 1: only crossings behind u_previous's d
uniform sampler2D u_previous; // the layer before's attachment 0 (d in .r)
uniform vec2 u_depth_range;   // d of the near and far planes (the depth buffer's 0 and 1)

layout(location = 0) out vec4 o_depth_normal;
layout(location = 1) out vec4 o_impact_dirt;
layout(location = 2) out vec2 o_density_surface;

const float COLORS_IMPACT = 1.0; // wx_color_use
const float COLORS_DIRT = 2.0;

// The peeling key of a crossing at d with outward normal n (above).
float peel_key(float d, vec3 n)
{
    return dot(n, u_view_dir) < 0.0 ? d + 4e-6 * (1.0 + abs(d)) : d;
}

void main()
{
    float d = dot(v_position, u_depth_row.xyz) + u_depth_row.w;
    vec3 n = v_normal;
    float len = length(n);
    if (!(len > 1e-6)) {
        // No usable vertex normal: the triangle's own plane, on its winding's
        // side for a layered camera.
        n = cross(dFdx(v_position), dFdy(v_position));
        len = length(n);
        if (u_outward && !gl_FrontFacing) {
            n = -n;
        }
    }
    n = len > 0.0 ? n / len : -u_view_dir;
    if (!u_outward && dot(n, u_view_dir) > 0.0) {
        n = -n;
    }
    if (u_outward) {
        float key = peel_key(d, n);
        if (u_peel) {
            // 1 mm apart at d = 50: two layers; one surface met twice: one.
            vec4 previous = texelFetch(u_previous, ivec2(gl_FragCoord.xy), 0);
            float before = peel_key(previous.r, previous.gba);
            if (!(key > before + 2e-6 * (1.0 + abs(previous.r)))) {
                discard;
            }
        }
        gl_FragDepth = clamp((key - u_depth_range.x) / (u_depth_range.y - u_depth_range.x), 0.0,
                             1.0);
    } else {
        gl_FragDepth = gl_FragCoord.z;
    }
    o_depth_normal = vec4(d, n);

    vec2 impact = v_material_b.y == COLORS_IMPACT ? v_color.rg : v_material_a.xy;
    vec3 dirt = v_material_b.y == COLORS_DIRT ? v_color.rgb
                                              : vec3(v_material_a.z, v_material_a.w, v_material_b.x);
    o_impact_dirt = vec4(impact, dirt.y, dirt.z);
    o_density_surface = vec2(dirt.x, v_material_b.z);
}
