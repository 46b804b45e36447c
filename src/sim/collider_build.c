// collider_build.c: the projected-maps collider's construction (thesis
// 4.8.4.1): each camera's matrices, its copy of the maps, the coarse pyramid
// the coarse test reads, and a layered camera's crossings reduced to the
// outline of its solids.
#include "sim/collider.h"
#include "core/big_alloc.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/matrix.h"
#include "sim/collider_internal.h"

// --- building ----------------------------------------------------------------

static wx_result setup_matrices(wx_collider_camera *cam, const float wtc[16], int index,
                                wx_error *err)
{
    // [x y z 1] * wtc = [u v d w]; the collider needs w constant (orthographic).
    double w = wtc[15];
    if (!wx_matrix_is_orthographic(wtc)) {
        return wx_fail(err, WX_CAUSE_BAD_CAMERA,
                       "input camera %d: projective (perspective) matrices are not "
                       "supported by the collider; use orthographic cameras",
                       index);
    }
    double W = cam->width, H = cam->height;
    for (int r = 0; r < 4; ++r) {
        double u = wtc[r * 4 + 0] / w, v = wtc[r * 4 + 1] / w, d = wtc[r * 4 + 2] / w;
        cam->mx[r] = u * W;
        cam->my[r] = -v * H;
        cam->md[r] = d;
    }
    cam->my[3] += H; // Y = (1 - v) * H
    for (int r = 0; r < 4; ++r) {
        cam->fmx[r] = (float)cam->mx[r];
        cam->fmy[r] = (float)cam->my[r];
        cam->fmd[r] = (float)cam->md[r];
    }
    double a[9], inv[9];
    for (int r = 0; r < 3; ++r) {
        a[r * 3 + 0] = wtc[r * 4 + 0] / w;
        a[r * 3 + 1] = wtc[r * 4 + 1] / w;
        a[r * 3 + 2] = wtc[r * 4 + 2] / w;
    }
    if (!wx_invert3(a, inv)) {
        return wx_fail(err, WX_CAUSE_BAD_CAMERA, "input camera %d: singular matrix", index);
    }
    // Row k of inv is the world displacement per unit of u, v, d.
    for (int k = 0; k < 3; ++k) {
        cam->back[k] = (float)-inv[6 + k];
    }
    double du = sqrt(inv[0] * inv[0] + inv[1] * inv[1] + inv[2] * inv[2]) / W;
    double dv = sqrt(inv[3] * inv[3] + inv[4] * inv[4] + inv[5] * inv[5]) / H;
    cam->texel_ws = (float)fmin(du, dv);
    return WX_OK;
}

// How far each curved cell dips in front of its corners (curve_cells), for
// the bounds build_coarse makes: per texel, the cell whose first corner it
// is, in units of `unit`; `q` NULL where no cell curves.
typedef struct cell_dips {
    uint8_t *q;
    double unit;
} cell_dips;

// The coarse pyramid: block minima per level, then the minimum over the 3x3
// blocks around each block, lowered by a margin for float rounding.
static wx_result build_coarse(wx_collider_camera *cam, const cell_dips *dips, wx_error *err)
{
    int W = cam->width, H = cam->height;
    int total = 0;
    for (int l = 0; l < WX_COARSE_LEVELS; ++l) {
        int shift = WX_COARSE_BLOCK_SHIFT + WX_COARSE_LEVEL_SHIFT * l;
        cam->level_width[l] = ((W - 1) >> shift) + 1;
        cam->level_height[l] = ((H - 1) >> shift) + 1;
        cam->level_offset[l] = total;
        total += cam->level_width[l] * cam->level_height[l];
    }
    cam->levels = WX_COARSE_LEVELS;
    cam->coarse = wx_big_malloc((size_t)total * sizeof *cam->coarse);
    float *blockmin = wx_big_malloc((size_t)total * sizeof *blockmin);
    if (cam->coarse == NULL || blockmin == NULL) {
        free(blockmin);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (collider pyramid)");
    }
    for (int i = 0; i < total; ++i) {
        blockmin[i] = INFINITY;
    }
    const float *first = cam->depth;
    float *lowered = NULL;
    if (dips->q != NULL) {
        // Second-order cells dip in front of their corners: each texel's
        // first crossing lowered by the largest dip of the four cells it is a
        // corner of bounds every cell from below as the corners did.
        lowered = wx_big_malloc((size_t)W * (size_t)H * sizeof *lowered);
        if (lowered == NULL) {
            free(blockmin);
            return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (collider pyramid)");
        }
        for (int j = 0; j < H; ++j) {
            for (int i = 0; i < W; ++i) {
                int most = 0;
                for (int y = j - 1; y <= j; ++y) {
                    for (int x = i - 1; x <= i; ++x) {
                        if (x >= 0 && y >= 0) {
                            int b = dips->q[(size_t)y * (size_t)W + (size_t)x];
                            most = b > most ? b : most;
                        }
                    }
                }
                size_t t = (size_t)j * (size_t)W + (size_t)i;
                lowered[t] = (float)(cam->depth[t] - dips->unit * most);
            }
        }
        first = lowered;
    }
    // Level 0 from the texels, each further level from the one below.
    float *level0 = blockmin + cam->level_offset[0];
    for (int j = 0; j < H; ++j) {
        const float *row = first + (size_t)j * (size_t)W;
        float *out = level0 + (size_t)(j >> WX_COARSE_BLOCK_SHIFT) * (size_t)cam->level_width[0];
        for (int i = 0; i < W; ++i) {
            float d = row[i];
            float *m = &out[i >> WX_COARSE_BLOCK_SHIFT];
            if (d < *m) {
                *m = d;
            }
        }
    }
    for (int l = 1; l < WX_COARSE_LEVELS; ++l) {
        const float *below = blockmin + cam->level_offset[l - 1];
        float *here = blockmin + cam->level_offset[l];
        int bw = cam->level_width[l - 1], bh = cam->level_height[l - 1];
        for (int by = 0; by < bh; ++by) {
            for (int bx = 0; bx < bw; ++bx) {
                float d = below[by * bw + bx];
                float *m = &here[(by >> WX_COARSE_LEVEL_SHIFT) * cam->level_width[l] +
                                 (bx >> WX_COARSE_LEVEL_SHIFT)];
                if (d < *m) {
                    *m = d;
                }
            }
        }
    }
    double margin_base = 1e-4 * cam->texel_ws;
    for (int l = 0; l < WX_COARSE_LEVELS; ++l) {
        const float *src = blockmin + cam->level_offset[l];
        float *dst = cam->coarse + cam->level_offset[l];
        int bw = cam->level_width[l], bh = cam->level_height[l];
        for (int by = 0; by < bh; ++by) {
            for (int bx = 0; bx < bw; ++bx) {
                float m = INFINITY;
                for (int y = by - 1; y <= by + 1; ++y) {
                    for (int x = bx - 1; x <= bx + 1; ++x) {
                        if (x >= 0 && x < bw && y >= 0 && y < bh && src[y * bw + x] < m) {
                            m = src[y * bw + x];
                        }
                    }
                }
                if (isfinite(m)) {
                    m = (float)(m - margin_base - 1e-6 * fabs(m));
                }
                dst[by * bw + bx] = m;
            }
        }
    }
    free(blockmin);
    // The fine test's bound: the 3 x 3 minimum of the first crossings, in rows
    // (the minimum over three columns, then over three rows). A solid starts
    // at a crossing, every crossing of a texel lies at or behind its first, and
    // a cell's bilinear depth lies between its corners'; only a sheet seen from
    // behind starts in front of its crossing, by one sheet: where some texel of
    // the 3 x 3 holds one (in any layer), the bound is a sheet nearer.
    size_t texels = (size_t)W * (size_t)H;
    cam->near3 = wx_big_malloc(texels * sizeof *cam->near3);
    float *across = wx_big_malloc(texels * sizeof *across);
    unsigned char *sheet = wx_big_calloc(texels, 1), *sheet_across = wx_big_calloc(texels, 1);
    if (cam->near3 == NULL || across == NULL || sheet == NULL || sheet_across == NULL) {
        free(lowered);
        free(across);
        free(sheet);
        free(sheet_across);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (collider pyramid)");
    }
    for (size_t at = 0; cam->layers > 1 && at < (size_t)cam->layers * texels; ++at) {
        uint8_t role = cam->role[at];
        if ((role & WX_ROLE_KIND) == WX_ROLE_SHEET && !(role & WX_ROLE_FACING)) {
            sheet[at % texels] = 1;
        }
    }
    for (int j = 0; j < H; ++j) {
        size_t r = (size_t)j * (size_t)W;
        const float *row = first + r;
        for (int i = 0; i < W; ++i) {
            float m = row[i];
            m = i > 0 && row[i - 1] < m ? row[i - 1] : m;
            m = i + 1 < W && row[i + 1] < m ? row[i + 1] : m;
            across[r + (size_t)i] = m;
            sheet_across[r + (size_t)i] =
                (unsigned char)(sheet[r + (size_t)i] | (i > 0 ? sheet[r + (size_t)i - 1] : 0) |
                                (i + 1 < W ? sheet[r + (size_t)i + 1] : 0));
        }
    }
    for (int j = 0; j < H; ++j) {
        for (int i = 0; i < W; ++i) {
            size_t at = (size_t)j * (size_t)W + (size_t)i;
            float m = across[at];
            bool behind_sheet = sheet_across[at] != 0;
            for (int y = j - 1; y <= j + 1; y += 2) {
                size_t other = (size_t)y * (size_t)W + (size_t)i;
                if (y >= 0 && y < H) {
                    m = across[other] < m ? across[other] : m;
                    behind_sheet |= sheet_across[other] != 0;
                }
            }
            if (isfinite(m)) {
                m = (float)(m - margin_base - 1e-6 * fabs(m) - (behind_sheet ? cam->sheet : 0.0));
            }
            cam->near3[at] = m;
        }
    }
    free(lowered);
    free(across);
    free(sheet);
    free(sheet_across);
    return WX_OK;
}

// Whether the map holds no surface on the outermost ring of texels of the
// sides asked for (left, right: columns 0 and W-1; top, bottom: rows 0 and H-1).
static bool sides_are_empty(const float *depth, int W, int H, const bool side[4])
{
    for (int i = 0; i < W; ++i) {
        if ((side[2] && isfinite(depth[i])) ||
            (side[3] && isfinite(depth[(size_t)(H - 1) * (size_t)W + (size_t)i]))) {
            return false;
        }
    }
    for (int j = 0; j < H; ++j) {
        if ((side[0] && isfinite(depth[(size_t)j * (size_t)W])) ||
            (side[1] && isfinite(depth[(size_t)j * (size_t)W + (size_t)(W - 1)]))) {
            return false;
        }
    }
    return true;
}

// True when no texel of the map's outermost ring records a surface.
static bool border_is_empty(const float *depth, int W, int H)
{
    const bool all[4] = { true, true, true, true };
    return sides_are_empty(depth, W, H, all);
}

void wx_collider_frame_box(wx_collider *collider, const double lo[3], const double hi[3])
{
    for (int c = 0; c < collider->camera_count; ++c) {
        wx_collider_camera *cam = &collider->cameras[c];
        double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
        for (int k = 0; k < 8; ++k) {
            double p[3] = { (k & 1) ? hi[0] : lo[0], (k & 2) ? hi[1] : lo[1],
                            (k & 4) ? hi[2] : lo[2] };
            double X = p[0] * cam->mx[0] + p[1] * cam->mx[1] + p[2] * cam->mx[2] + cam->mx[3];
            double Y = p[0] * cam->my[0] + p[1] * cam->my[1] + p[2] * cam->my[2] + cam->my[3];
            xlo = fmin(xlo, X);
            xhi = fmax(xhi, X);
            ylo = fmin(ylo, Y);
            yhi = fmax(yhi, Y);
        }
        // A side the box reaches beyond (by more than rounding) is a side of
        // the whole camera's frame; at the others `weathering tiles` cut the
        // frame to the box, and what lies beyond them lies outside the box.
        const double eps = 1e-3; // texels
        bool side[4];
        side[0] = xlo < -eps;
        side[1] = xhi > cam->width + eps;
        side[2] = ylo < -eps;
        side[3] = yhi > cam->height + eps;
        cam->frames_model = sides_are_empty(cam->depth, cam->width, cam->height, side);
    }
}

// The roles of every texel's crossings (depth already copied, normals set):
// each texel's crossings are replaced by their outline (outline above),
// nearest first, with the layer each came from in `origin`.
static void classify_layers(wx_collider_camera *cam)
{
    int K = cam->layers;
    size_t texels = (size_t)cam->width * (size_t)cam->height;
    for (size_t t = 0; t < texels; ++t) {
        bool entering[WX_MAX_LAYERS];
        float depth[WX_MAX_LAYERS];
        int n = 0;
        for (int k = 0; k < K; ++k) {
            size_t at = (size_t)k * texels + t;
            if (n < k || !isfinite(cam->depth[at])) {
                continue; // a crossing after an empty layer is ignored
            }
            n = k + 1;
            depth[k] = cam->depth[at];
            const float *nv = cam->normal + 3 * at;
            // back points towards the camera: n . view < 0 is n . back > 0. A
            // grazing or missing normal counts as entering, as one layer's does.
            float dot = nv[0] * cam->back[0] + nv[1] * cam->back[1] + nv[2] * cam->back[2];
            entering[k] = !(dot < 0.0f);
        }
        uint8_t kind[WX_MAX_LAYERS], from[WX_MAX_LAYERS];
        int m = wx_layers_outline(entering, n, K, kind, from);
        for (int k = 0; k < K; ++k) {
            size_t at = (size_t)k * texels + t;
            if (k < m) {
                cam->depth[at] = depth[from[k]];
                cam->role[at] = (uint8_t)(kind[k] | (entering[from[k]] ? WX_ROLE_FACING : 0));
                cam->origin[at] = from[k];
            } else {
                cam->depth[at] = INFINITY;
                cam->role[at] = WX_ROLE_NONE;
                cam->origin[at] = 0;
            }
        }
    }
}
// Widening a camera's crossings by their margins (docs/physics.md, "Which
// camera's surface a particle meets"). A camera's map records a surface seen
// at angle theta to its axis to about half a texel times tan(theta) along that
// axis (the depth changes by texel * tan(theta) across a texel), so its "not
// behind" is sure only that far in front of a crossing. The point rule takes
// the intersection of every camera's solid, so without a margin the
// collision surface was whichever camera's surface lay innermost: on the top
// of a lumpy model the side cameras' grazing ones, in a pattern that turns
// with the model in the camera grid, which a sliding particle, meeting the
// collision surface at every step, followed. Each crossing moves by the part
// of its camera's precision that exceeds the most head-on camera's at that
// surface (its normal against every camera's axis): an entering face (or a
// full texel's last one) towards the camera, a leaving face away from it; a
// sheet's slab stays. The most head-on camera keeps its surface, which is
// then the collision surface, and the others' solids reach past it. At most
// MARGIN_MAX_TAN half texels: 32 texels, the whole margin of a slope down to
// 0.9 degrees. Between two of a side camera's rows' crossings its surface
// lies inside a curved near-flat top; capped at two texels (tan 4, slopes of
// 14 degrees) the margin left grooves there along lines of equal height, and
// sliding rain hit up to 16% more or less by the height's place within those
// rows (docs/physics.md, "Contour lines on flat tops").
#define MARGIN_MAX_TAN 64.0

static double tan_of_cos(double c)
{
    c = c < 1.0 ? c : 1.0;
    return sqrt(1.0 - c * c) / (c > 1e-3 ? c : 1e-3);
}

// Widens camera `cam`'s crossings; axes[c]: camera c's unit axis (towards it).
static void widen_crossings(const wx_collider *collider, const double (*axes)[3],
                            wx_collider_camera *cam)
{
    double bl = sqrt((double)cam->back[0] * cam->back[0] + (double)cam->back[1] * cam->back[1] +
                     (double)cam->back[2] * cam->back[2]);
    if (!(bl > 0.0)) {
        return;
    }
    const double *own_axis = axes[cam - collider->cameras];
    size_t texels = (size_t)cam->width * (size_t)cam->height;
    for (size_t at = 0; at < (size_t)cam->layers * texels; ++at) {
        int kind = cam->role[at] & WX_ROLE_KIND;
        double sign = kind == WX_ROLE_ENTER || kind == WX_ROLE_TAIL ? -1.0
                      : kind == WX_ROLE_LEAVE                       ? 1.0
                                                                    : 0.0;
        if (sign == 0.0 || !isfinite(cam->depth[at])) {
            continue;
        }
        size_t t = at % texels;
        const float *n = cam->normal + 3 * ((size_t)cam->origin[at] * texels + t);
        double nl = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
        if (!(nl > 1e-6) || !isfinite(nl)) {
            continue;
        }
        double own = fabs(n[0] * own_axis[0] + n[1] * own_axis[1] + n[2] * own_axis[2]) / nl;
        double best = own;
        for (int c = 0; c < collider->camera_count; ++c) {
            const double *a = axes[c];
            double along = fabs(n[0] * a[0] + n[1] * a[1] + n[2] * a[2]) / nl;
            best = along > best ? along : best;
        }
        double excess = fmin(tan_of_cos(own) - tan_of_cos(best), MARGIN_MAX_TAN);
        if (excess > 0.0) {
            cam->depth[at] = (float)(cam->depth[at] + sign * 0.5 * cam->texel_ws * excess / bl);
        }
    }
}

// Second-order cells (docs/physics.md, "Depth between texels"). A bilinear
// cell is exact on a plane; on a curved surface it is the chord between the
// four texel centres: behind the surface by up to a/8 between them (a the
// depth's second derivative, per texel squared) and with a kink in its slope
// at every row and column of centres, where a slide hops. The normals give
// the depth's slope at each centre, so the change of slope across the cell
// gives a and b along X and Y, and depth + a/2 fx (fx - 1) + b/2 fy (fy - 1)
// (0 at the corners, still a quadratic along a segment) is right to second
// order. Only where the normals explain the depths: slopes of at most
// CURVE_TAN texels of depth per texel, the chord's slope along each side
// within CURVE_TOL of a texel of the mean of its ends' slopes (a depth jump,
// a widened crossing beside an unwidened one), and slopes that change by at
// most CURVE_CAP per texel (else a crease or a rim: the cell stays a chord).
#define CURVE_TAN 6.0
#define CURVE_TOL 0.5
#define CURVE_CAP 1.0

// dD/dX at constant Y and dD/dY at constant X on the plane of normal n: along
// n x my (resp. n x mx), which keeps Y (X), scaled to one texel of X (Y).
static bool depth_slopes(const wx_collider_camera *cam, const float *n, double *gx, double *gy)
{
    const double *mx = cam->mx, *my = cam->my, *md = cam->md;
    double nx = n[0], ny = n[1], nz = n[2];
    double a[3] = { ny * my[2] - nz * my[1], nz * my[0] - nx * my[2], nx * my[1] - ny * my[0] };
    double b[3] = { ny * mx[2] - nz * mx[1], nz * mx[0] - nx * mx[2], nx * mx[1] - ny * mx[0] };
    double ax = a[0] * mx[0] + a[1] * mx[1] + a[2] * mx[2];
    double by = b[0] * my[0] + b[1] * my[1] + b[2] * my[2];
    if (!(fabs(ax) > 1e-12) || !(fabs(by) > 1e-12)) {
        return false; // seen edge-on
    }
    *gx = (a[0] * md[0] + a[1] * md[1] + a[2] * md[2]) / ax;
    *gy = (b[0] * md[0] + b[1] * md[1] + b[2] * md[2]) / by;
    return isfinite(*gx) && isfinite(*gy);
}

// Layer k's slopes per texel into g (2 per texel; NAN where none is usable).
static void layer_slopes(const wx_collider_camera *cam, int k, double texel, float *g)
{
    size_t texels = (size_t)cam->width * (size_t)cam->height;
    for (size_t t = 0; t < texels; ++t) {
        size_t at = (size_t)k * texels + t;
        g[2 * t] = g[2 * t + 1] = NAN;
        bool fill = cam->layers > 1 ? (cam->role[at] & WX_ROLE_FILL) != 0
                                    : cam->fill != NULL && cam->fill[t];
        if (!isfinite(cam->depth[at]) || fill) {
            continue;
        }
        size_t layer = cam->layers > 1 ? cam->origin[at] : 0;
        double gx, gy;
        if (depth_slopes(cam, cam->normal + 3 * (layer * texels + t), &gx, &gy) &&
            fabs(gx) <= CURVE_TAN * texel && fabs(gy) <= CURVE_TAN * texel) {
            g[2 * t] = (float)gx;
            g[2 * t + 1] = (float)gy;
        }
    }
}

static wx_result curve_cells(wx_collider_camera *cam, cell_dips *dips, wx_error *err)
{
    dips->q = NULL;
    int W = cam->width, H = cam->height;
    size_t texels = (size_t)W * (size_t)H;
    double bl = sqrt((double)cam->back[0] * cam->back[0] + (double)cam->back[1] * cam->back[1] +
                     (double)cam->back[2] * cam->back[2]);
    if (!(bl > 0.0) || W < 2 || H < 2) {
        return WX_OK;
    }
    double texel = cam->texel_ws / bl; // a texel, in depth
    cam->curve_unit = CURVE_CAP * texel / 32767.0;
    dips->unit = CURVE_CAP * texel / 4.0 / 255.0;
    float *g = wx_big_malloc(2 * texels * sizeof *g);
    int16_t *curve = wx_big_calloc(2 * (size_t)cam->layers * texels, sizeof *curve);
    uint8_t *bulge = wx_big_calloc(texels, 1);
    if (g == NULL || curve == NULL || bulge == NULL) {
        free(g);
        free(curve);
        free(bulge);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (collider curvature)");
    }
    bool any = false;
    double tol = CURVE_TOL * texel, cap = CURVE_CAP * texel;
    for (int k = 0; k < cam->layers; ++k) {
        layer_slopes(cam, k, texel, g);
        const float *depth = cam->depth + (size_t)k * texels;
        for (int j = 0; j + 1 < H; ++j) {
            for (int i = 0; i + 1 < W; ++i) {
                size_t c[4] = { (size_t)j * (size_t)W + (size_t)i, 0, 0, 0 };
                c[1] = c[0] + 1;
                c[2] = c[0] + (size_t)W;
                c[3] = c[2] + 1;
                double gx[4], gy[4];
                bool usable = true, flat = true;
                for (int q = 0; q < 4; ++q) {
                    gx[q] = g[2 * c[q]];
                    gy[q] = g[2 * c[q] + 1];
                    usable &= !isnan(gx[q]);
                    flat &= gx[q] == gx[0] && gy[q] == gy[0];
                }
                if (!usable || flat) {
                    continue;
                }
                double dx0 = gx[1] - gx[0], dx1 = gx[3] - gx[2];
                double dy0 = gy[2] - gy[0], dy1 = gy[3] - gy[1];
                if (fabs(dx0) > cap || fabs(dx1) > cap || fabs(dy0) > cap || fabs(dy1) > cap ||
                    fabs((depth[c[1]] - depth[c[0]]) - 0.5 * (gx[0] + gx[1])) > tol ||
                    fabs((depth[c[3]] - depth[c[2]]) - 0.5 * (gx[2] + gx[3])) > tol ||
                    fabs((depth[c[2]] - depth[c[0]]) - 0.5 * (gy[0] + gy[2])) > tol ||
                    fabs((depth[c[3]] - depth[c[1]]) - 0.5 * (gy[1] + gy[3])) > tol) {
                    continue;
                }
                long qa = lround(0.5 * (dx0 + dx1) / cam->curve_unit);
                long qb = lround(0.5 * (dy0 + dy1) / cam->curve_unit);
                if (qa == 0 && qb == 0) {
                    continue;
                }
                size_t at = (size_t)k * texels + c[0];
                curve[2 * at] = (int16_t)qa;
                curve[2 * at + 1] = (int16_t)qb;
                // The dip in front of the corners: a/8 + b/8 where they are > 0.
                double dip = ((qa > 0 ? qa : 0) + (qb > 0 ? qb : 0)) * cam->curve_unit / 8.0;
                double units = ceil(dip / dips->unit);
                uint8_t u = (uint8_t)(units < 255.0 ? units : 255.0);
                bulge[c[0]] = u > bulge[c[0]] ? u : bulge[c[0]];
                cam->bulge_most = fmax(cam->bulge_most, u * dips->unit);
                any = true;
            }
        }
    }
    free(g);
    if (!any) {
        free(curve);
        free(bulge);
        return WX_OK;
    }
    cam->curve = curve;
    dips->q = bulge;
    return WX_OK;
}

wx_result wx_collider_init(wx_collider *collider, const wx_camera *cameras, const wx_maps *maps,
                           int count, bool nearest, wx_error *err)
{
    memset(collider, 0, sizeof *collider);
    if (count > WX_MAX_INPUT_CAMERAS) {
        return wx_fail(err, WX_CAUSE_TOO_MANY, "%d input cameras; the collider takes at most %d",
                       count, WX_MAX_INPUT_CAMERAS);
    }
    collider->nearest = nearest;
    collider->cameras = calloc(count > 0 ? (size_t)count : 1, sizeof *collider->cameras);
    if (collider->cameras == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (collider)");
    }
    collider->camera_count = count;
    for (int c = 0; c < count; ++c) {
        wx_collider_camera *cam = &collider->cameras[c];
        const wx_maps *m = &maps[c];
        if (m->depth == NULL || m->normal == NULL || m->impact == NULL || m->width < 1 ||
            m->height < 1) {
            wx_collider_free(collider);
            return wx_fail(err, WX_CAUSE_BAD_ARGUMENT,
                           "input camera %d: the collider needs depth, normal and impact "
                           "maps",
                           c);
        }
        if ((cameras[c].width != 0 && cameras[c].width != m->width) ||
            (cameras[c].height != 0 && cameras[c].height != m->height)) {
            wx_collider_free(collider);
            return wx_fail(err, WX_CAUSE_MAP_SIZE,
                           "input camera %d: maps are %d x %d, the camera is %d x %d", c, m->width,
                           m->height, cameras[c].width, cameras[c].height);
        }
        cam->width = m->width;
        cam->height = m->height;
        wx_result r = setup_matrices(cam, cameras[c].wtc, c, err);
        if (r != WX_OK) {
            wx_collider_free(collider);
            return r;
        }
        int layers = wx_maps_layers(m);
        if (layers > WX_MAX_LAYERS) {
            wx_collider_free(collider);
            return wx_fail(err, WX_CAUSE_BAD_ARGUMENT,
                           "input camera %d: %d layers; the collider takes at most %d", c, layers,
                           WX_MAX_LAYERS);
        }
        size_t texels = (size_t)m->width * (size_t)m->height;
        cam->layers = layers;
        cam->depth = wx_big_malloc((size_t)layers * texels * sizeof *cam->depth);
        if (layers > 1) {
            cam->role = wx_big_malloc((size_t)layers * texels);
            cam->origin = wx_big_malloc((size_t)layers * texels);
        }
        if (cam->depth == NULL || (layers > 1 && (cam->role == NULL || cam->origin == NULL))) {
            wx_collider_free(collider);
            return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (collider depth)");
        }
        for (size_t t = 0; t < (size_t)layers * texels; ++t) {
            cam->depth[t] = wx_depth_is_empty(m->depth[t]) ? INFINITY : m->depth[t];
        }
        cam->frames_model = border_is_empty(cam->depth, m->width, m->height);
        cam->normal = m->normal;
        cam->impact = m->impact;
        if (layers > 1) {
            // A quarter texel (docs/physics.md, "Layered maps"): thick enough for
            // float rounding and to bridge the steps the silhouette rule leaves
            // along a sheet's edge, thin enough that a hit from behind lies
            // within half the collider's precision (half a texel) of the sheet.
            double bl =
                sqrt((double)cam->back[0] * cam->back[0] + (double)cam->back[1] * cam->back[1] +
                     (double)cam->back[2] * cam->back[2]);
            cam->sheet = 0.25 * cam->texel_ws / bl;
            classify_layers(cam);
        }
    }
    // Every camera's axis is known now: widen the layered cameras' crossings
    // by their margins, then build each pyramid from the depths as widened.
    double axes[WX_MAX_INPUT_CAMERAS][3];
    for (int c = 0; c < count; ++c) {
        const float *b = collider->cameras[c].back;
        double l = sqrt((double)b[0] * b[0] + (double)b[1] * b[1] + (double)b[2] * b[2]);
        for (int k = 0; k < 3; ++k) {
            axes[c][k] = l > 0.0 ? b[k] / l : 0.0;
        }
    }
    for (int c = 0; c < count; ++c) {
        if (collider->cameras[c].layers > 1) {
            widen_crossings(collider, (const double(*)[3])axes, &collider->cameras[c]);
        }
    }
    wx_result filled = wx_collider_fill_missed(collider, (const double(*)[3])axes, err);
    if (filled != WX_OK) {
        wx_collider_free(collider);
        return filled;
    }
    for (int c = 0; c < count; ++c) {
        cell_dips dips = { NULL, 0.0 };
        wx_result r = nearest ? WX_OK : curve_cells(&collider->cameras[c], &dips, err);
        if (r == WX_OK) {
            r = build_coarse(&collider->cameras[c], &dips, err);
        }
        free(dips.q);
        if (r != WX_OK) {
            wx_collider_free(collider);
            return r;
        }
    }
    for (int c = 0; c < count; ++c) {
        if (collider->cameras[c].layers > 1) {
            for (int k = 0; k < count; ++k) {
                collider->layered_slack =
                    fmax(collider->layered_slack, (double)collider->cameras[k].texel_ws);
            }
            break;
        }
    }
    return WX_OK;
}

wx_result wx_collider_view(wx_collider *view, const wx_collider *shared, const wx_maps *maps,
                           wx_error *err)
{
    memset(view, 0, sizeof *view);
    for (int c = 0; c < shared->camera_count; ++c) {
        const wx_collider_camera *cam = &shared->cameras[c];
        if (maps[c].impact == NULL || maps[c].width != cam->width ||
            maps[c].height != cam->height || wx_maps_layers(&maps[c]) != cam->layers) {
            return wx_fail(err, WX_CAUSE_BAD_ARGUMENT,
                           "input camera %d: its impact map does not match the shared collider", c);
        }
    }
    *view = *shared;
    view->cameras = malloc((size_t)shared->camera_count * sizeof *view->cameras + 1);
    if (view->cameras == NULL) {
        memset(view, 0, sizeof *view);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "collider: out of memory");
    }
    memcpy(view->cameras, shared->cameras, (size_t)shared->camera_count * sizeof *view->cameras);
    for (int c = 0; c < shared->camera_count; ++c) {
        view->cameras[c].impact = maps[c].impact;
    }
    view->view = true;
    return WX_OK;
}

void wx_collider_free(wx_collider *collider)
{
    for (int c = 0; c < collider->camera_count && !collider->view; ++c) {
        free(collider->cameras[c].depth);
        free(collider->cameras[c].role);
        free(collider->cameras[c].origin);
        free(collider->cameras[c].coarse);
        free(collider->cameras[c].near3);
        free(collider->cameras[c].fill);
        free(collider->cameras[c].curve);
    }
    free(collider->cameras);
    memset(collider, 0, sizeof *collider);
}
