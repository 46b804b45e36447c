// view.c: the orbit camera (see view.h).
#include "view.h"

#include <math.h>
#include <string.h>

static const float PI = 3.14159265358979f;

void vw_mat4_mul(const float a[16], const float b[16], float out[16])
{
    float r[16];
    for (int col = 0; col < 4; ++col) {
        for (int row = 0; row < 4; ++row) {
            float s = 0.0f;
            for (int k = 0; k < 4; ++k) {
                s += a[k * 4 + row] * b[col * 4 + k];
            }
            r[col * 4 + row] = s;
        }
    }
    memcpy(out, r, sizeof r);
}

static void normalize3(float v[3])
{
    float len = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (len > 0.0f) {
        v[0] /= len;
        v[1] /= len;
        v[2] /= len;
    }
}

static void cross3(const float a[3], const float b[3], float out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

// Unit vectors of the eye: forward (towards the target), right and up.
static void orbit_basis(const vw_orbit *orbit, float fwd[3], float right[3], float up[3])
{
    float cp = cosf(orbit->pitch), sp = sinf(orbit->pitch);
    float cy = cosf(orbit->yaw), sy = sinf(orbit->yaw);
    // yaw 0, pitch 0: looking along -Z.
    fwd[0] = -sy * cp;
    fwd[1] = -sp;
    fwd[2] = -cy * cp;
    right[0] = cy;
    right[1] = 0.0f;
    right[2] = -sy;
    cross3(right, fwd, up);
    normalize3(up);
}

void vw_orbit_eye(const vw_orbit *orbit, float eye[3])
{
    float fwd[3], right[3], up[3];
    orbit_basis(orbit, fwd, right, up);
    for (int k = 0; k < 3; ++k) {
        eye[k] = orbit->target[k] - orbit->distance * fwd[k];
    }
}

void vw_orbit_frame(vw_orbit *orbit, const float lo[3], const float hi[3], float aspect)
{
    float half[3];
    for (int k = 0; k < 3; ++k) {
        orbit->target[k] = 0.5f * (lo[k] + hi[k]);
        half[k] = 0.5f * (hi[k] - lo[k]);
    }
    float radius = sqrtf(half[0] * half[0] + half[1] * half[1] + half[2] * half[2]);
    if (!(radius > 1e-6f)) {
        radius = 1.0f;
    }
    orbit->fov_y = 45.0f * PI / 180.0f;
    orbit->yaw = 35.0f * PI / 180.0f;
    orbit->pitch = 25.0f * PI / 180.0f;
    // The bounding sphere fits the narrower of the two fields of view.
    float half_fov = 0.5f * orbit->fov_y;
    if (aspect < 1.0f) {
        half_fov = atanf(tanf(half_fov) * aspect);
    }
    orbit->distance = 1.05f * radius / sinf(half_fov);
    orbit->scene_radius = radius;
}

void vw_orbit_matrix(const vw_orbit *orbit, float aspect, float mvp[16])
{
    float fwd[3], right[3], up[3], eye[3];
    orbit_basis(orbit, fwd, right, up);
    vw_orbit_eye(orbit, eye);
    float view[16] = {
        right[0], up[0], -fwd[0], 0.0f,
        right[1], up[1], -fwd[1], 0.0f,
        right[2], up[2], -fwd[2], 0.0f,
        0.0f,     0.0f,  0.0f,    1.0f,
    };
    view[12] = -(right[0] * eye[0] + right[1] * eye[1] + right[2] * eye[2]);
    view[13] = -(up[0] * eye[0] + up[1] * eye[1] + up[2] * eye[2]);
    view[14] = fwd[0] * eye[0] + fwd[1] * eye[1] + fwd[2] * eye[2];

    // Clip planes around what is drawn, wherever the eye is.
    float reach = orbit->distance + 4.0f * orbit->scene_radius;
    float near_z = fmaxf(1e-3f * reach, orbit->distance - 4.0f * orbit->scene_radius);
    near_z = fminf(near_z, 0.05f * orbit->distance);
    float far_z = reach;
    float f = 1.0f / tanf(0.5f * orbit->fov_y);
    if (!(aspect > 0.0f)) {
        aspect = 1.0f;
    }
    float proj[16] = { 0 };
    proj[0] = f / aspect;
    proj[5] = f;
    proj[10] = (far_z + near_z) / (near_z - far_z);
    proj[11] = -1.0f;
    proj[14] = 2.0f * far_z * near_z / (near_z - far_z);
    vw_mat4_mul(proj, view, mvp);
}

void vw_orbit_rotate(vw_orbit *orbit, float dx, float dy)
{
    const float per_pixel = 0.005f;
    orbit->yaw -= dx * per_pixel;
    orbit->pitch += dy * per_pixel;
    const float limit = 89.0f * PI / 180.0f;
    orbit->pitch = fmaxf(-limit, fminf(limit, orbit->pitch));
    orbit->yaw = fmodf(orbit->yaw, 2.0f * PI);
}

void vw_orbit_pan(vw_orbit *orbit, float dx, float dy, float window_height)
{
    float fwd[3], right[3], up[3];
    orbit_basis(orbit, fwd, right, up);
    // World units per pixel at the target's distance.
    float scale = 2.0f * orbit->distance * tanf(0.5f * orbit->fov_y) /
                  (window_height > 1.0f ? window_height : 1.0f);
    for (int k = 0; k < 3; ++k) {
        orbit->target[k] += (-dx * right[k] + dy * up[k]) * scale;
    }
}

void vw_orbit_zoom(vw_orbit *orbit, float steps)
{
    orbit->distance *= powf(0.85f, steps);
    float lo = 1e-3f * orbit->scene_radius, hi = 100.0f * orbit->scene_radius;
    orbit->distance = fmaxf(lo, fminf(hi, orbit->distance));
}
