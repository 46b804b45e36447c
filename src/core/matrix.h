// matrix.h: 4x4 matrices as the program stores them (docs/design.md section 2, in
// docs/design.md): 16 numbers row by row, applied to row vectors,
// [x y z 1] * M = [u v d w]. The one orthographic test, the products and
// inverses the modules need, in double where precision matters.
#ifndef WX_MATRIX_H
#define WX_MATRIX_H

#include <stdbool.h>

/// The one orthographic test of the program (scene loading, collider, gather):
/// every entry finite, the last column (0, 0, 0, w) with w != 0, relative to
/// the matrix's scale (|w| > 1e-12 of the largest entry; |m[3]|, |m[7]|,
/// |m[11]| at most 1e-6 of that entry and of |m0| + |m5| + |m10| + |w|).
bool wx_matrix_is_orthographic(const float m[16]);

/// An orthographic matrix in double with w = 1 (divided by w, last column
/// exactly 0 0 0 1). False when it is not orthographic.
bool wx_matrix_to_affine(const float m[16], double out[16]);

/// Product of two row-vector matrices in double: (p * a) * b = p * out.
void wx_matrix_mul(const double a[16], const double b[16], double out[16]);

/// Row r (0..3) of a matrix as a 3-vector.
void wx_matrix_row3(const double m[16], int r, double out[3]);

/// The matrix with its translation moved by `origin`: [p - origin, 1] * out =
/// [p, 1] * m, in double (for geometry stored relative to an origin).
void wx_matrix_fold_origin(const float m[16], const double origin[3], double out[16]);

/// [x y z 1] * m without the division by w, in double.
void wx_matrix_apply_affine(const float m[16], const double p[3], double out[3]);

/// [x y z 1] * m, divided by w. Returns false when w is 0 or not finite.
bool wx_transform_point(const float m[16], const float p[3], float out[3]);

/// Inverse of a 3x3 matrix (row-major) in double; false when singular relative
/// to its scale (|det| <= 1e-12 * (largest entry)^3) or not finite.
bool wx_invert3(const double a[9], double inv[9]);

/// Sets inv to the inverse of m (cglm, precise variant). Returns false when m
/// is singular relative to its scale or anything is not finite.
bool wx_matrix_invert(const float m[16], float inv[16]);

/// Largest absolute element of a*b - I, a measure of how far two matrices are
/// from being inverses of one another (relative to their scale).
float wx_matrix_inverse_error(const float a[16], const float b[16]);

/// Dot product and length of 3-vectors in double.
double wx_dot3(const double a[3], const double b[3]);
double wx_length3(const double a[3]);

/// Two unit vectors e1, e2 across the unit vector d, (d, e1, e2) right-handed:
/// e1 = unit(d x u) with u the x axis, or the y axis when d lies within 26
/// degrees of x; e2 = d x e1.
void wx_perpendicular_basis(const double d[3], double e1[3], double e2[3]);

#endif
