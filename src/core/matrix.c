// matrix.c: 4x4 row-vector matrices (matrix.h). cglm stores a mat4 as four
// columns and multiplies column vectors; our matrices are row-major and multiply
// row vectors: the two layouts are the same 16 floats read as transposes of one
// another, so [x y z 1] * M is glm_mat4_mulv(M, v) on the same memory and
// inverses carry over.
#include "core/matrix.h"

#include <cglm/cglm.h>
#include <math.h>
#include <string.h>

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

bool wx_matrix_to_affine(const float m[16], double out[16])
{
    if (!wx_matrix_is_orthographic(m)) {
        return false;
    }
    double w = m[15];
    for (int k = 0; k < 16; ++k) {
        out[k] = (double)m[k] / w;
    }
    out[3] = out[7] = out[11] = 0.0;
    out[15] = 1.0;
    return true;
}

void wx_matrix_mul(const double a[16], const double b[16], double out[16])
{
    // (p * a) * b = p * (a * b): (a*b)[r][c] = sum_k a[r][k] * b[k][c].
    for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) {
            double sum = 0.0;
            for (int k = 0; k < 4; ++k) {
                sum += a[r * 4 + k] * b[k * 4 + c];
            }
            out[r * 4 + c] = sum;
        }
    }
}

void wx_matrix_row3(const double m[16], int r, double out[3])
{
    out[0] = m[r * 4 + 0];
    out[1] = m[r * 4 + 1];
    out[2] = m[r * 4 + 2];
}

void wx_matrix_fold_origin(const float m[16], const double origin[3], double out[16])
{
    for (int k = 0; k < 16; ++k) {
        out[k] = m[k];
    }
    for (int col = 0; col < 4; ++col) {
        for (int j = 0; j < 3; ++j) {
            out[12 + col] += origin[j] * (double)m[4 * j + col];
        }
    }
}

void wx_matrix_apply_affine(const float m[16], const double p[3], double out[3])
{
    for (int k = 0; k < 3; ++k) {
        out[k] = p[0] * m[k] + p[1] * m[4 + k] + p[2] * m[8 + k] + m[12 + k];
    }
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

static void to_mat4(const float m[16], mat4 out)
{
    memcpy(out, m, sizeof(float) * 16);
}

bool wx_matrix_invert(const float m[16], float inv[16])
{
    mat4 a;
    to_mat4(m, a);
    float det = glm_mat4_det(a);
    float scale = 0.0f;
    for (int i = 0; i < 16; ++i) {
        if (!isfinite(m[i])) {
            return false;
        }
        scale = fmaxf(scale, fabsf(m[i]));
    }
    // Singular when the determinant vanishes relative to the entries' scale.
    if (!(fabsf(det) > 1e-12f * scale * scale * scale * scale) || !isfinite(det)) {
        return false;
    }
    mat4 b;
    glm_mat4_inv_precise(a, b);
    memcpy(inv, b, sizeof(float) * 16);
    for (int i = 0; i < 16; ++i) {
        if (!isfinite(inv[i])) {
            return false;
        }
    }
    return true;
}

float wx_matrix_inverse_error(const float a[16], const float b[16])
{
    // Row-vector product: (a * b)[r][c] = sum_k a[r][k] * b[k][c]. Each term is
    // weighed by the size of what it sums, so the measure is relative.
    float worst = 0.0f;
    for (int r = 0; r < 4; ++r) {
        for (int col = 0; col < 4; ++col) {
            double sum = 0.0, magnitude = 0.0;
            for (int k = 0; k < 4; ++k) {
                double term = (double)a[r * 4 + k] * (double)b[k * 4 + col];
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

double wx_dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

double wx_length3(const double a[3])
{
    return sqrt(wx_dot3(a, a));
}

void wx_perpendicular_basis(const double d[3], double e1[3], double e2[3])
{
    double u[3] = { 0.0, 0.0, 0.0 };
    u[fabs(d[0]) < 0.9 ? 0 : 1] = 1.0; // any vector not along d
    e1[0] = d[1] * u[2] - d[2] * u[1];
    e1[1] = d[2] * u[0] - d[0] * u[2];
    e1[2] = d[0] * u[1] - d[1] * u[0];
    double l1 = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    for (int k = 0; k < 3; ++k) {
        e1[k] /= l1;
    }
    e2[0] = d[1] * e1[2] - d[2] * e1[1];
    e2[1] = d[2] * e1[0] - d[0] * e1[2];
    e2[2] = d[0] * e1[1] - d[1] * e1[0];
}
