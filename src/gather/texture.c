// texture.c: the UV raster of a mesh and the sampling of its texture (texture.h).
#include "gather/texture.h"
#include "core/big_alloc.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/matrix.h"
#include "core/parallel.h"
#include "gather/visibility.h"

// ---------------------------------------------------------------------------
// The raster.

typedef struct point2 {
    double x, y;
} point2;

// Twice the signed area of (a, b, p), computed from the lexicographically
// smaller end of the edge so that edge(a, b, p) == -edge(b, a, p) exactly: a
// texel centre on an edge two triangles share is inside exactly one of them.
static double edge(point2 a, point2 b, point2 p)
{
    bool swap = b.x < a.x || (b.x == a.x && b.y < a.y);
    if (swap) {
        point2 t = a;
        a = b;
        b = t;
    }
    double e = (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
    return swap ? -e : e;
}

// The tie rule for a centre exactly on edge a -> b of a positively oriented
// triangle: of the two directions of an edge, exactly one owns it.
static bool owns_edge(point2 a, point2 b)
{
    double dx = b.x - a.x, dy = b.y - a.y;
    return dy > 0.0 || (dy == 0.0 && dx < 0.0);
}

static bool inside(double e, point2 a, point2 b)
{
    return e > 0.0 || (e == 0.0 && owns_edge(a, b));
}

// A triangle's UVs and the box of whole UV tiles they span (tile (a, b)
// holds [a, a + 1] x [b, b + 1]; a triangle touching a tile's border from
// outside does not span it). In double, and finite whatever the floats: a
// box of 1e30 tiles is counted, never walked.
typedef struct tri_uv {
    const float *uv[3];
    double tu0, tu1, tv0, tv1; // first and last tile along u and v
    double tiles;              // (tu1 - tu0 + 1) * (tv1 - tv0 + 1)
} tri_uv;

// Reads triangle tri's UVs; false when one of them is not finite.
static bool triangle_uvs(const wx_mesh_data *mesh, const float *uvs, int64_t tri, tri_uv *t)
{
    const uint32_t *idx = &mesh->indices[3 * (size_t)tri];
    double lo[2] = { INFINITY, INFINITY }, hi[2] = { -INFINITY, -INFINITY };
    for (int k = 0; k < 3; ++k) {
        const float *uv = &uvs[2 * (size_t)idx[k]];
        t->uv[k] = uv;
        if (!isfinite(uv[0]) || !isfinite(uv[1])) {
            return false;
        }
        for (int a = 0; a < 2; ++a) {
            lo[a] = fmin(lo[a], (double)uv[a]);
            hi[a] = fmax(hi[a], (double)uv[a]);
        }
    }
    t->tu0 = floor(lo[0]);
    t->tu1 = fmax(t->tu0, ceil(hi[0]) - 1.0);
    t->tv0 = floor(lo[1]);
    t->tv1 = fmax(t->tv0, ceil(hi[1]) - 1.0);
    t->tiles = (t->tu1 - t->tu0 + 1.0) * (t->tv1 - t->tv0 + 1.0);
    return true;
}

// Whether the triangle's UVs lie within WX_UV_FAR of 0 (tiles tu0..tu1, tv0..tv1).
static bool near_enough(const tri_uv *t)
{
    return fmax(fabs(t->tu0), fabs(t->tu1 + 1.0)) <= WX_UV_FAR &&
           fmax(fabs(t->tv0), fabs(t->tv1 + 1.0)) <= WX_UV_FAR;
}

static bool spans_tile(const tri_uv *t, double tu, double tv)
{
    return tu >= t->tu0 && tu <= t->tu1 && tv >= t->tv0 && tv <= t->tv1;
}

// Texel coordinates of a UV read in tile (tu, tv): centres at integers, row 0
// at v = tv + 1. The offset is taken off exactly (both are whole or the float
// is), so a triangle in tile (2, 0) lands on the texels of its copy in (0, 0).
static point2 texel_in_tile(const float *uv, double tu, double tv, int width, int height)
{
    point2 p = { ((double)uv[0] - tu) * width - 0.5,
                 (1.0 - ((double)uv[1] - tv)) * height - 0.5 };
    return p;
}

// The copy of a triangle in tile (tu, tv), positively oriented in q; false
// when it has no area (or the numbers overflow).
static bool oriented_copy(const tri_uv *t, double tu, double tv, int width, int height,
                          point2 q[3])
{
    for (int k = 0; k < 3; ++k) {
        q[k] = texel_in_tile(t->uv[k], tu, tv, width, height);
    }
    double area = edge(q[0], q[1], q[2]);
    if (!(area != 0.0) || !isfinite(area)) {
        return false;
    }
    if (area < 0.0) {
        point2 s = q[1];
        q[1] = q[2];
        q[2] = s;
    }
    return true;
}

// Whether texel centre c lies inside the positively oriented triangle q (edges
// shared by two triangles going to exactly one of them). Not inlined: the
// raster and wx_uv_raster_point must decide every centre alike.
static __attribute__((noinline)) bool covers_centre(const point2 q[3], point2 c)
{
    return inside(edge(q[1], q[2], c), q[1], q[2]) && inside(edge(q[2], q[0], c), q[2], q[0]) &&
           inside(edge(q[0], q[1], c), q[0], q[1]);
}

// The texels a copy's bounding box reaches, clamped to the raster before any
// conversion to int (an empty range when it lies off the raster).
static void copy_box(const point2 q[3], int width, int height, int *i0, int *i1, int *j0, int *j1)
{
    double x0 = fmin(q[0].x, fmin(q[1].x, q[2].x)), x1 = fmax(q[0].x, fmax(q[1].x, q[2].x));
    double y0 = fmin(q[0].y, fmin(q[1].y, q[2].y)), y1 = fmax(q[0].y, fmax(q[1].y, q[2].y));
    *i0 = (int)fmin((double)width, fmax(0.0, ceil(x0)));
    *i1 = (int)fmax(-1.0, fmin(width - 1.0, floor(x1)));
    *j0 = (int)fmin((double)height, fmax(0.0, ceil(y0)));
    *j1 = (int)fmax(-1.0, fmin(height - 1.0, floor(y1)));
}

// Whether the copy q covers any texel centre of a width x height tile.
static bool copy_covers_any(const point2 q[3], int width, int height)
{
    int i0, i1, j0, j1;
    copy_box(q, width, height, &i0, &i1, &j0, &j1);
    for (int j = j0; j <= j1; ++j) {
        for (int i = i0; i <= i1; ++i) {
            if (covers_centre(q, (point2){ i, j })) {
                return true;
            }
        }
    }
    return false;
}

static void draw_copy(const point2 q[3], int32_t tri, wx_uv_raster *r, unsigned char *count)
{
    int i0, i1, j0, j1;
    copy_box(q, r->width, r->height, &i0, &i1, &j0, &j1);
    for (int j = j0; j <= j1; ++j) {
        for (int i = i0; i <= i1; ++i) {
            if (!covers_centre(q, (point2){ i, j })) {
                continue;
            }
            size_t t = (size_t)j * (size_t)r->width + (size_t)i;
            if (count[t] == 0) {
                r->triangle[t] = tri; // the lowest index (its first copy) wins an overlap
                r->covered++;
            } else if (count[t] == 1) {
                r->overlapping++;
            }
            count[t] = count[t] < 2 ? count[t] + 1 : 2;
        }
    }
}

static bool outside_box(const tri_uv *t, double u_max, double v_max)
{
    bool out = false;
    for (int k = 0; k < 3; ++k) {
        out = out || t->uv[k][0] < 0.0f || t->uv[k][0] > u_max || t->uv[k][1] < 0.0f ||
              t->uv[k][1] > v_max;
    }
    return out;
}

// The tile of a raster's copies when it has one: CLIP (0, 0), UDIM its tile.
static bool fixed_tile(const wx_uv_raster *r, double *tu, double *tv)
{
    if (r->tiles == WX_TILES_REPEAT) {
        return false;
    }
    *tu = r->tiles == WX_TILES_UDIM ? (double)(r->udim % WX_UDIM_COLUMNS) : 0.0;
    *tv = r->tiles == WX_TILES_UDIM ? (double)(r->udim / WX_UDIM_COLUMNS) : 0.0;
    return true;
}

// Whether the triangle's corners span an area in 3D.
static bool has_area(const wx_mesh_data *mesh, const uint32_t *idx)
{
    const float *a = &mesh->positions[3 * (size_t)idx[0]];
    const float *b = &mesh->positions[3 * (size_t)idx[1]];
    const float *c = &mesh->positions[3 * (size_t)idx[2]];
    double e1[3], e2[3];
    for (int k = 0; k < 3; ++k) {
        e1[k] = (double)b[k] - a[k];
        e2[k] = (double)c[k] - a[k];
    }
    double n[3] = { e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                    e1[0] * e2[1] - e1[1] * e2[0] };
    return n[0] != 0.0 || n[1] != 0.0 || n[2] != 0.0;
}

static void raster_triangle(const wx_mesh_data *mesh, const float *uvs, int32_t tri,
                            wx_uv_raster *r, unsigned char *count)
{
    tri_uv t;
    if (!triangle_uvs(mesh, uvs, tri, &t) ||
        (r->tiles != WX_TILES_CLIP && t.tiles > WX_UV_MAX_TILES_PER_TRIANGLE) ||
        !near_enough(&t)) {
        r->triangles_unusable++;
        return;
    }
    r->triangles_outside += r->tiles == WX_TILES_UDIM
                                ? outside_box(&t, WX_UDIM_COLUMNS, WX_UDIM_ROWS)
                                : outside_box(&t, 1.0, 1.0);
    point2 q[3];
    if (!oriented_copy(&t, t.tu0, t.tv0, r->width, r->height, q)) {
        r->triangles_degenerate++;
        // A triangle with a surface but no extent in UV can hold no texel:
        // an OBJ face without `vt` (Assimp gives it (0, 0) at every corner).
        r->triangles_unusable += mesh->positions != NULL &&
                                 has_area(mesh, &mesh->indices[3 * (size_t)tri]);
        return;
    }
    double tu, tv;
    if (fixed_tile(r, &tu, &tv)) {
        if (spans_tile(&t, tu, tv) && oriented_copy(&t, tu, tv, r->width, r->height, q)) {
            draw_copy(q, tri, r, count);
        }
        return;
    }
    // REPEAT: the copy at every tile the triangle spans, v then u (integer
    // counters: at 1e20 adding 1 to a double changes nothing).
    const int nu = (int)(t.tu1 - t.tu0) + 1, nv = (int)(t.tv1 - t.tv0) + 1;
    for (int b = 0; b < nv; ++b) {
        for (int a = 0; a < nu; ++a) {
            if (oriented_copy(&t, t.tu0 + a, t.tv0 + b, r->width, r->height, q)) {
                draw_copy(q, tri, r, count);
            }
        }
    }
}

// Padding: the nearest covered texel (Euclidean, between centres) of every
// texel, by the separable exact distance transform of Felzenszwalb and
// Huttenlocher (2012) carrying the nearest texel's index.
static wx_result pad(wx_uv_raster *r, int padding, wx_error *err)
{
    const int W = r->width, H = r->height;
    const size_t texels = (size_t)W * (size_t)H;
    int32_t *row_of = wx_big_malloc(texels * sizeof *row_of); // nearest covered row in the column
    int *v = malloc((size_t)W * sizeof *v);
    double *z = malloc(((size_t)W + 1) * sizeof *z);
    if (row_of == NULL || v == NULL || z == NULL) {
        free(row_of);
        free(v);
        free(z);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "texture: out of memory (padding)");
    }
    for (int i = 0; i < W; ++i) {
        int last = -1;
        for (int j = 0; j < H; ++j) {
            size_t t = (size_t)j * (size_t)W + (size_t)i;
            last = r->triangle[t] >= 0 ? j : last;
            row_of[t] = last;
        }
        last = -1;
        for (int j = H - 1; j >= 0; --j) {
            size_t t = (size_t)j * (size_t)W + (size_t)i;
            last = r->triangle[t] >= 0 ? j : last;
            if (last >= 0 && (row_of[t] < 0 || last - j < j - row_of[t])) {
                row_of[t] = last;
            }
        }
    }
    const double reach2 = (double)padding * (double)padding;
    for (int j = 0; j < H; ++j) {
        const int32_t *rows = &row_of[(size_t)j * (size_t)W];
        // f(i) = (j - row)^2 for the columns with a covered texel.
        int k = -1;
        for (int q = 0; q < W; ++q) {
            if (rows[q] < 0) {
                continue;
            }
            double fq = (double)(j - rows[q]) * (double)(j - rows[q]) + (double)q * q;
            double s = -INFINITY;
            while (k >= 0) {
                int p = v[k];
                double fp = (double)(j - rows[p]) * (double)(j - rows[p]) + (double)p * p;
                s = (fq - fp) / (2.0 * (q - p));
                if (s > z[k]) {
                    break;
                }
                --k;
            }
            ++k;
            v[k] = q;
            z[k] = k == 0 ? -INFINITY : s;
            z[k + 1] = INFINITY;
        }
        for (int i = 0, m = 0; i < W && k >= 0; ++i) {
            while (z[m + 1] < i) {
                ++m;
            }
            size_t t = (size_t)j * (size_t)W + (size_t)i;
            if (r->triangle[t] >= 0) {
                r->source[t] = (int32_t)t;
                continue;
            }
            int q = v[m];
            double dy = (double)(j - rows[q]), dx = (double)(i - q);
            if (dx * dx + dy * dy <= reach2) {
                r->source[t] = (int32_t)((size_t)rows[q] * (size_t)W + (size_t)q);
                r->padded++;
            }
        }
    }
    free(row_of);
    free(v);
    free(z);
    return WX_OK;
}

wx_uv_raster_def wx_default_uv_raster_def(void)
{
    return (wx_uv_raster_def){ .tiles = WX_TILES_REPEAT };
}

wx_result wx_uv_raster_build(const wx_uv_raster_def *def, wx_uv_raster *out, wx_error *err)
{
    memset(out, 0, sizeof *out);
    const wx_mesh_data *mesh = def->mesh;
    const int uv = def->uv, width = def->width, height = def->height;
    if (uv < 0 || uv >= WX_MESH_MAX_UV_CHANNELS || mesh->uvs[uv] == NULL || width <= 0 ||
        height <= 0 || (int64_t)width * height > INT32_MAX ||
        (def->tiles == WX_TILES_UDIM && (def->udim < 0 || def->udim >= WX_UDIM_TILES))) {
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "texture: no UV channel %d or a bad size", uv);
    }
    const size_t texels = (size_t)width * (size_t)height;
    out->width = width;
    out->height = height;
    out->tiles = def->tiles;
    out->udim = def->tiles == WX_TILES_UDIM ? def->udim : 0;
    out->triangle = wx_big_malloc(texels * sizeof *out->triangle);
    out->source = wx_big_malloc(texels * sizeof *out->source);
    unsigned char *count = wx_big_calloc(texels, 1);
    if (out->triangle == NULL || out->source == NULL || count == NULL) {
        free(count);
        wx_uv_raster_free(out);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY,
                       "texture: out of memory for a %d x %d UV raster", width, height);
    }
    for (size_t t = 0; t < texels; ++t) {
        out->triangle[t] = -1;
        out->source[t] = -1;
    }
    for (int64_t tri = 0; tri < mesh->triangle_count; ++tri) {
        raster_triangle(mesh, mesh->uvs[uv], (int32_t)tri, out, count);
    }
    free(count);
    wx_result r = WX_OK;
    if (def->padding > 0 && out->covered > 0) {
        r = pad(out, def->padding, err);
    } else {
        for (size_t t = 0; t < texels; ++t) {
            out->source[t] = out->triangle[t] >= 0 ? (int32_t)t : -1;
        }
    }
    if (r != WX_OK) {
        wx_uv_raster_free(out);
    }
    return r;
}

void wx_uv_raster_free(wx_uv_raster *raster)
{
    free(raster->triangle);
    free(raster->source);
    memset(raster, 0, sizeof *raster);
}

bool wx_uv_raster_point(const wx_mesh_data *mesh, int uv, const wx_uv_raster *raster,
                        size_t t, double position[3], float normal[3])
{
    int32_t tri = raster->triangle[t];
    if (tri < 0) {
        return false;
    }
    const uint32_t *idx = &mesh->indices[3 * (size_t)tri];
    point2 c = { (double)(t % (size_t)raster->width), (double)(t / (size_t)raster->width) };
    // The copy the raster drew here: its only one, else (REPEAT) the first in
    // the raster's order whose copy holds the centre.
    tri_uv tu;
    double ctu = 0.0, ctv = 0.0;
    if (!triangle_uvs(mesh, mesh->uvs[uv], tri, &tu)) {
        return false;
    }
    if (!fixed_tile(raster, &ctu, &ctv)) {
        ctu = tu.tu0;
        ctv = tu.tv0;
        bool found = tu.tiles == 1.0;
        const int nu = (int)(tu.tu1 - tu.tu0) + 1, nv = (int)(tu.tv1 - tu.tv0) + 1;
        point2 q[3];
        for (int b = 0; !found && b < nv; ++b) {
            for (int a = 0; !found && a < nu; ++a) {
                found = oriented_copy(&tu, tu.tu0 + a, tu.tv0 + b, raster->width,
                                      raster->height, q) &&
                        covers_centre(q, c);
                ctu = found ? tu.tu0 + a : ctu;
                ctv = found ? tu.tv0 + b : ctv;
            }
        }
    }
    point2 p[3];
    for (int k = 0; k < 3; ++k) {
        p[k] = texel_in_tile(tu.uv[k], ctu, ctv, raster->width, raster->height);
    }
    double b[3] = { edge(p[1], p[2], c), edge(p[2], p[0], c), edge(p[0], p[1], c) };
    double sum = b[0] + b[1] + b[2];
    double n[3] = { 0.0, 0.0, 0.0 }, w[3], local[3];
    for (int k = 0; k < 3; ++k) {
        w[k] = b[k] / sum;
        const float *nk = &mesh->normals[3 * (size_t)idx[k]];
        for (int a = 0; a < 3; ++a) {
            n[a] += w[k] * nk[a];
        }
    }
    // On the smooth surface the bake draws (its depth maps hold this point),
    // with the normal its normal maps hold there.
    wx_mesh_phong_point(mesh, tri, w, local);
    for (int a = 0; a < 3; ++a) {
        position[a] = mesh->origin[a] + local[a];
    }
    if (wx_mesh_triangle_curves(mesh, tri)) {
        float smooth[3];
        wx_mesh_phong_normal(mesh, tri, w, smooth);
        for (int a = 0; a < 3; ++a) {
            n[a] = smooth[a];
        }
    }
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 1e-6)) {
        // No usable vertex normals: the triangle's own, from its winding.
        const float *a = &mesh->positions[3 * (size_t)idx[0]];
        const float *bb = &mesh->positions[3 * (size_t)idx[1]];
        const float *cc = &mesh->positions[3 * (size_t)idx[2]];
        double e1[3], e2[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = (double)bb[k] - a[k];
            e2[k] = (double)cc[k] - a[k];
        }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
    for (int a = 0; a < 3; ++a) {
        normal[a] = len > 0.0 ? (float)(n[a] / len) : 0.0f;
    }
    return len > 0.0;
}

wx_result wx_uv_survey_build(const wx_mesh_data *mesh, int uv, int width, int height,
                             wx_uv_survey *out, wx_error *err)
{
    memset(out, 0, sizeof *out);
    if (uv < 0 || uv >= WX_MESH_MAX_UV_CHANNELS || mesh->uvs[uv] == NULL || width <= 0 ||
        height <= 0) {
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "texture: no UV channel %d or a bad size", uv);
    }
    double lo[2] = { INFINITY, INFINITY }, hi[2] = { -INFINITY, -INFINITY };
    out->triangles = mesh->triangle_count;
    for (int64_t tri = 0; tri < mesh->triangle_count; ++tri) {
        tri_uv t;
        if (!triangle_uvs(mesh, mesh->uvs[uv], tri, &t) ||
            t.tiles > WX_UV_MAX_TILES_PER_TRIANGLE || !near_enough(&t)) {
            out->triangles_unusable++;
            continue;
        }
        for (int k = 0; k < 3; ++k) {
            for (int a = 0; a < 2; ++a) {
                lo[a] = fmin(lo[a], (double)t.uv[k][a]);
                hi[a] = fmax(hi[a], (double)t.uv[k][a]);
            }
        }
        out->triangles_outside_unit += outside_box(&t, 1.0, 1.0);
        bool beyond_udim = outside_box(&t, WX_UDIM_COLUMNS, WX_UDIM_ROWS);
        out->triangles_outside_udim += beyond_udim;
        point2 q[3];
        if (!oriented_copy(&t, t.tu0, t.tv0, width, height, q)) {
            out->triangles_degenerate++;
            continue;
        }
        out->triangles_in_other_tiles += t.tiles == 1.0 && !beyond_udim &&
                                         (t.tu0 != 0.0 || t.tv0 != 0.0);
        // Each copy is tested only while it can tell something new: the first
        // covered centre anywhere, a UDIM tile's first.
        const int nu = (int)(t.tu1 - t.tu0) + 1, nv = (int)(t.tv1 - t.tv0) + 1;
        for (int b = 0; b < nv; ++b) {
            for (int a = 0; a < nu; ++a) {
                double tu = t.tu0 + a, tv = t.tv0 + b;
                int k = tu >= 0.0 && tu < WX_UDIM_COLUMNS && tv >= 0.0 && tv < WX_UDIM_ROWS
                            ? (int)tu + WX_UDIM_COLUMNS * (int)tv
                            : -1;
                bool known = k >= 0 ? (out->udim[k / 8] >> (k % 8)) & 1u : out->covers;
                if (known || !oriented_copy(&t, tu, tv, width, height, q) ||
                    !copy_covers_any(q, width, height)) {
                    continue;
                }
                out->covers = true;
                if (k >= 0) {
                    out->udim[k / 8] |= (uint8_t)(1u << (k % 8));
                    out->udim_count++;
                }
            }
        }
    }
    for (int a = 0; a < 2; ++a) {
        out->uv_min[a] = isfinite(lo[a]) ? lo[a] : 0.0;
        out->uv_max[a] = isfinite(hi[a]) ? hi[a] : 0.0;
    }
    return WX_OK;
}

// ---------------------------------------------------------------------------
// The sampling.

// An input camera prepared for world points.
typedef struct view_sampler {
    double cx[4], cy[4], cd[4]; // [x y z 1] -> continuous texel x, y and depth
    int width, height;
    const float *depth, *normal;
    float ray[3];
    float tol_world;
    const float *crossing_depth, *crossing_normal; // a layer view's (gather.h)
    int crossing_layers, crossing_layer;
} view_sampler;

typedef struct sample_job {
    const wx_texture_def *def;
    const view_sampler *views;
    float *const *out;
    float *seen;
    int64_t *seen_rows; // per row: covered texels seen
} sample_job;

// The values camera v holds at the point (world p, depth dp there, normal n),
// into values[c], and in *coverage how much of its four bilinear taps see the
// point (their weights times the normals' agreement, in (0, 1]); false when it
// does not see the point.
static bool sample_view(const sample_job *job, int v, const double p[3], const float n[3],
                        float *values, float *coverage)
{
    const view_sampler *s = &job->views[v];
    double x = s->cx[0] * p[0] + s->cx[1] * p[1] + s->cx[2] * p[2] + s->cx[3];
    double y = s->cy[0] * p[0] + s->cy[1] * p[1] + s->cy[2] * p[2] + s->cy[3];
    if (!(x >= -0.5 && x < (double)s->width - 0.5 && y >= -0.5 && y < (double)s->height - 0.5)) {
        return false;
    }
    float dp = (float)(s->cd[0] * p[0] + s->cd[1] * p[1] + s->cd[2] * p[2] + s->cd[3]);
    const int i0 = (int)(x + 1.0) - 1, j0 = (int)(y + 1.0) - 1; // x + 1 > 0: floor
    const float fx = (float)(x - i0), fy = (float)(y - j0);
    const float weights[4] = { (1.0f - fx) * (1.0f - fy), fx * (1.0f - fy), (1.0f - fx) * fy,
                               fx * fy };
    const int channels = job->def->channels;
    float den = 0.0f;
    for (int c = 0; c < channels; ++c) {
        values[c] = 0.0f;
    }
    for (int k = 0; k < 4; ++k) {
        int ti = i0 + (k & 1), tj = j0 + (k >> 1);
        if (ti < 0 || tj < 0 || ti >= s->width || tj >= s->height || weights[k] <= 0.0f) {
            continue;
        }
        size_t t = (size_t)tj * (size_t)s->width + (size_t)ti;
        float cos_view = 0.0f;
        float agree = wx_visible_agreement(s->depth[t], &s->normal[3 * t], s->ray, s->tol_world,
                                           WX_GATHER_TOL_MIN_COS, dp, n, &cos_view);
        float w = weights[k] * agree;
        if (!(w > 0.0f) ||
            wx_crossing_nearer(s->crossing_depth, s->crossing_normal, s->crossing_layers,
                               s->crossing_layer, (size_t)s->width * (size_t)s->height, t, dp, n)) {
            continue;
        }
        den += w;
        for (int c = 0; c < channels; ++c) {
            values[c] += w * job->def->smoothed[(size_t)v * (size_t)channels + (size_t)c][t];
        }
    }
    if (!(den > 0.0f)) {
        return false;
    }
    for (int c = 0; c < channels; ++c) {
        values[c] /= den;
    }
    *coverage = den;
    return true;
}

static void sample_rows(int64_t begin, int64_t end, int worker, void *context)
{
    (void)worker;
    const sample_job *job = context;
    const wx_texture_def *def = job->def;
    const int W = def->raster->width, channels = def->channels;
    float values[WX_IMAGE_MAX_CHANNELS], sum[WX_IMAGE_MAX_CHANNELS];
    for (int64_t j = begin; j < end; ++j) {
        int64_t seen_here = 0;
        for (int i = 0; i < W; ++i) {
            size_t t = (size_t)j * (size_t)W + (size_t)i;
            double p[3];
            float n[3];
            if (!wx_uv_raster_point(def->mesh, def->uv, def->raster, t, p, n)) {
                continue;
            }
            if (def->position != NULL && def->normal != NULL) {
                memcpy(&def->position[3 * t], p, sizeof p);
                memcpy(&def->normal[3 * t], n, sizeof n);
            }
            float total = 0.0f;
            for (int c = 0; c < channels; ++c) {
                sum[c] = 0.0f;
            }
            for (int v = 0; v < def->input_count; ++v) {
                float coverage = 0.0f;
                if (!sample_view(job, v, p, n, values, &coverage)) {
                    continue;
                }
                // A camera that sees the surface head-on resolves it best:
                // per unit of surface it has |N.view| texels, each of them
                // |N.view| times as precise in depth, so its weight is
                // |N.view|^2 (docs/texture.md: against |N.view| it lowers the
                // noise, the error and what turning the model changes). And
                // it counts as much as its taps around the point see it: near
                // where it stops seeing the surface (its silhouettes, an
                // occluder's edge, the end of what a layer holds) its value
                // rests on the taps on one side, and its weight fades there
                // instead of dropping from whole to nothing between two
                // texels wherever its grid puts that step.
                const float *ray = job->views[v].ray;
                float cv = fabsf(n[0] * ray[0] + n[1] * ray[1] + n[2] * ray[2]);
                cv = cv > WX_GATHER_AREA_MIN_COS ? cv : WX_GATHER_AREA_MIN_COS;
                float w = cv * cv * coverage;
                total += w;
                for (int c = 0; c < channels; ++c) {
                    sum[c] += w * values[c];
                }
            }
            if (total > 0.0f) {
                for (int c = 0; c < channels; ++c) {
                    job->out[c][t] = sum[c] / total;
                }
                job->seen[t] = 1.0f;
                seen_here++;
            }
        }
        job->seen_rows[j] = seen_here;
    }
}

static bool prepare_view(const wx_gather_view *view, view_sampler *s)
{
    double wtc[16], head_area = 0.0;
    if (!wx_matrix_to_affine(view->camera->wtc, wtc) ||
        !wx_gather_view_frame(view, s->ray, &s->tol_world, &head_area)) {
        return false;
    }
    wx_gather_view_rows(view, wtc, NULL, s->cx, s->cy, s->cd);
    s->width = view->width;
    s->height = view->height;
    s->depth = view->depth;
    s->normal = view->normal;
    s->crossing_depth = view->crossing_depth;
    s->crossing_normal = view->crossing_normal;
    s->crossing_layers = view->crossing_layers;
    s->crossing_layer = view->crossing_layer;
    return true;
}

wx_result wx_texture_sample(const wx_texture_def *def, float *const *out, float *seen,
                            int64_t *seen_texels, wx_error *err)
{
    const wx_uv_raster *r = def->raster;
    const int W = r->width, H = r->height;
    const size_t texels = (size_t)W * (size_t)H;
    if (def->channels < 1 || def->channels > WX_IMAGE_MAX_CHANNELS) {
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "texture: %d channels", def->channels);
    }
    view_sampler *views = calloc((size_t)def->input_count + 1, sizeof *views);
    int64_t *seen_rows = calloc((size_t)H, sizeof *seen_rows);
    if (views == NULL || seen_rows == NULL) {
        free(views);
        free(seen_rows);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "texture: out of memory");
    }
    for (int v = 0; v < def->input_count; ++v) {
        if (!prepare_view(&def->inputs[v], &views[v])) {
            free(views);
            free(seen_rows);
            return wx_fail(err, WX_CAUSE_BAD_CAMERA,
                           "texture: input camera %d is not orthographic or its frame is "
                           "degenerate",
                           v);
        }
    }
    for (int c = 0; c < def->channels; ++c) {
        memset(out[c], 0, texels * sizeof *out[c]);
    }
    memset(seen, 0, texels * sizeof *seen);
    sample_job job = { .def = def, .views = views, .out = out, .seen = seen,
                       .seen_rows = seen_rows };
    wx_parallel_for(def->threads, H, 4, sample_rows, &job);
    int64_t seen_count = 0;
    for (int j = 0; j < H; ++j) {
        seen_count += seen_rows[j];
    }
    if (seen_texels != NULL) {
        *seen_texels = seen_count;
    }
    free(views);
    free(seen_rows);
    return WX_OK;
}

void wx_texture_pad(const wx_uv_raster *raster, float *const *planes, int count)
{
    const size_t texels = (size_t)raster->width * (size_t)raster->height;
    for (size_t t = 0; t < texels; ++t) {
        int32_t s = raster->source[t];
        if (s < 0 || (size_t)s == t) {
            continue;
        }
        for (int c = 0; c < count; ++c) {
            planes[c][t] = planes[c][s];
        }
    }
}
