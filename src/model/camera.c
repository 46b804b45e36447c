// camera.c: orthographic cameras, <View> to matrices and texel addressing
// (docs/design.md section 2). cglm does the vector maths of a <View> (its
// layout and ours: core/matrix.c).
#include "model/camera.h"

#include "core/matrix.h"

#include <cglm/cglm.h>
#include <math.h>
#include <string.h>

static float length3(const float v[3])
{
    return sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

const char *wx_camera_problem(const wx_camera *camera)
{
    for (int k = 0; k < 16; ++k) {
        if (!isfinite(camera->wtc[k]) || !isfinite(camera->ctw[k])) {
            return "its matrices are not finite in single precision";
        }
    }
    if (!wx_matrix_is_orthographic(camera->wtc) || !wx_matrix_is_orthographic(camera->ctw)) {
        const float *m = camera->wtc;
        bool skewed = fabsf(m[3]) + fabsf(m[7]) + fabsf(m[11]) > 1e-6f * fabsf(m[15]);
        return skewed ? "its matrices are not orthographic (the last column must be 0 0 0 1)"
                      : "its matrices mix numbers of very different sizes (the camera lies too "
                        "far from the origin, or its frame is too large, for single precision)";
    }
    double a[9], inv[9];
    double w = camera->wtc[15];
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            a[r * 3 + c] = camera->wtc[r * 4 + c] / w;
        }
    }
    if (!wx_invert3(a, inv)) {
        return "its world-to-map matrix is singular (or its frame is too large or too small "
               "against its depth scale to invert in single precision)";
    }
    return NULL;
}

wx_result wx_camera_from_view(const wx_view *view, wx_camera *out, wx_error *err)
{
    if (!(view->width_ws > 0.0f) || !(view->height_ws > 0.0f)) {
        return wx_fail(err, WX_CAUSE_BAD_CAMERA, "view width and height must be positive");
    }
    if (view->width_px < 1 || view->height_px < 1) {
        return wx_fail(err, WX_CAUSE_BAD_CAMERA, "view resolution must be at least 1 pixel");
    }
    double delta[3], distance2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        delta[k] = (double)view->target[k] - (double)view->eye[k];
        distance2 += delta[k] * delta[k];
    }
    double distance = sqrt(distance2); // in double: |eye - target| may pass FLT_MAX squared
    if (!(distance > 0.0) || !isfinite(distance)) {
        return wx_fail(err, WX_CAUSE_BAD_CAMERA, "view eye and target are the same point");
    }
    vec3 forward = { view->target[0] - view->eye[0], view->target[1] - view->eye[1],
                     view->target[2] - view->eye[2] };
    float norm = glm_vec3_norm(forward);
    if (isfinite(norm) && norm > 0.0f) {
        glm_vec3_scale(forward, 1.0f / norm, forward);
    } else { // beyond float's range squared: the scene check refuses such a camera
        for (int k = 0; k < 3; ++k) {
            forward[k] = (float)(delta[k] / distance);
        }
    }
    vec3 up = { view->up[0], view->up[1], view->up[2] };
    vec3 right;
    glm_vec3_cross(forward, up, right);
    float right_len = glm_vec3_norm(right);
    if (!(right_len > 1e-6f * length3(view->up))) {
        return wx_fail(err, WX_CAUSE_BAD_CAMERA, "view up is parallel to the viewing direction");
    }
    glm_vec3_scale(right, 1.0f / right_len, right);
    vec3 true_up;
    glm_vec3_cross(right, forward, true_up);

    // u = (p-eye).right/W + 1/2, v = (p-eye).up/H + 1/2, d = (p-eye).forward.
    float *m = out->wtc;
    memset(m, 0, sizeof out->wtc);
    for (int i = 0; i < 3; ++i) {
        m[i * 4 + 0] = right[i] / view->width_ws;
        m[i * 4 + 1] = true_up[i] / view->height_ws;
        m[i * 4 + 2] = forward[i];
    }
    vec3 eye = { view->eye[0], view->eye[1], view->eye[2] };
    m[12] = -glm_vec3_dot(eye, right) / view->width_ws + 0.5f;
    m[13] = -glm_vec3_dot(eye, true_up) / view->height_ws + 0.5f;
    m[14] = -glm_vec3_dot(eye, forward);
    m[15] = 1.0f;

    // The inverse is built directly rather than inverted numerically, so that
    // map-to-world is exact for large world coordinates.
    float *c = out->ctw;
    memset(c, 0, sizeof out->ctw);
    for (int i = 0; i < 3; ++i) {
        c[0 * 4 + i] = right[i] * view->width_ws;
        c[1 * 4 + i] = true_up[i] * view->height_ws;
        c[2 * 4 + i] = forward[i];
        c[12 + i] = view->eye[i] - 0.5f * right[i] * view->width_ws -
                    0.5f * true_up[i] * view->height_ws;
    }
    c[15] = 1.0f;
    out->width = view->width_px;
    out->height = view->height_px;
    return WX_OK;
}

void wx_camera_world_to_map(const wx_camera *cam, const float p[3], float uvd[3])
{
    if (!wx_transform_point(cam->wtc, p, uvd)) {
        uvd[0] = uvd[1] = uvd[2] = NAN;
    }
}

void wx_camera_map_to_world(const wx_camera *cam, const float uvd[3], float p[3])
{
    if (!wx_transform_point(cam->ctw, uvd, p)) {
        p[0] = p[1] = p[2] = NAN;
    }
}

bool wx_map_contains(float u, float v)
{
    return u >= 0.0f && u < 1.0f && v > 0.0f && v <= 1.0f;
}

bool wx_map_texel(int width, int height, float u, float v, int *i, int *j)
{
    if (!wx_map_contains(u, v)) {
        return false;
    }
    int col = (int)floorf(u * (float)width);
    int row = (int)floorf((1.0f - v) * (float)height);
    // u < 1 and v > 0 can still round to W or H in float: clamp to the last texel.
    *i = col < width ? col : width - 1;
    *j = row < height ? row : height - 1;
    return true;
}

void wx_map_texel_center(int width, int height, int i, int j, float *u, float *v)
{
    *u = ((float)i + 0.5f) / (float)width;
    *v = 1.0f - ((float)j + 0.5f) / (float)height;
}

void wx_camera_view_dir(const wx_camera *cam, float dir[3])
{
    // d grows along the viewing direction: the gradient of d in world space is
    // the column of wtc that produces d, rows 0..2.
    float g[3] = { cam->wtc[2], cam->wtc[6], cam->wtc[10] };
    float len = length3(g);
    for (int i = 0; i < 3; ++i) {
        dir[i] = len > 0.0f ? g[i] / len : 0.0f;
    }
}

void wx_camera_frame_size(const wx_camera *cam, float *width_ws, float *height_ws)
{
    // A step of 1 in u moves the world point by the first row of ctw.
    *width_ws = length3(&cam->ctw[0]);
    *height_ws = length3(&cam->ctw[4]);
}
