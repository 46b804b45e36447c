// camera.c: orthographic cameras, matrices and texel addressing (DESIGN section 2).
//
// cglm stores a mat4 as four columns and multiplies column vectors. Our matrices
// are row-major and multiply row vectors; the two layouts are the same 16 floats
// read as transposes of one another, so [x y z 1] * M (row vector, row-major) is
// exactly glm_mat4_mulv(M, v) on the same memory, and inverses carry over.
#include "camera.h"

#include <cglm/cglm.h>
#include <math.h>
#include <string.h>

static void to_mat4(const float m[16], mat4 out)
{
    memcpy(out, m, sizeof(float) * 16);
}

static float length3(const float v[3])
{
    return sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

bool wx_matrix_is_orthographic(const float m[16])
{
    double scale = 0.0;
    for (int k = 0; k < 16; ++k) {
        if (!isfinite(m[k])) {
            return false;
        }
        scale = fmax(scale, fabs((double)m[k]));
    }
    double w = m[15];
    double skew = fabs((double)m[3]) + fabs((double)m[7]) + fabs((double)m[11]);
    double diagonal = fabs((double)m[0]) + fabs((double)m[5]) + fabs((double)m[10]) + fabs(w);
    bool each_small = fabs((double)m[3]) <= 1e-6 * diagonal &&
                      fabs((double)m[7]) <= 1e-6 * diagonal &&
                      fabs((double)m[11]) <= 1e-6 * diagonal;
    return fabs(w) > 1e-12 * scale && skew <= 1e-6 * scale && each_small;
}

bool wx_invert3(const double a[9], double inv[9])
{
    double c00 = a[4] * a[8] - a[5] * a[7];
    double c01 = a[5] * a[6] - a[3] * a[8];
    double c02 = a[3] * a[7] - a[4] * a[6];
    double det = a[0] * c00 + a[1] * c01 + a[2] * c02;
    double scale = 0.0;
    for (int i = 0; i < 9; ++i) {
        scale = fmax(scale, fabs(a[i]));
    }
    if (!(fabs(det) > 1e-12 * scale * scale * scale) || !isfinite(det)) {
        return false;
    }
    double r = 1.0 / det;
    inv[0] = c00 * r;
    inv[1] = (a[2] * a[7] - a[1] * a[8]) * r;
    inv[2] = (a[1] * a[5] - a[2] * a[4]) * r;
    inv[3] = c01 * r;
    inv[4] = (a[0] * a[8] - a[2] * a[6]) * r;
    inv[5] = (a[2] * a[3] - a[0] * a[5]) * r;
    inv[6] = c02 * r;
    inv[7] = (a[1] * a[6] - a[0] * a[7]) * r;
    inv[8] = (a[0] * a[4] - a[1] * a[3]) * r;
    return true;
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
        return wx_error_set(err, WX_BAD_INPUT, "view width and height must be positive");
    }
    if (view->width_px < 1 || view->height_px < 1) {
        return wx_error_set(err, WX_BAD_INPUT, "view resolution must be at least 1 pixel");
    }
    double delta[3], distance2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        delta[k] = (double)view->target[k] - (double)view->eye[k];
        distance2 += delta[k] * delta[k];
    }
    double distance = sqrt(distance2); // in double: |eye - target| may pass FLT_MAX squared
    if (!(distance > 0.0) || !isfinite(distance)) {
        return wx_error_set(err, WX_BAD_INPUT, "view eye and target are the same point");
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
        return wx_error_set(err, WX_BAD_INPUT, "view up is parallel to the viewing direction");
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

bool wx_camera_invert(const float wtc[16], float ctw[16])
{
    mat4 m;
    to_mat4(wtc, m);
    float det = glm_mat4_det(m);
    float scale = 0.0f;
    for (int i = 0; i < 16; ++i) {
        if (!isfinite(wtc[i])) {
            return false;
        }
        scale = fmaxf(scale, fabsf(wtc[i]));
    }
    // Singular when the determinant vanishes relative to the entries' scale.
    if (!(fabsf(det) > 1e-12f * scale * scale * scale * scale) || !isfinite(det)) {
        return false;
    }
    mat4 inv;
    glm_mat4_inv_precise(m, inv);
    memcpy(ctw, inv, sizeof(float) * 16);
    for (int i = 0; i < 16; ++i) {
        if (!isfinite(ctw[i])) {
            return false;
        }
    }
    return true;
}

float wx_camera_inverse_error(const float wtc[16], const float ctw[16])
{
    // Row-vector product: (wtc * ctw)[r][c] = sum_k wtc[r][k] * ctw[k][c]. Each
    // term is weighed by the size of what it sums, so the measure is relative.
    float worst = 0.0f;
    for (int r = 0; r < 4; ++r) {
        for (int col = 0; col < 4; ++col) {
            double sum = 0.0, magnitude = 0.0;
            for (int k = 0; k < 4; ++k) {
                double term = (double)wtc[r * 4 + k] * (double)ctw[k * 4 + col];
                sum += term;
                magnitude += fabs(term);
            }
            double target = r == col ? 1.0 : 0.0;
            double error = fabs(sum - target) / (magnitude > 1.0 ? magnitude : 1.0);
            if (!(error <= worst)) {
                worst = (float)error;
            }
        }
    }
    return worst;
}

bool wx_transform_point(const float m[16], const float p[3], float out[3])
{
    double r[4];
    for (int col = 0; col < 4; ++col) {
        r[col] = (double)p[0] * m[col] + (double)p[1] * m[4 + col] + (double)p[2] * m[8 + col] +
                 (double)m[12 + col];
    }
    if (r[3] == 0.0 || !isfinite(r[3])) {
        return false;
    }
    for (int i = 0; i < 3; ++i) {
        out[i] = (float)(r[i] / r[3]);
    }
    return true;
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
