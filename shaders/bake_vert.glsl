// bake_vert.glsl: orthographic projection of a mesh into one camera's map
// (src/raster/bake.c). Positions are relative to the mesh's origin; u_wtc is the
// camera's WTCMatrix with that origin folded into its translation row. A
// row-major matrix for row vectors, uploaded as it is, reads in GLSL as the
// same matrix for column vectors, so u_wtc * p gives (u, v, d, 1).
//
// Every vertex belongs to triangles of one material (src/mesh.h), so the
// material's properties are looked up here, once per vertex, from a buffer
// texture of two RGBA texels per material: (absorption, bounce, dirt, deposit),
// (erosion, vertex colour use, global surface index + 1, 0).
#version 450 core

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_color;
layout(location = 3) in uint a_material;

uniform mat4 u_wtc;
uniform vec2 u_depth_range; // d of the near and far planes
uniform samplerBuffer u_material_props;

out vec3 v_position;
out vec3 v_normal;
out vec4 v_color;
flat out vec4 v_material_a; // absorption, bounce, dirt, deposit
flat out vec3 v_material_b; // erosion, vertex colour use, surface index + 1

void main()
{
    vec4 uvd = u_wtc * vec4(a_position, 1.0);
    // clip x, y = 2u-1, 2v-1; z maps [near, far] of d onto [-1, 1].
    float z = 2.0 * (uvd.z - u_depth_range.x) / (u_depth_range.y - u_depth_range.x) - 1.0;
    gl_Position = vec4(2.0 * uvd.x - 1.0, 2.0 * uvd.y - 1.0, z, 1.0);
    v_position = a_position;
    v_normal = a_normal;
    v_color = a_color;
    int m = int(a_material);
    v_material_a = texelFetch(u_material_props, 2 * m);
    v_material_b = texelFetch(u_material_props, 2 * m + 1).xyz;
}
