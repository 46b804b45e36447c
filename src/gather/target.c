// target.c: targets of the gather (target.h).
#include "gather/target.h"

wx_target wx_target_from_camera(const wx_camera *camera, const wx_maps *maps)
{
    wx_target target = { .kind = WX_TARGET_CAMERA, .camera = camera, .width = maps->width,
                         .height = maps->height, .depth = maps->depth, .normal = maps->normal };
    return target;
}
