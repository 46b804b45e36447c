// gen_thesis_maps.c: writes the pre-rendered maps of xml_scenes/thesis_box.xml,
// a scene in the thesis' own format (matrices and maps, no geometry): a 2 m cube
// standing on a 6 m square slab, seen by a front and a top camera, and an output
// camera at the front. The maps are ray-cast analytically, so they are exact.
//
//   make build/libweathering.a
//   cc -std=c11 -O2 -D_POSIX_C_SOURCE=200809L -Isrc -I/usr/include/OpenEXR \
//      tests/tools/gen_thesis_maps.c build/libweathering.a -lOpenEXRCore-3_1 -lxml2 \
//      -lassimp -lOSMesa -lpng -lm -lpthread -o build/gen_thesis_maps
//   build/gen_thesis_maps maps
// It prints the matrices to paste into the scene.
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "model/camera.h"
#include "io/exr.h"
#include "model/image.h"

enum { SIZE = 256 };

typedef struct aabb {
    float lo[3], hi[3];
    float absorption, bounce, deposit, erosion;
} aabb;

// The cube and the slab it stands on.
static const aabb boxes[2] = {
    { { -1, 0, -1 }, { 1, 2, 1 }, 0.1f, 0.3f, 0.5f, 0.1f },
    { { -3, -0.2f, -3 }, { 3, 0, 3 }, 0.3f, 0.2f, 0.8f, 0.05f },
};

// Slab test: entry distance along the ray and the entry face's normal.
static bool hit_box(const aabb *b, const float o[3], const float dir[3], float *t_out, float n[3])
{
    float t0 = -INFINITY, t1 = INFINITY;
    int axis = -1;
    float sign = 0;
    for (int k = 0; k < 3; ++k) {
        if (fabsf(dir[k]) < 1e-12f) {
            if (o[k] < b->lo[k] || o[k] > b->hi[k]) {
                return false;
            }
            continue;
        }
        float a = (b->lo[k] - o[k]) / dir[k], c = (b->hi[k] - o[k]) / dir[k];
        float near = fminf(a, c), far = fmaxf(a, c);
        if (near > t0) {
            t0 = near;
            axis = k;
            sign = dir[k] > 0 ? -1.0f : 1.0f;
        }
        t1 = fminf(t1, far);
    }
    if (t0 > t1 || t0 < 0 || axis < 0) {
        return false;
    }
    *t_out = t0;
    n[0] = n[1] = n[2] = 0;
    n[axis] = sign;
    return true;
}

static void print_matrix(const char *name, const float m[16])
{
    printf("        <%s matrix=\"", name);
    for (int k = 0; k < 16; ++k) {
        printf("%.9g%s", m[k] + 0.0f, k < 15 ? " " : "");
    }
    printf("\"/>\n");
}

static int write_camera(const char *dir, const char *name, const wx_view *view, bool output)
{
    wx_camera cam;
    wx_error err;
    if (wx_camera_from_view(view, &cam, &err) != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
        return 1;
    }
    float view_dir[3];
    wx_camera_view_dir(&cam, view_dir);
    const char *rgb[3] = { "R", "G", "B" };
    wx_image depth = { 0 }, normal = { 0 }, impact = { 0 }, dirt = { 0 };
    if (wx_image_alloc(&depth, SIZE, SIZE, 1, rgb, &err) != WX_OK ||
        wx_image_alloc(&normal, SIZE, SIZE, 3, rgb, &err) != WX_OK ||
        wx_image_alloc(&impact, SIZE, SIZE, 2, rgb, &err) != WX_OK ||
        wx_image_alloc(&dirt, SIZE, SIZE, 3, rgb, &err) != WX_OK) {
        fprintf(stderr, "%s\n", err.message);
        return 1;
    }
    for (int j = 0; j < SIZE; ++j) {
        for (int i = 0; i < SIZE; ++i) {
            float u, v;
            wx_map_texel_center(SIZE, SIZE, i, j, &u, &v);
            const float uvd[3] = { u, v, 0.0f };
            float origin[3];
            wx_camera_map_to_world(&cam, uvd, origin);
            float best = INFINITY, n[3] = { 0, 0, 0 };
            const aabb *hit = NULL;
            for (int b = 0; b < 2; ++b) {
                float t, nb[3];
                if (hit_box(&boxes[b], origin, view_dir, &t, nb) && t < best) {
                    best = t;
                    memcpy(n, nb, sizeof n);
                    hit = &boxes[b];
                }
            }
            size_t at = (size_t)j * SIZE + (size_t)i;
            depth.channels[0][at] = best;
            for (int k = 0; k < 3; ++k) {
                normal.channels[k][at] = n[k];
            }
            if (hit != NULL) {
                impact.channels[0][at] = hit->absorption;
                impact.channels[1][at] = hit->bounce;
                dirt.channels[1][at] = hit->deposit;
                dirt.channels[2][at] = hit->erosion;
            }
        }
    }
    wx_image *images[4] = { &depth, &normal, &impact, &dirt };
    const char *kinds[4] = { "depth", "normal", "impact", "dirt" };
    int count = output ? 2 : 4;
    int status = 0;
    for (int m = 0; m < count && status == 0; ++m) {
        wx_image_set_m44f(images[m], "WTCMatrix", cam.wtc);
        wx_image_set_m44f(images[m], "CTWMatrix", cam.ctw);
        wx_image_set_string(images[m], "cameraName", name);
        char path[4096];
        snprintf(path, sizeof path, "%s/thesis_box_%s_%s.exr", dir, name, kinds[m]);
        if (wx_exr_write(path, images[m], &err) != WX_OK) {
            fprintf(stderr, "%s\n", err.message);
            status = 1;
        }
    }
    for (int m = 0; m < 4; ++m) {
        wx_image_free(images[m]);
    }
    printf("      <Ortho cameraName=\"%s\"%s>\n", name, output ? " out=\"true\"" : "");
    print_matrix("CTWMatrix", cam.ctw);
    print_matrix("WTCMatrix", cam.wtc);
    return status;
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "maps";
    wx_view front = { .eye = { 0, 1, 10 }, .target = { 0, 1, 0 }, .up = { 0, 1, 0 },
                      .width_ws = 8, .height_ws = 8, .width_px = SIZE, .height_px = SIZE };
    wx_view top = { .eye = { 0, 10, 0 }, .target = { 0, 0, 0 }, .up = { 0, 0, -1 },
                    .width_ws = 8, .height_ws = 8, .width_px = SIZE, .height_px = SIZE };
    return write_camera(dir, "front", &front, false) | write_camera(dir, "top", &top, false) |
           write_camera(dir, "out", &front, true);
}
