// bake_peel.c: a layered camera drawn by depth peeling (docs/design.md
// section 14, docs/cameras.md "Contacts"): the passes read back and merged
// into the camera's layers on the CPU, where a contact (a solid left and
// another entered at one depth: two solids lying on each other) gives way to
// the crossings behind it when a texel's crossings outnumber its layers, so
// the layers hold what a particle reaches. bake.c calls bake_peel_camera.
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>

#include "core/big_alloc.h"
#include "core/error.h"
#include "model/camera.h"
#include "raster/baker_internal.h"

// At most this many peeling passes per layer: a texel needs one pass per
// crossing it keeps and two per contact dropped before its last one (texels
// still open after them keep what they hold).
#define PEEL_PASSES_PER_LAYER 4

// Per texel while a layered camera peels: the crossings kept (0 to layers),
// and PEEL_DONE once nothing after them can change them.
#define PEEL_DONE 0x80u

static double dot3(const float a[3], const float b[3])
{
    return (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2];
}

// Whether a crossing with outward normal n leaves a solid (faces away from the camera).
static bool leaving(const float n[3], const float view[3])
{
    return dot3(n, view) > 0.0;
}

// The plane value of texel t at o.
static float *plane_at(const plane_out *o, size_t t)
{
    return o->plane + (o->stride > 0 ? o->stride : 1) * t;
}

// Whether crossing (d, n), the next one peeled at a texel, and (d0, n0), the
// last one kept there, are a contact: a crossing leaving a solid and one
// entering a solid at the same depth, within the peeling tie step of
// bake_frag.glsl (4e-6 x (1 + |d|): 0.2 mm at d = 50), with no free space
// between them. Two solids lying on each other (the slabs of a roof, a pane on
// a wall) meet there; no particle reaches either face (peel_merge).
static bool peel_contact(float d0, const float n0[3], float d, const float n[3], const float view[3])
{
    return leaving(n0, view) && dot3(n, view) < 0.0 &&
           fabs((double)d - (double)d0) <= 4e-6 * (1.0 + fabs((double)d0));
}

// The solids texel t's first k kept crossings leave open (entering and
// leaving crossings paired as brackets; a leaving one with none open counts
// for nothing). A contact counts only where this is 0 after its leaving
// crossing: between two solids on the outside, where free space would be.
// Inside another solid (the house's 1 mm pane lying on its core within a
// facade box) the peel has merged coincident faces (the pane's back and the
// box's: one depth, one crossing), the crossings no longer pair up, and
// without the contact the core's face behind would be read as the pane's
// (wx_maps_bury, the gather's nearer crossing): seen where nothing reaches.
static int peel_inside(plane_out (*dst)[PASS_PLANES], size_t t, int k, const float view[3])
{
    int inside = 0;
    for (int l = 0; l < k; ++l) {
        float n[3] = { *plane_at(&dst[l][PASS_NX], t), *plane_at(&dst[l][PASS_NY], t),
                       *plane_at(&dst[l][PASS_NZ], t) };
        inside = leaving(n, view) ? (inside > 0 ? inside - 1 : 0) : inside + 1;
    }
    return inside;
}

// Copies crossing `from` of texel t's kept layers over crossing `to`.
static void peel_move(plane_out (*dst)[PASS_PLANES], int planes, size_t t, int from, int to)
{
    for (int p = 0; p < planes; ++p) {
        if (dst[to][p].plane != NULL) {
            *plane_at(&dst[to][p], t) = *plane_at(&dst[from][p], t);
        }
    }
}

// Merges one peeling pass (`pass`: `planes` planes of `texels`) into the kept
// layers `dst` (layer l's plane p at dst[l][p]; a NULL plane is not wanted).
// Contacts are kept while there is room, for they seal the faces on either
// side (wx_maps_bury, and the gather's nearer crossing), and give way to the
// crossings a particle can reach: at each open texel a crossing that closes a
// contact with the last one kept is kept beside it (bit l of pairs[t]: layers
// l and l + 1 are a contact), or, with no room left, drops it; any other
// crossing is kept, in a full stack after the deepest contact kept is dropped
// to make room, unless it leaves a solid none of the others left open (a
// coincident face merged: peel_inside). Returns the texels still open: a texel closes when nothing is
// behind, or when its stack is full of crossings no later one can displace.
static size_t peel_merge(const float *pass, int planes, size_t texels, plane_out (*dst)[PASS_PLANES],
                         int layers, unsigned char *kept, unsigned char *pairs,
                         const float view[3])
{
    size_t open = 0;
    for (size_t t = 0; t < texels; ++t) {
        if (kept[t] & PEEL_DONE) {
            continue;
        }
        float d = pass[PASS_D * texels + t];
        if (!(d < INFINITY)) {
            kept[t] |= PEEL_DONE;
            continue;
        }
        int k = kept[t];
        float n[3] = { pass[PASS_NX * texels + t], pass[PASS_NY * texels + t],
                       pass[PASS_NZ * texels + t] };
        bool contact = false;
        if (k > 0 && peel_inside(dst, t, k, view) == 0) {
            const plane_out *last = dst[k - 1];
            float n0[3] = { *plane_at(&last[PASS_NX], t), *plane_at(&last[PASS_NY], t),
                            *plane_at(&last[PASS_NZ], t) };
            contact = peel_contact(*plane_at(&last[PASS_D], t), n0, d, n, view);
        }
        if (contact && k == layers) {
            kept[t] = (unsigned char)(k - 1); // no room: the contact goes
            ++open;
            continue;
        }
        if (!contact && k == layers) {
            if (pairs[t] == 0 || (leaving(n, view) && peel_inside(dst, t, k, view) == 0)) {
                // Nothing to displace, or a crossing leaving no solid kept: a
                // face merged with one it coincides with left the crossings
                // unpaired, and the contact stays (as above).
                kept[t] |= PEEL_DONE;
                continue;
            }
            int j = 7;
            while (!(pairs[t] & (1u << j))) {
                --j;
            }
            for (int l = j + 2; l < k; ++l) {
                peel_move(dst, planes, t, l, l - 2);
            }
            pairs[t] = (unsigned char)(pairs[t] & ~(1u << j)); // the deepest: none after it
            k -= 2;
        }
        for (int p = 0; p < planes; ++p) {
            if (dst[k][p].plane != NULL) {
                *plane_at(&dst[k][p], t) = pass[(size_t)p * texels + t];
            }
        }
        if (contact) {
            pairs[t] = (unsigned char)(pairs[t] | (1u << (k - 1)));
        }
        kept[t] = (unsigned char)(k + 1);
        if (k + 1 == layers && pairs[t] == 0 && !leaving(n, view)) {
            // Full of reachable crossings, the last entering a solid: no later
            // crossing makes a contact with it or displaces one.
            kept[t] |= PEEL_DONE;
            continue;
        }
        ++open;
    }
    return open;
}

// Sets the baker's region to the rectangle of the texels still open (kept
// without PEEL_DONE).
static void open_region(baker *b, int width, const unsigned char *kept, size_t texels)
{
    int x0 = width, x1 = 0, y0 = -1, y1 = 0;
    for (size_t t = 0; t < texels; ++t) {
        if (!(kept[t] & PEEL_DONE)) {
            int x = (int)(t % (size_t)width), y = (int)(t / (size_t)width);
            x0 = x < x0 ? x : x0;
            x1 = x + 1 > x1 ? x + 1 : x1;
            y0 = y0 < 0 ? y : y0;
            y1 = y + 1;
        }
    }
    if (y0 >= 0) {
        bake_set_region(b, x0, y0, x1, y1);
    }
}

// Draws layered camera c by depth peeling, into the kept layers `dst` (see
// peel_merge): pass after pass, each keeping the crossings behind the one
// before (bake_frag.glsl), until no texel is open or after
// PEEL_PASSES_PER_LAYER x layers passes. Each texel's slots after its kept
// crossings are the background (d +inf, the rest 0). *drawn: the most
// crossings a texel kept (the layers after it hold none).
wx_result bake_peel_camera(baker *b, int c, int layers, int planes, plane_out (*dst)[PASS_PLANES],
                             int *drawn, wx_error *err)
{
    const wx_scene_camera *sc = &b->scene->cameras[c];
    size_t texels = (size_t)sc->camera.width * (size_t)sc->camera.height;
    float view[3];
    wx_camera_view_dir(&sc->camera, view);
    float *pass = wx_big_malloc((size_t)planes * texels * sizeof *pass);
    unsigned char *kept = wx_big_calloc(texels, 1), *pairs = wx_big_calloc(texels, 1);
    wx_result r = pass != NULL && kept != NULL && pairs != NULL
                      ? WX_OK
                      : wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "bake: out of memory (peeling)");
    size_t open = texels;
    int targets = planes > PASS_DEPTH_PLANES ? TARGET_COUNT : 1;
    for (int p = 0; r == WX_OK && open > 0 && p < PEEL_PASSES_PER_LAYER * layers; ++p) {
        r = bake_draw_camera(b, c, targets, p, err);
        if (r == WX_OK) {
            plane_out out[4];
            for (int q = 0; q < 4; ++q) {
                out[q] = (plane_out){ pass + (size_t)(PASS_D + q) * texels, 1 };
            }
            r = bake_read_target(b, TARGET_DEPTH_NORMAL, 4, out, err);
        }
        if (r == WX_OK && targets > 1) {
            plane_out out[4];
            for (int q = 0; q < 4; ++q) {
                out[q] = (plane_out){ pass + (size_t)(PASS_ABSORPTION + q) * texels, 1 };
            }
            r = bake_read_target(b, TARGET_IMPACT_DIRT, 4, out, err);
        }
        if (r == WX_OK && targets > 1) {
            plane_out out[2] = { { pass + (size_t)PASS_DENSITY * texels, 1 },
                                 { pass + (size_t)PASS_SURFACE * texels, 1 } };
            r = bake_read_target(b, TARGET_DENSITY, 2, out, err);
        }
        if (r == WX_OK) {
            open = peel_merge(pass, planes, texels, dst, layers, kept, pairs, view);
        }
        if (r == WX_OK && open > 0) {
            r = bake_keep_previous_layer(b, err);
            // The next pass draws the open texels' rectangle alone: a texel's
            // fragments read its own previous texel only, so the open ones
            // come out as they would from the whole frame, and after the
            // first passes few are open (the house's side cameras: 3 180
            // texels in a 12 x 713 rectangle for their last 10 passes).
            open_region(b, sc->camera.width, kept, texels);
        }
    }
    bake_set_region(b, 0, 0, 0, 0);
    int most = 0;
    for (size_t t = 0; r == WX_OK && t < texels; ++t) {
        int k = kept[t] & ~PEEL_DONE;
        most = k > most ? k : most;
        for (int l = k; l < layers; ++l) {
            for (int q = 0; q < planes; ++q) {
                const plane_out *o = &dst[l][q];
                if (o->plane != NULL) {
                    *plane_at(o, t) = q == PASS_D ? INFINITY : 0.0f;
                }
            }
        }
    }
    *drawn = most;
    free(pairs);
    free(kept);
    free(pass);
    return r;
}
