// camera.h: orthographic cameras and the map-space conventions of docs/design.md
// section 2.
//
// Matrices are 16 floats stored row by row and applied to row vectors, as in the
// thesis and Maya/Imath: [x y z 1] * wtc = [u v d w]. u, v in [0,1] across the
// map (v = 0 at the bottom row), d the distance from the camera plane along the
// viewing direction. EXR row 0 is the top: texel (i, j) has i = floor(u*W),
// j = floor((1-v)*H).
#ifndef WX_CAMERA_H
#define WX_CAMERA_H

#include <stdbool.h>

#include "core/error.h"

/// An orthographic view as given by <View>: eye, target, up, world extent, pixels.
typedef struct wx_view {
    float eye[3];
    float target[3];
    float up[3];
    float width_ws;  ///< world-space width of the frame
    float height_ws; ///< world-space height of the frame
    int width_px;
    int height_px;
} wx_view;

/// A camera: its matrices and, once known, the size of its maps.
typedef struct wx_camera {
    float wtc[16]; ///< world to map, row-major, row vectors
    float ctw[16]; ///< map to world (inverse of wtc)
    int width;     ///< map width in texels (0 while unknown)
    int height;    ///< map height in texels (0 while unknown)
} wx_camera;

/// Builds the matrices of an orthographic <View>. Fails (WX_BAD_INPUT, message
/// without file context) when eye == target, up is parallel to the view
/// direction, or a size is not positive.
wx_result wx_camera_from_view(const wx_view *view, wx_camera *out, wx_error *err);

/// Why the camera's matrices cannot be used (a phrase for a message), or NULL
/// when they can: every entry finite in single precision, both matrices
/// orthographic (wx_matrix_is_orthographic), the linear part of wtc invertible
/// (wx_invert3, as the collider inverts it).
const char *wx_camera_problem(const wx_camera *camera);

/// World point to map space (u, v, d).
void wx_camera_world_to_map(const wx_camera *cam, const float p[3], float uvd[3]);

/// Map space (u, v, d) to world point.
void wx_camera_map_to_world(const wx_camera *cam, const float uvd[3], float p[3]);

/// True when (u, v) lies inside the map: 0 <= u < 1 and 0 < v <= 1.
bool wx_map_contains(float u, float v);

/// Texel column i and row j (row 0 at the top) of (u, v) in a W x H map. Returns
/// false when (u, v) is outside the map.
bool wx_map_texel(int width, int height, float u, float v, int *i, int *j);

/// (u, v) of the centre of texel (i, j) in a W x H map.
void wx_map_texel_center(int width, int height, int i, int j, float *u, float *v);

/// Unit viewing direction (towards larger d) in world space.
void wx_camera_view_dir(const wx_camera *cam, float dir[3]);

/// World-space size of the whole frame along u and v, and the area of one texel
/// seen head-on (for an orthographic camera).
void wx_camera_frame_size(const wx_camera *cam, float *width_ws, float *height_ws);

#endif
