// collider.c: the projected-maps collider (thesis 4.8.4.1, docs/design.md section 4):
// the depth surface, the point rule and the swept test. Its construction is in
// collider_build.c, the coarse test in collider_coarse.c.
#include "sim/collider.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/matrix.h"
#include "sim/force_field.h"
#include "sim/particles.h"
#include "sim/collider_internal.h"

// --- the depth surface ---------------------------------------------------------

// Index of the maps' planes (normal, impact) of crossing k of texel t: the
// layer it came from.
static inline size_t maps_index(const wx_collider_camera *cam, int k, size_t t)
{
    size_t texels = (size_t)cam->width * (size_t)cam->height;
    size_t layer = cam->layers > 1 ? cam->origin[(size_t)k * texels + t] : 0;
    return layer * texels + t;
}

// fmin and fmax are library calls unless NaN semantics are relaxed; these are
// plain compares (no NaN reaches them).
static inline double dmin(double a, double b)
{
    return a < b ? a : b;
}

static inline double dmax(double a, double b)
{
    return a > b ? a : b;
}

static inline int clampi(int v, int lo, int hi)
{
    return v < lo ? lo : (v > hi ? hi : v);
}

// The depth function over one half-texel cell (hx, hy) (half-texel units):
// depth(X, Y) = k0 + k1*fx + k2*fy + k3*fx*fy with fx = X - ox, fy = Y - oy.
// Returns false when the cell's texel holds no surface.
typedef struct cell_depth {
    double k0, k1, k2, k3;
    double k4, k5; ///< second-order terms: + k4 fx^2 + k5 fy^2 (curve_terms)
    double ox, oy;
} cell_depth;

// The bilinear depth over the cell whose corners are the centres of texels
// (i0, j0), (i0+1, j0), (i0, j0+1), (i0+1, j0+1), of depths d00, d10, d01, d11.
static void bilinear_cell(cell_depth *cd, int i0, int j0, double d00, double d10, double d01,
                          double d11)
{
    cd->ox = i0 + 0.5;
    cd->oy = j0 + 0.5;
    cd->k0 = d00;
    cd->k1 = d10 - d00;
    cd->k2 = d01 - d00;
    cd->k3 = d00 - d10 - d01 + d11;
    cd->k4 = cd->k5 = 0.0;
}

// Adds the second-order terms of the cell whose first corner is texel (i0, j0)
// of the layer at index `plane` to a bilinear cell: depth += a/2 fx (fx - 1) +
// b/2 fy (fy - 1), which is 0 at the corners (collider_build.c, curve_cells).
// A cell by the map's border (corners clamped onto one texel) has none.
static inline void curve_terms(const wx_collider_camera *cam, size_t plane, int i0, int j0,
                               cell_depth *cd)
{
    if (cam->curve == NULL || i0 < 0 || j0 < 0 || i0 + 1 >= cam->width || j0 + 1 >= cam->height) {
        return;
    }
    size_t at = plane + (size_t)j0 * (size_t)cam->width + (size_t)i0;
    double a = 0.5 * cam->curve_unit * cam->curve[2 * at];
    double b = 0.5 * cam->curve_unit * cam->curve[2 * at + 1];
    cd->k4 = a;
    cd->k5 = b;
    cd->k1 -= a;
    cd->k2 -= b;
}

static bool cell_surface(const wx_collider *collider, const wx_collider_camera *cam, int hx,
                         int hy, cell_depth *cd)
{
    int W = cam->width, H = cam->height;
    int tx = hx >> 1, ty = hy >> 1;
    float own = cam->depth[(size_t)ty * (size_t)W + (size_t)tx];
    if (!isfinite(own)) {
        return false;
    }
    cd->k1 = cd->k2 = cd->k3 = cd->k4 = cd->k5 = 0.0;
    cd->k0 = own;
    cd->ox = cd->oy = 0.0;
    if (collider->nearest) {
        return true;
    }
    // The bilinear cell between texel centres: corners i0, i0+1 and j0, j0+1.
    int i0 = hx / 2 - 1 + (hx & 1), j0 = hy / 2 - 1 + (hy & 1);
    int ia = clampi(i0, 0, W - 1), ib = clampi(i0 + 1, 0, W - 1);
    int ja = clampi(j0, 0, H - 1), jb = clampi(j0 + 1, 0, H - 1);
    const float *row_a = cam->depth + (size_t)ja * (size_t)W;
    const float *row_b = cam->depth + (size_t)jb * (size_t)W;
    double d00 = row_a[ia], d10 = row_a[ib], d01 = row_b[ia], d11 = row_b[ib];
    if (!isfinite(d00) || !isfinite(d10) || !isfinite(d01) || !isfinite(d11)) {
        return true; // silhouette: the texel's own depth
    }
    // A fill is no surface: its start blended with a face beside it would tilt
    // the face into the solid (along a cube's edge, a sliver behind its side
    // said "free" and drops fell through the corner of its top).
    if (cam->fill != NULL) {
        const uint8_t *fa = cam->fill + (size_t)ja * (size_t)W;
        const uint8_t *fb = cam->fill + (size_t)jb * (size_t)W;
        if ((fa[ia] | fa[ib] | fb[ia] | fb[ib]) != 0) {
            return true;
        }
    }
    bilinear_cell(cd, i0, j0, d00, d10, d01, d11);
    curve_terms(cam, 0, i0, j0, cd);
    return true;
}

// Whether crossing k at index `at` (planes of one layer) lies strictly between
// crossings k-1 and k+1 of the texel at index `of` (k-1 none for k = 0, k+1
// none past the last layer or an empty one).
static inline bool crossing_between(const wx_collider_camera *cam, int k, size_t at, size_t of)
{
    size_t layer = (size_t)cam->width * (size_t)cam->height;
    double d = cam->depth[at];
    if (k > 0 && !(d > cam->depth[of - layer])) {
        return false;
    }
    return k + 1 >= cam->layers || !(d >= cam->depth[of + layer]);
}

// Layer k's depth over half-texel cell (hx, hy) of a camera with layers, whose
// own texel holds crossing `own` with role `own_role`: the bilinear cell when
// the four texels around hold layer k facing the same way (the silhouette rule
// generalised: a layer's surface is smooth where its neighbours see the same
// side of something), else the texel's own depth.
static void layer_cell(const wx_collider *collider, const wx_collider_camera *cam, int k,
                       int hx, int hy, float own, uint8_t own_role, cell_depth *cd)
{
    cd->k1 = cd->k2 = cd->k3 = cd->k4 = cd->k5 = 0.0;
    cd->k0 = own;
    cd->ox = cd->oy = 0.0;
    if (collider->nearest) {
        return;
    }
    int W = cam->width, H = cam->height;
    size_t plane = (size_t)k * (size_t)W * (size_t)H;
    int i0 = hx / 2 - 1 + (hx & 1), j0 = hy / 2 - 1 + (hy & 1);
    int ia = clampi(i0, 0, W - 1), ib = clampi(i0 + 1, 0, W - 1);
    int ja = clampi(j0, 0, H - 1), jb = clampi(j0 + 1, 0, H - 1);
    size_t ra = plane + (size_t)ja * (size_t)W, rb = plane + (size_t)jb * (size_t)W;
    if (cam->curve != NULL) {
        // Its own cache line: asked for now, it comes while the checks below
        // read the corners.
        __builtin_prefetch(cam->curve + 2 * (ra + ia));
    }
    double d00 = cam->depth[ra + ia], d10 = cam->depth[ra + ib];
    double d01 = cam->depth[rb + ia], d11 = cam->depth[rb + ib];
    if (!isfinite(d00) || !isfinite(d10) || !isfinite(d01) || !isfinite(d11)) {
        return;
    }
    unsigned differ = (unsigned)(cam->role[ra + ia] ^ own_role) |
                      (unsigned)(cam->role[ra + ib] ^ own_role) |
                      (unsigned)(cam->role[rb + ia] ^ own_role) |
                      (unsigned)(cam->role[rb + ib] ^ own_role);
    if (differ & (WX_ROLE_FACING | WX_ROLE_FILL)) {
        return; // nor between a fill and a surface (cell_surface)
    }
    // Nor across a jump from one surface to another that happen to be the
    // k-th crossing of neighbouring texels (a handrail's front and the glass
    // behind it, in the row where the handrail ends): each corner's crossing
    // must lie between the own texel's crossings k-1 and k+1, and the own one
    // between the corner's. Else the ramp between them is a thin solid slab
    // sweeping through the free space between the two (drops stopped in mid
    // air above a sill behind a balcony's handrail).
    const size_t corners[4] = { ra + ia, ra + ib, rb + ia, rb + ib };
    size_t at = plane + (size_t)(hy >> 1) * (size_t)W + (size_t)(hx >> 1);
    for (int c = 0; c < 4; ++c) {
        if (!crossing_between(cam, k, corners[c], at) ||
            !crossing_between(cam, k, at, corners[c])) {
            return;
        }
    }
    bilinear_cell(cd, i0, j0, d00, d10, d01, d11);
    curve_terms(cam, plane, i0, j0, cd);
}

static inline double cell_value(const cell_depth *cd, double X, double Y)
{
    double fx = X - cd->ox, fy = Y - cd->oy;
    return cd->k0 + cd->k1 * fx + cd->k2 * fy + cd->k3 * fx * fy + cd->k4 * fx * fx +
           cd->k5 * fy * fy;
}

// Where a sheet's slab starts, past its crossing's depth: the slab lies on the
// side its outward normal points away from, where a solid would be: behind the
// crossing (along the view) when the camera sees the sheet's front, in front of
// it when it sees its back. So cameras that see a sheet from opposite sides
// agree on one slab, a quarter texel thick, not two that only touch.
static inline double sheet_start(const wx_collider_camera *cam, uint8_t role)
{
    return (role & WX_ROLE_FACING) ? 0.0 : -cam->sheet;
}

// The crossings' depths at texel-space point (X, Y) inside the frame of a camera
// with layers: how many there are (layers after the first empty one hold none),
// their depths and roles.
static int layer_depths(const wx_collider *collider, const wx_collider_camera *cam, double X,
                        double Y, double depth[WX_MAX_LAYERS], uint8_t role[WX_MAX_LAYERS])
{
    int hx = clampi((int)(2.0 * X), 0, 2 * cam->width - 1);
    int hy = clampi((int)(2.0 * Y), 0, 2 * cam->height - 1);
    size_t texels = (size_t)cam->width * (size_t)cam->height;
    size_t t = (size_t)(hy >> 1) * (size_t)cam->width + (size_t)(hx >> 1);
    int n = 0;
    for (; n < cam->layers; ++n) {
        float own = cam->depth[(size_t)n * texels + t];
        if (!isfinite(own)) {
            break;
        }
        role[n] = cam->role[(size_t)n * texels + t];
        cell_depth cd;
        layer_cell(collider, cam, n, hx, hy, own, role[n], &cd);
        depth[n] = cell_value(&cd, X, Y);
    }
    return n;
}

// The point rule of one camera with layers at (X, Y, D) inside its frame: D lies
// strictly inside one of the solid intervals or sheet slabs of the crossings.
static bool layers_may_collide(const wx_collider *collider, const wx_collider_camera *cam,
                               double X, double Y, double D)
{
    double depth[WX_MAX_LAYERS];
    uint8_t role[WX_MAX_LAYERS];
    int n = layer_depths(collider, cam, X, Y, depth, role);
    for (int k = 0; k < n; ++k) {
        switch (role[k] & WX_ROLE_KIND) {
        case WX_ROLE_ENTER:
            if (D > depth[k] && D < depth[k + 1]) {
                return true;
            }
            break;
        case WX_ROLE_SHEET: {
            double front = depth[k] + sheet_start(cam, role[k]);
            if (D > front && D < front + cam->sheet) {
                return true;
            }
            break;
        }
        case WX_ROLE_TAIL:
            if (D > depth[k]) {
                return true;
            }
            break;
        default:
            break;
        }
    }
    return false;
}

double wx_collider_depth_at(const wx_collider *collider, int c, double X, double Y)
{
    const wx_collider_camera *cam = &collider->cameras[c];
    if (!(X >= 0.0 && X < cam->width && Y >= 0.0 && Y < cam->height)) {
        return INFINITY;
    }
    if (cam->layers > 1) {
        double depth[WX_MAX_LAYERS];
        uint8_t role[WX_MAX_LAYERS];
        return layer_depths(collider, cam, X, Y, depth, role) > 0 ? depth[0] : INFINITY;
    }
    int hx = clampi((int)(2.0 * X), 0, 2 * cam->width - 1);
    int hy = clampi((int)(2.0 * Y), 0, 2 * cam->height - 1);
    cell_depth cd;
    if (!cell_surface(collider, cam, hx, hy, &cd)) {
        return INFINITY;
    }
    return cell_value(&cd, X, Y);
}

// Camera c's answer for a point (X, Y, D) inside its frame: it may collide
// (behind its surface, or inside one of its solid intervals with layers).
bool wx_collider_camera_may_collide(const wx_collider *collider, int c, double X, double Y,
                                    double D)
{
    const wx_collider_camera *cam = &collider->cameras[c];
    if (cam->layers > 1) {
        return layers_may_collide(collider, cam, X, Y, D);
    }
    return D > wx_collider_depth_at(collider, c, X, Y);
}

bool wx_collider_point_collides(const wx_collider *collider, const float p[3])
{
    // p in every camera's texel space, once for both passes below (a collider
    // holds at most WX_MAX_INPUT_CAMERAS cameras).
    double X[WX_MAX_INPUT_CAMERAS], Y[WX_MAX_INPUT_CAMERAS], D[WX_MAX_INPUT_CAMERAS];
    bool inside[WX_MAX_INPUT_CAMERAS];
    // First the cheap bound: a camera that sees p in front of its texel's
    // near3 says "in front" (near3 bounds every crossing the rule below reads
    // there), and one such camera frees the point.
    for (int c = 0; c < collider->camera_count; ++c) {
        const wx_collider_camera *cam = &collider->cameras[c];
        X[c] = p[0] * cam->mx[0] + p[1] * cam->mx[1] + p[2] * cam->mx[2] + cam->mx[3];
        Y[c] = p[0] * cam->my[0] + p[1] * cam->my[1] + p[2] * cam->my[2] + cam->my[3];
        D[c] = p[0] * cam->md[0] + p[1] * cam->md[1] + p[2] * cam->md[2] + cam->md[3];
        inside[c] = X[c] >= 0.0 && X[c] < cam->width && Y[c] >= 0.0 && Y[c] < cam->height;
        if (inside[c] &&
            D[c] < cam->near3[(size_t)(int)Y[c] * (size_t)cam->width + (size_t)(int)X[c]]) {
            return false;
        }
    }
    bool informed = false;
    for (int c = 0; c < collider->camera_count; ++c) {
        const wx_collider_camera *cam = &collider->cameras[c];
        if (!inside[c]) {
            if (cam->frames_model) {
                return false; // the whole model is inside this frame, p is not
            }
            continue; // no information
        }
        informed = true;
        if (!wx_collider_camera_may_collide(collider, c, X[c], Y[c], D[c])) {
            return false; // this camera sees the point in front (or no surface)
        }
    }
    return informed;
}

// --- the swept test -------------------------------------------------------------

// One camera's walk along the segment: X(s) = X0 + s*dX etc. in texel space,
// through half-texel cells. f(s) = D(s) - depth(X(s), Y(s)) = A + B s + C s^2 in
// the current cell; the camera says "behind" where f >= 0.
typedef struct march {
    const wx_collider_camera *cam;
    double X0, Y0, D0, dX, dY, dD;
    double rX, rY; ///< 1/dX, 1/dY (0 when the segment does not move along that axis)
    double s_in, s_out; ///< the segment's line is inside the frame for s in [s_in, s_out)
    bool placed;        ///< a current cell exists
    int hx, hy;         ///< current half-texel cell
    double tnx, tny;    ///< parameters of its next x and y boundaries
    double sa, sb;      ///< its parameter interval
    bool surface;       ///< the cell's texel holds a surface
    double A, B, C;     ///< f over the cell
    // With layers: f_k = D - depth_k = LA + LB s + LC s^2 for the cell texel's
    // `count` crossings, their roles, and the crossing whose interval or slab
    // the last answer of march_entry lies in (-1: none).
    int count;
    int hit_k;
    uint8_t role[WX_MAX_LAYERS];
    double LA[WX_MAX_LAYERS], LB[WX_MAX_LAYERS], LC[WX_MAX_LAYERS];
    /// The crossings' functions are made when the segment can reach them
    /// (layers_first): `near` bounds every crossing's depth in the cell from
    /// below (the least first crossing of the four texels around it), and
    /// `ready` says the functions are made.
    double near;
    bool ready;
    const wx_collider *collider;
} march;

// Parameter interval where lo <= P0 + s*dP < hi, intersected into [*a, *b);
// r = 1/dP, or 0 when dP is 0.
static void clip_slab(double P0, double r, double lo, double hi, double *a, double *b)
{
    if (r == 0.0) {
        if (!(P0 >= lo && P0 < hi)) {
            *a = INFINITY;
            *b = -INFINITY;
        }
        return;
    }
    double t0 = (lo - P0) * r, t1 = (hi - P0) * r;
    if (t0 > t1) {
        double t = t0;
        t0 = t1;
        t1 = t;
    }
    *a = dmax(*a, t0);
    *b = dmin(*b, t1);
}

static void march_init(march *m, const wx_collider_camera *cam, const double p0[3],
                       const double d[3])
{
    m->cam = cam;
    m->ready = false;
    m->X0 = p0[0] * cam->mx[0] + p0[1] * cam->mx[1] + p0[2] * cam->mx[2] + cam->mx[3];
    m->Y0 = p0[0] * cam->my[0] + p0[1] * cam->my[1] + p0[2] * cam->my[2] + cam->my[3];
    m->D0 = p0[0] * cam->md[0] + p0[1] * cam->md[1] + p0[2] * cam->md[2] + cam->md[3];
    m->dX = d[0] * cam->mx[0] + d[1] * cam->mx[1] + d[2] * cam->mx[2];
    m->dY = d[0] * cam->my[0] + d[1] * cam->my[1] + d[2] * cam->my[2];
    m->dD = d[0] * cam->md[0] + d[1] * cam->md[1] + d[2] * cam->md[2];
    m->rX = m->dX != 0.0 ? 1.0 / m->dX : 0.0;
    m->rY = m->dY != 0.0 ? 1.0 / m->dY : 0.0;
    m->s_in = -INFINITY;
    m->s_out = INFINITY;
    clip_slab(m->X0, m->rX, 0.0, cam->width, &m->s_in, &m->s_out);
    clip_slab(m->Y0, m->rY, 0.0, cam->height, &m->s_in, &m->s_out);
    m->placed = false;
    m->hit_k = -1;
}

static inline bool march_inside(const march *m, double s)
{
    return s >= m->s_in && s < m->s_out;
}

// Parameter of the next cell boundary along one axis after cell index h
// (r = 1/dP, or 0 when the segment does not move along the axis).
static double next_boundary(double P0, double r, int h)
{
    if (r > 0.0) {
        return ((h + 1) * 0.5 - P0) * r;
    }
    if (r < 0.0) {
        return (h * 0.5 - P0) * r;
    }
    return INFINITY;
}

// The cell's depth along the segment: depth(s) = c[0] + c[1] s + c[2] s^2, from
// k0 + k1 fx + k2 fy + k3 fx fy + k4 fx^2 + k5 fy^2 with fx = fx0 + s dX,
// fy = fy0 + s dY.
static inline void cell_along(const cell_depth *cd, const march *m, double c[3])
{
    double fx0 = m->X0 - cd->ox, fy0 = m->Y0 - cd->oy;
    c[0] = cell_value(cd, m->X0, m->Y0);
    c[1] = cd->k1 * m->dX + cd->k2 * m->dY + cd->k3 * (fx0 * m->dY + fy0 * m->dX) +
           2.0 * (cd->k4 * fx0 * m->dX + cd->k5 * fy0 * m->dY);
    c[2] = cd->k3 * m->dX * m->dY + cd->k4 * m->dX * m->dX + cd->k5 * m->dY * m->dY;
}

// The cell's functions f_k for a camera with layers.
// The cell's crossings: how many, and a bound below their depths anywhere in
// the cell. Every crossing's depth in the cell is bilinear between the four
// texels around it or the cell texel's own (one of the four), and each
// texel's crossings lie at or behind its first, so none lies nearer than the
// least first crossing of the four, less the largest dip of any curved cell
// (`bulge_most`): a segment in front of that bound (by a sheet's thickness)
// meets nothing in the cell, and the crossings' functions are not made
// (make_layers).
static void cell_layers(const wx_collider *collider, march *m)
{
    const wx_collider_camera *cam = m->cam;
    size_t texels = (size_t)cam->width * (size_t)cam->height;
    size_t t = (size_t)(m->hy >> 1) * (size_t)cam->width + (size_t)(m->hx >> 1);
    (void)collider;
    int n = 0;
    while (n < cam->layers && isfinite(cam->depth[(size_t)n * texels + t])) {
        n++;
    }
    int W = cam->width, H = cam->height;
    int i0 = m->hx / 2 - 1 + (m->hx & 1), j0 = m->hy / 2 - 1 + (m->hy & 1);
    int ia = clampi(i0, 0, W - 1), ib = clampi(i0 + 1, 0, W - 1);
    int ja = clampi(j0, 0, H - 1), jb = clampi(j0 + 1, 0, H - 1);
    const float *ra = cam->depth + (size_t)ja * (size_t)W, *rb = cam->depth + (size_t)jb * (size_t)W;
    m->near = dmin(dmin(ra[ia], ra[ib]), dmin(rb[ia], rb[ib]));
    m->near -= cam->bulge_most; // curved cells dip in front of their corners
    m->count = n;
    m->surface = n > 0;
    m->ready = false;
}

// The functions f_k of the cell's crossings (cell_layers).
static void make_layers(march *m)
{
    const wx_collider *collider = m->collider;
    const wx_collider_camera *cam = m->cam;
    size_t texels = (size_t)cam->width * (size_t)cam->height;
    size_t t = (size_t)(m->hy >> 1) * (size_t)cam->width + (size_t)(m->hx >> 1);
    int n = 0;
    for (; n < m->count; ++n) {
        float own = cam->depth[(size_t)n * texels + t];
        if (!isfinite(own)) {
            break;
        }
        uint8_t role = cam->role[(size_t)n * texels + t];
        cell_depth cd;
        layer_cell(collider, cam, n, m->hx, m->hy, own, role, &cd);
        double c[3];
        cell_along(&cd, m, c);
        m->role[n] = role;
        m->LA[n] = m->D0 - c[0];
        m->LB[n] = m->dD - c[1];
        m->LC[n] = -c[2];
    }
    m->ready = true;
}

static void cell_function(const wx_collider *collider, march *m)
{
    if (m->cam->layers > 1) {
        cell_layers(collider, m);
        return;
    }
    cell_depth cd;
    m->surface = cell_surface(collider, m->cam, m->hx, m->hy, &cd);
    if (!m->surface) {
        return;
    }
    double c[3];
    cell_along(&cd, m, c);
    m->A = m->D0 - c[0];
    m->B = m->dD - c[1];
    m->C = -c[2];
}

// Puts the walk in the cell that holds parameter s (s inside the frame).
static void march_place(const wx_collider *collider, march *m, double s)
{
    const wx_collider_camera *cam = m->cam;
    double X = m->X0 + s * m->dX, Y = m->Y0 + s * m->dY;
    m->hx = clampi((int)floor(2.0 * X), 0, 2 * cam->width - 1);
    m->hy = clampi((int)floor(2.0 * Y), 0, 2 * cam->height - 1);
    m->tnx = next_boundary(m->X0, m->rX, m->hx);
    m->tny = next_boundary(m->Y0, m->rY, m->hy);
    m->sa = s;
    m->sb = dmin(m->tnx, m->tny);
    m->placed = true;
    cell_function(collider, m);
}

// Steps to the next cell; false when the walk leaves the map.
static bool march_advance(const wx_collider *collider, march *m)
{
    const wx_collider_camera *cam = m->cam;
    double nx = m->tnx, ny = m->tny;
    if (nx <= ny) {
        m->hx += m->rX > 0.0 ? 1 : -1;
        m->tnx = next_boundary(m->X0, m->rX, m->hx);
    }
    if (ny <= nx) {
        m->hy += m->rY > 0.0 ? 1 : -1;
        m->tny = next_boundary(m->Y0, m->rY, m->hy);
    }
    if (m->hx < 0 || m->hx >= 2 * cam->width || m->hy < 0 || m->hy >= 2 * cam->height) {
        return false;
    }
    m->sa = dmin(nx, ny);
    m->sb = dmin(m->tnx, m->tny);
    cell_function(collider, m);
    return true;
}

// Smallest s in [lo, hi] with A + B s + C s^2 >= 0, or +inf.
static double first_nonnegative(double A, double B, double C, double lo, double hi)
{
    double f = A + lo * (B + lo * C);
    if (f >= 0.0) {
        return lo;
    }
    double g = B + 2.0 * C * lo; // slope at lo
    double len = hi - lo;
    double tau;
    // Relative to the other terms over the interval, is the curvature negligible?
    if (fabs(C) * len * len <= 1e-12 * (fabs(f) + fabs(g) * len)) {
        if (!(g > 0.0)) {
            return INFINITY;
        }
        tau = -f / g;
    } else {
        double disc = g * g - 4.0 * C * f;
        if (disc < 0.0) {
            return INFINITY;
        }
        double q = -0.5 * (g + copysign(sqrt(disc), g));
        double r1 = q / C;
        double r2 = q != 0.0 ? f / q : INFINITY;
        if (r1 > r2) {
            double t = r1;
            r1 = r2;
            r2 = t;
        }
        tau = r1 > 0.0 ? r1 : r2;
        if (!(tau > 0.0)) {
            return INFINITY;
        }
    }
    return tau <= len ? lo + tau : INFINITY;
}

// Smallest s in [lo, hi] with g1(s) >= 0 and, when `bounded`, g2(s) <= 0 (inside
// [enter, leave] of a solid interval, f measured from each face): leapfrogs
// between the two conditions, each step past a root of one quadratic, so a few
// rounds settle it; +inf when none.
static double first_between(double A1, double B1, double C1, bool bounded, double A2, double B2,
                            double C2, double lo, double hi)
{
    double s = lo;
    for (int round = 0; round < 8; ++round) {
        double s1 = first_nonnegative(A1, B1, C1, s, hi);
        if (!(s1 <= hi)) {
            return INFINITY;
        }
        if (!bounded || A2 + s1 * (B2 + s1 * C2) <= 0.0) {
            return s1;
        }
        double s2 = first_nonnegative(-A2, -B2, -C2, s1, hi);
        if (!(s2 <= hi)) {
            return INFINITY;
        }
        if (A1 + s2 * (B1 + s2 * C1) >= 0.0) {
            return s2;
        }
        s = s2;
    }
    return INFINITY;
}

// With layers: the smallest s in [lo, hi] inside one of the cell texel's solid
// intervals or sheet slabs (m->hit_k: the crossing that starts it), or +inf.
static double layers_first(march *m, double lo, double hi)
{
    double best = INFINITY;
    double sheet = m->cam->sheet;
    if (!m->ready) {
        // In front of every crossing of the cell over [lo, hi] (d is linear
        // in s): nothing to meet here.
        double d_far = dmax(m->D0 + lo * m->dD, m->D0 + hi * m->dD);
        if (d_far < m->near - 2.0 * sheet) {
            return INFINITY;
        }
        make_layers(m);
    }
    for (int k = 0; k < m->count; ++k) {
        int kind = m->role[k] & WX_ROLE_KIND;
        double r;
        double top = dmin(hi, best);
        if (kind == WX_ROLE_ENTER) {
            r = first_between(m->LA[k], m->LB[k], m->LC[k], true, m->LA[k + 1], m->LB[k + 1],
                              m->LC[k + 1], lo, top);
        } else if (kind == WX_ROLE_SHEET) {
            double front = m->LA[k] - sheet_start(m->cam, m->role[k]);
            r = first_between(front, m->LB[k], m->LC[k], true, front - sheet, m->LB[k],
                              m->LC[k], lo, top);
        } else if (kind == WX_ROLE_TAIL) {
            r = first_nonnegative(m->LA[k], m->LB[k], m->LC[k], lo, top);
        } else {
            continue;
        }
        if (r < best) {
            best = r;
            m->hit_k = k;
        }
    }
    return best;
}

// The face of a camera with layers that a hit at s (inside the interval or slab
// of crossing m->hit_k) is on: the nearer of the interval's two faces (the
// entering one for a particle from the front, the leaving one from behind; a
// sheet's front or back). `dist` is how far behind that face (into the solid)
// the point lies, `side` +1 when the free side is towards the camera, -1 when
// away, `offset` the face's depth past the crossing's (a sheet's faces: where
// its slab starts and ends).
typedef struct layer_face {
    int layer;
    double dist, side, offset;
} layer_face;

static layer_face hit_face(const march *m, double s)
{
    int k = m->hit_k;
    double fk = m->LA[k] + s * (m->LB[k] + s * m->LC[k]);
    layer_face face = { k, fk, 1.0, 0.0 };
    int kind = m->role[k] & WX_ROLE_KIND;
    if (kind == WX_ROLE_ENTER) {
        double fl = m->LA[k + 1] + s * (m->LB[k + 1] + s * m->LC[k + 1]);
        if (-fl < fk) {
            face = (layer_face){ k + 1, -fl, -1.0, 0.0 };
        }
    } else if (kind == WX_ROLE_SHEET) {
        double start = sheet_start(m->cam, m->role[k]), end = start + m->cam->sheet;
        face = (layer_face){ k, fk - start, 1.0, start };
        if (end - fk < fk - start) {
            face = (layer_face){ k, end - fk, -1.0, end };
        }
    }
    return face;
}

// The smallest s' >= s where this camera puts the segment's point behind its
// surface or outside its frame (both let a collision happen, unless the camera
// frames the whole model: then outside is free space); > 1 when none within the
// segment.
static double march_entry(const wx_collider *collider, march *m, double s)
{
    bool frames = m->cam->frames_model;
    if (!march_inside(m, s)) {
        if (!frames) {
            return s;
        }
        if (s < m->s_in && m->s_in <= 1.0 && m->s_in < m->s_out) {
            s = m->s_in; // free space up to the frame, then the map decides
        } else {
            return 2.0;
        }
    }
    if (!m->placed || s >= m->sb || s < m->sa) {
        march_place(collider, m, s);
    }
    double end = dmin(m->s_out, 1.0);
    for (int guard = 0; guard < 8 * (m->cam->width + m->cam->height) + 16; ++guard) {
        double lo = dmax(s, m->sa);
        double hi = dmin(m->sb, end);
        if (m->surface && lo <= hi) {
            double r = m->cam->layers > 1 ? layers_first(m, lo, hi)
                                          : first_nonnegative(m->A, m->B, m->C, lo, hi);
            if (r <= hi) {
                return r;
            }
        }
        if (m->sb >= end) {
            return m->s_out <= 1.0 && !frames ? m->s_out : 2.0;
        }
        if (!march_advance(collider, m)) {
            return m->s_out <= 1.0 && !frames ? m->s_out : 2.0;
        }
    }
    return 2.0;
}

// The camera that gives the hit at parameter s: docs/design.md section 4's "smallest
// d - depth", read to each map's precision. Across one texel, the depth of a
// surface seen at angle theta changes by texel * tan(theta), so a camera that
// sees the surface at a grazing angle has d - depth near 0 over a wide band and
// would win hits that belong to a camera seeing the same surface head-on. Such a
// camera's texel covers a long strip of surface while it wins only part of the
// strip's hits, so its dirt per area comes out too low and the mask shows the
// cameras' patches. So: among the cameras whose d - depth is within half a texel
// plus one texel's worth of that slope (against the bilinear depth and against
// the hit texel's own depth), the most head-on one (largest |N.view|,
// the camera `bake` gives initial dirt to) gives the hit; without any, the
// smallest d - depth. -1 when no camera sees a surface at s.
//
// Along a convex edge two cameras can be within their precision of the hit
// and hold two surfaces: a drop falling on a roof a few millimetres from its
// eave lies within the front camera's precision (and, with layers, its slack
// of a texel) behind the wall it sees head-on. That camera took the hit, put
// the drop back in front of the wall (off the roof, where it fell), and the
// roof's last texel row got none of its rain (docs/physics.md, "Where a hit
// lands"). So the surface hit is the one the segment enters most (the least
// N . dir of the candidates' normals), and only cameras whose normal agrees
// with that one's (PICK_SAME_SURFACE) compete by |N.view|: on a smooth
// surface every candidate agrees and the rule above is unchanged.
// Ties of |N.view| within this go to the camera outside the surface
// (model/ownership.c's TIE_COSINE).
#define PICK_TIE_COSINE 1e-4
// Two candidates' unit normals hold the same surface when N1 . N2 is at least
// this (60 degrees: a texel's normals on a curved surface agree far better;
// the faces of an edge a camera grid resolves meet at more).
#define PICK_SAME_SURFACE 0.5

static int pick_camera(const wx_collider *collider, const march *m, double s, const double dir[3])
{
    int best = -1, closest = -1, filled = -1;
    double best_cos = -1.0, closest_f = INFINITY;
    bool best_facing = true;
    // The cameras that may record the hit (within their precision), with
    // their |N.view|, facing and unit normal.
    int cand[WX_MAX_INPUT_CAMERAS];
    double cand_cos[WX_MAX_INPUT_CAMERAS], cand_n[WX_MAX_INPUT_CAMERAS][3];
    bool cand_facing[WX_MAX_INPUT_CAMERAS];
    int cands = 0;
    for (int c = 0; c < collider->camera_count; ++c) {
        if (!march_inside(&m[c], s) || !m[c].surface) {
            continue;
        }
        const wx_collider_camera *cam = &collider->cameras[c];
        double f = m[c].A + s * (m[c].B + s * m[c].C);
        size_t texel = (size_t)(m[c].hy >> 1) * (size_t)cam->width + (size_t)(m[c].hx >> 1);
        size_t in_maps = texel;
        double face_depth = 0.0;
        if (cam->layers > 1) {
            // The chosen layer's face: its distance and its own texel's depth.
            if (m[c].hit_k < 0) {
                continue;
            }
            layer_face face = hit_face(&m[c], s);
            if (m[c].role[face.layer] & WX_ROLE_FILL) {
                filled = filled < 0 ? c : filled;
                continue; // a fill is no surface
            }
            f = face.dist;
            in_maps = maps_index(cam, face.layer, texel);
            texel += (size_t)face.layer * (size_t)cam->width * (size_t)cam->height;
            face_depth = face.offset;
        } else if (cam->fill != NULL && cam->fill[texel]) {
            filled = filled < 0 ? c : filled;
            continue;
        }
        if (closest < 0 || f < closest_f) {
            closest = c;
            closest_f = f;
        }
        const float *n = cam->normal + 3 * in_maps;
        double bl = sqrt((double)cam->back[0] * cam->back[0] + (double)cam->back[1] * cam->back[1] +
                         (double)cam->back[2] * cam->back[2]);
        double nl = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
        if (!(bl > 0.0) || !(nl > 1e-6) || !isfinite(nl)) {
            continue;
        }
        double cos_view = fabs(n[0] * cam->back[0] + n[1] * cam->back[1] + n[2] * cam->back[2]) /
                          (bl * nl);
        double tan_view = sqrt(dmax(0.0, 1.0 - cos_view * cos_view)) / dmax(cos_view, 0.05);
        double precision = cam->texel_ws * (0.5 + tan_view) + collider->layered_slack;
        // The texel itself must record this surface too: between a wall and a
        // slab's edge in front of it the bilinear depth is no surface at all,
        // and a point behind it (on the ground between them) is not seen there.
        double d = m[c].D0 + s * m[c].dD;
        double off = fabs(d - ((double)cam->depth[texel] + face_depth)) * bl;
        // Two cameras facing each other see every surface equally head-on;
        // with layers one sees it from outside, the other through the solid,
        // in a layer whose index changes wherever another part crosses its
        // rays. The one outside takes the tie (as ownership does), so a
        // surface's deposits do not follow those patches.
        bool facing = cam->layers <= 1 ||
                      n[0] * cam->back[0] + n[1] * cam->back[1] + n[2] * cam->back[2] > 0.0f;
        if (f * bl <= precision && off <= precision) {
            cand[cands] = c;
            cand_cos[cands] = cos_view;
            cand_facing[cands] = facing;
            for (int k = 0; k < 3; ++k) {
                cand_n[cands][k] = n[k] / nl;
            }
            cands++;
        }
    }
    // The surface the segment enters most: the candidates' reference.
    int entered = 0;
    double least = INFINITY;
    for (int q = 0; q < cands; ++q) {
        double e = cand_n[q][0] * dir[0] + cand_n[q][1] * dir[1] + cand_n[q][2] * dir[2];
        if (e < least) {
            least = e;
            entered = q;
        }
    }
    for (int q = 0; q < cands; ++q) {
        const double *a = cand_n[q], *b = cand_n[entered];
        if (!(a[0] * b[0] + a[1] * b[1] + a[2] * b[2] >= PICK_SAME_SURFACE)) {
            continue; // another surface of the edge
        }
        bool better = cand_cos[q] > best_cos;
        if (cand_facing[q] != best_facing && fabs(cand_cos[q] - best_cos) <= PICK_TIE_COSINE) {
            better = cand_facing[q];
        }
        if (better) {
            best = cand[q];
            best_cos = cand_cos[q];
            best_facing = cand_facing[q];
        }
    }
    // Where every camera that agrees holds only a fill (a solid's edge on the
    // silhouettes of all of them), the first of them: the hit faces its camera.
    return best >= 0 ? best : closest >= 0 ? closest : filled;
}

// True when camera `cam` sees p inside its frame and in front of its surface (or
// over no surface): then p does not collide, whatever the other cameras say.
static bool camera_sees_in_front(const wx_collider *collider, const wx_collider_camera *cam,
                                 const float p[3])
{
    double X = p[0] * cam->mx[0] + p[1] * cam->mx[1] + p[2] * cam->mx[2] + cam->mx[3];
    double Y = p[0] * cam->my[0] + p[1] * cam->my[1] + p[2] * cam->my[2] + cam->my[3];
    double D = p[0] * cam->md[0] + p[1] * cam->md[1] + p[2] * cam->md[2] + cam->md[3];
    if (!(X >= 0.0 && X < cam->width && Y >= 0.0 && Y < cam->height)) {
        return false;
    }
    int c = (int)(cam - collider->cameras);
    return !wx_collider_camera_may_collide(collider, c, X, Y, D);
}

// Where the particle goes back after a hit at s, validated by the point rule:
//  - when the hit is on the camera's surface (d - depth within half a texel),
//    onto that surface along the camera's axis, slightly in front of it (a
//    hundredth of a texel, at least a hair more than float rounding of d);
//  - when the segment entered through a silhouette or a frame edge (d - depth
//    larger: the surface that camera records is elsewhere), a little back along
//    the segment, where it came from;
//  - else the start of the segment (outside, since particles always are).
// With layers the surface is the hit face and "in front" its free side: `side`
// is +1 to go towards the camera (an entering face, as with one layer), -1 to go
// away from it (a leaving face, a sheet's back), and f the depth behind the face.
static void put_back(const wx_collider *collider, const wx_collider_camera *cam,
                     const double a[3], const double d[3], double s, double f, double side,
                     double D, float out[3])
{
    double eps = dmax(0.01 * cam->texel_ws, 2e-6 * (1.0 + fabs(D)));
    double lift = side * (dmax(f, 0.0) + eps);
    float on_surface[3];
    for (int k = 0; k < 3; ++k) {
        on_surface[k] = (float)(a[k] + s * d[k] + lift * cam->back[k]);
    }
    bool surface_first = f <= 0.5 * cam->texel_ws;
    if (surface_first && camera_sees_in_front(collider, cam, on_surface)) {
        memcpy(out, on_surface, sizeof on_surface);
        return;
    }
    double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    static const double back_off[3] = { 0.01, 0.1, 0.5 }; // texels
    for (int t = 0; t < 3 && len > 0.0; ++t) {
        double sb = dmax(0.0, s - back_off[t] * cam->texel_ws / len);
        float q[3];
        for (int k = 0; k < 3; ++k) {
            q[k] = (float)(a[k] + sb * d[k]);
        }
        if (!wx_collider_point_collides(collider, q)) {
            memcpy(out, q, sizeof q);
            return;
        }
    }
    float start[3] = { (float)a[0], (float)a[1], (float)a[2] };
    if (!surface_first && !wx_collider_point_collides(collider, on_surface)) {
        memcpy(out, on_surface, sizeof on_surface);
    } else if (s > 0.0 && !wx_collider_point_collides(collider, start)) {
        memcpy(out, start, sizeof start);
    } else {
        memcpy(out, on_surface, sizeof on_surface); // inside whatever we try: the surface
    }
}

bool wx_collider_sweep(const wx_collider *collider, const float p0[3], const float p1[3],
                       wx_hit *hit)
{
    int K = collider->camera_count;
    march m[WX_MAX_INPUT_CAMERAS];
    double a[3] = { p0[0], p0[1], p0[2] };
    double d[3] = { (double)p1[0] - p0[0], (double)p1[1] - p0[1], (double)p1[2] - p0[2] };
    for (int c = 0; c < K; ++c) {
        march_init(&m[c], &collider->cameras[c], a, d);
        m[c].collider = collider;
    }
    // Leapfrog: raise s until every camera agrees that P(s) may collide and at
    // least one camera sees it (docs/design.md section 4, thesis 4.8.4.1).
    double s = 0.0;
    bool agreed = false;
    for (int round = 0; round < 1 << 20 && !agreed; ++round) {
        double s_frame = INFINITY;
        for (int c = 0; c < K; ++c) {
            if (march_inside(&m[c], s)) {
                s_frame = s;
                break;
            }
            if (m[c].s_in > s && m[c].s_in < s_frame) {
                s_frame = m[c].s_in;
            }
        }
        if (!(s_frame <= 1.0)) {
            return false;
        }
        s = s_frame;
        agreed = true;
        for (int c = 0; c < K; ++c) {
            double e = march_entry(collider, &m[c], s);
            if (!(e <= 1.0)) {
                return false;
            }
            if (e > s) {
                s = e;
                agreed = false;
            }
        }
    }
    if (!agreed) {
        return false;
    }
    int best = pick_camera(collider, m, s, d);
    double best_f = best >= 0 ? m[best].A + s * (m[best].B + s * m[best].C) : 0.0;
    if (best < 0) {
        return false; // only when rounding puts s on a frame edge: no surface there
    }
    const wx_collider_camera *cam = &collider->cameras[best];
    int tx = m[best].hx >> 1, ty = m[best].hy >> 1;
    size_t texel = (size_t)ty * (size_t)cam->width + (size_t)tx;
    // The layer whose planes give the hit: 0 with one layer, else the hit face's.
    layer_face face = { 0, best_f, 1.0, 0.0 };
    if (cam->layers > 1) {
        face = hit_face(&m[best], s);
    }
    size_t at = maps_index(cam, face.layer, texel);
    hit->s = (float)s;
    hit->camera = best;
    hit->layer = (int)(at / ((size_t)cam->width * (size_t)cam->height));
    hit->texel = (uint32_t)texel;
    double point[3];
    for (int k = 0; k < 3; ++k) {
        point[k] = a[k] + s * d[k];
        hit->point[k] = (float)point[k];
    }
    put_back(collider, cam, a, d, s, face.dist, face.side, m[best].D0 + s * m[best].dD,
             hit->front);
    const float *n = cam->normal + 3 * at;
    float len = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (len > 1e-6f && isfinite(len)) {
        for (int k = 0; k < 3; ++k) {
            hit->normal[k] = n[k] / len;
        }
    } else {
        // No usable normal: face the camera (the free side, with layers).
        float bl = sqrtf(cam->back[0] * cam->back[0] + cam->back[1] * cam->back[1] +
                         cam->back[2] * cam->back[2]);
        for (int k = 0; k < 3; ++k) {
            hit->normal[k] = (float)face.side * cam->back[k] / bl;
        }
    }
    if (cam->layers > 1 &&
        hit->normal[0] * d[0] + hit->normal[1] * d[1] + hit->normal[2] * d[2] > 0.0) {
        // Pointing along the segment: a sheet hit from behind. The bounce
        // reflects off the side the particle is on.
        for (int k = 0; k < 3; ++k) {
            hit->normal[k] = -hit->normal[k];
        }
    }
    hit->absorption = cam->impact[2 * at];
    hit->bounce = cam->impact[2 * at + 1];
    return true;
}

void wx_collider_bump_lift(const wx_collider_camera *cam, const float n[3], float climb,
                           float out[3])
{
    // Along the camera's axis (until 7 December 2026) the lift also slid the
    // particle along the surface towards the camera: uphill where the top
    // camera recorded a slope, downhill where a side camera did, so the camera
    // grid a slope's slides fell in set how they went.
    float facing = n[0] * cam->back[0] + n[1] * cam->back[1] + n[2] * cam->back[2];
    float lift = (facing >= 0.0f ? climb : -climb) * cam->texel_ws;
    for (int k = 0; k < 3; ++k) {
        out[k] = lift * n[k];
    }
}
