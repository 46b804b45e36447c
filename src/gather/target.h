// target.h: where a gather evaluates the mask: a set of texels, each standing
// for one surface point with a world position and a normal (docs/architecture.md).
//
// A target is made by a camera: the output camera's (or an input camera's)
// depth and normal maps, the point of texel (i, j) its centre at the depth the
// map holds, and the second pass smooths over the camera's texel grid. A UV
// layout (a TextureMap, gather/texture.h) is not a target of its own: its
// texels sample the masks computed on the input cameras' targets, so that its
// smoothing runs along the surface in world space and ignores UV seams. A new
// kind adds a case to wx_target_kind and its construction; the passes read the
// target only through this struct.
#ifndef WX_TARGET_H
#define WX_TARGET_H

#include "model/camera.h"
#include "model/maps.h"

typedef enum wx_target_kind {
    WX_TARGET_CAMERA = 0, ///< the texels of an orthographic camera's maps
} wx_target_kind;

/// A gather's target: views into memory the caller owns. Row 0 is the top,
/// texel (i, j) at j*width + i (model/maps.h).
typedef struct wx_target {
    wx_target_kind kind;
    const wx_camera *camera; ///< WX_TARGET_CAMERA: orthographic matrices
    int width;
    int height;
    const float *depth;  ///< width*height; +inf, NaN, <= 0 or >= 1e30: no surface
    const float *normal; ///< 3*width*height, interleaved, world-space unit normals
} wx_target;

/// The target of a camera and its depth and normal maps.
wx_target wx_target_from_camera(const wx_camera *camera, const wx_maps *maps);

#endif
