// view.h: the viewer's orbit camera and the little matrix algebra it needs.
//
// GL matrices here are column-major (as glUniformMatrix4fv takes them without
// transposing) and apply to column vectors, unlike the scene's row-major,
// row-vector camera matrices (camera.h). Y is up.
#ifndef VW_VIEW_H
#define VW_VIEW_H

/// An orbit around `target`: the eye sits at `distance` from it, `yaw` radians
/// around +Y (0 looks along -Z) and `pitch` radians above the horizon.
typedef struct vw_orbit {
    float target[3];
    float distance;
    float yaw;
    float pitch;
    float fov_y;        ///< vertical field of view, radians
    float scene_radius; ///< size of what is drawn, for the clip planes
} vw_orbit;

/// out = a * b (column-major 4x4).
void vw_mat4_mul(const float a[16], const float b[16], float out[16]);

/// Frames the box [lo, hi] in a window of aspect width/height, looking from
/// the front-right and a little above.
void vw_orbit_frame(vw_orbit *orbit, const float lo[3], const float hi[3], float aspect);

/// Eye position in world space.
void vw_orbit_eye(const vw_orbit *orbit, float eye[3]);

/// Projection * view for a window of the given aspect.
void vw_orbit_matrix(const vw_orbit *orbit, float aspect, float mvp[16]);

/// Left drag: dx, dy in pixels.
void vw_orbit_rotate(vw_orbit *orbit, float dx, float dy);

/// Right or middle drag: moves the target in the view plane so that the point
/// under the cursor follows it; dx, dy in pixels, height of the window in pixels.
void vw_orbit_pan(vw_orbit *orbit, float dx, float dy, float window_height);

/// Scroll: positive steps move closer.
void vw_orbit_zoom(vw_orbit *orbit, float steps);

#endif
