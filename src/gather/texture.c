// texture.c: the UV raster of a mesh and the sampling of its texture (texture.h).
#include "gather/texture.h"

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

// Texel coordinates of a UV: centres at integers, row 0 at v = 1.
static point2 texel_of(const float *uv, int width, int height)
{
    point2 p = { (double)uv[0] * width - 0.5, (1.0 - (double)uv[1]) * height - 0.5 };
    return p;
}

static bool in_tile(const float *uv)
{
    return uv[0] >= 0.0f && uv[0] <= 1.0f && uv[1] >= 0.0f && uv[1] <= 1.0f;
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

static bool far_uv(const float *uv)
{
    return !(fabsf(uv[0]) <= WX_UV_FAR && fabsf(uv[1]) <= WX_UV_FAR);
}

// The columns of row y where the centre may be inside edge a -> b of a
// positively oriented triangle, widened by what rounding can move: [*lo, *hi]
// narrowed to them. The exact test (edge, inside) decides within.
static void edge_span(point2 a, point2 b, double y, double *lo, double *hi)
{
    double dy = b.y - a.y, dx = b.x - a.x;
    if (dy == 0.0) {
        if (dx * (y - a.y) < 0.0) {
            *hi = -1.0; // the whole row is outside this edge
        }
        return;
    }
    double x = a.x + dx * (y - a.y) / dy; // where the edge crosses the row
    double slack = 2.0 + 1e-12 * (fabs(x) + fabs(a.x) + fabs(b.x) +
                                  fabs(dx) * (fabs(y) + fabs(a.y) + fabs(b.y)) / fabs(dy));
    if (dy > 0.0) {
        *hi = fmin(*hi, x + slack); // inside: left of the crossing
    } else {
        *lo = fmax(*lo, x - slack);
    }
}

static void raster_triangle(const wx_mesh_data *mesh, const float *uvs, int32_t tri,
                            wx_uv_raster *r, unsigned char *count)
{
    const uint32_t *idx = &mesh->indices[3 * (size_t)tri];
    point2 p[3];
    bool outside = false, far = false, finite = true;
    for (int k = 0; k < 3; ++k) {
        const float *uv = &uvs[2 * (size_t)idx[k]];
        p[k] = texel_of(uv, r->width, r->height);
        outside = outside || !in_tile(uv);
        finite = finite && isfinite(uv[0]) && isfinite(uv[1]);
        far = far || far_uv(uv);
    }
    if (!finite) {
        r->triangles_unusable++;
        return;
    }
    r->triangles_outside += outside;
    if (far) {
        return; // no texel position survives in float that far out (texture.h)
    }
    double area = edge(p[0], p[1], p[2]);
    if (!(area != 0.0) || !isfinite(area)) {
        r->triangles_degenerate++;
        // A triangle with a surface but no extent in UV can hold no texel.
        r->triangles_unusable += mesh->positions != NULL && has_area(mesh, idx);
        return;
    }
    if (area < 0.0) {
        point2 t = p[1];
        p[1] = p[2];
        p[2] = t;
    }
    // The texel centres of the bounding box within the tile, clamped in double
    // before any cast.
    double x0 = fmin(p[0].x, fmin(p[1].x, p[2].x)), x1 = fmax(p[0].x, fmax(p[1].x, p[2].x));
    double y0 = fmin(p[0].y, fmin(p[1].y, p[2].y)), y1 = fmax(p[0].y, fmax(p[1].y, p[2].y));
    x0 = fmax(0.0, ceil(x0));
    x1 = fmin(r->width - 1.0, floor(x1));
    y0 = fmax(0.0, ceil(y0));
    y1 = fmin(r->height - 1.0, floor(y1));
    if (!(x0 <= x1 && y0 <= y1)) {
        return;
    }
    const int j0 = (int)y0, j1 = (int)y1;
    for (int j = j0; j <= j1; ++j) {
        // Only the columns near the triangle's span of this row are tested, so
        // a long thin triangle costs its rows, not its bounding box.
        double lo = x0, hi = x1;
        edge_span(p[1], p[2], j, &lo, &hi);
        edge_span(p[2], p[0], j, &lo, &hi);
        edge_span(p[0], p[1], j, &lo, &hi);
        lo = fmax(x0, ceil(lo));
        hi = fmin(x1, floor(hi));
        if (!(lo <= hi)) {
            continue;
        }
        for (int i = (int)lo; i <= (int)hi; ++i) {
            point2 c = { i, j };
            if (!inside(edge(p[1], p[2], c), p[1], p[2]) ||
                !inside(edge(p[2], p[0], c), p[2], p[0]) ||
                !inside(edge(p[0], p[1], c), p[0], p[1])) {
                continue;
            }
            size_t t = (size_t)j * (size_t)r->width + (size_t)i;
            if (count[t] == 0) {
                r->triangle[t] = tri; // the lowest index wins an overlap
                r->covered++;
            } else if (count[t] == 1) {
                r->overlapping++;
            }
            count[t] = count[t] < 2 ? count[t] + 1 : 2;
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
    int32_t *row_of = malloc(texels * sizeof *row_of); // nearest covered row in the column
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

wx_result wx_uv_raster_build(const wx_mesh_data *mesh, int uv, int width, int height,
                             int padding, wx_uv_raster *out, wx_error *err)
{
    memset(out, 0, sizeof *out);
    if (uv < 0 || uv >= WX_MESH_MAX_UV_CHANNELS || mesh->uvs[uv] == NULL || width <= 0 ||
        height <= 0 || (int64_t)width * height > INT32_MAX) {
        return wx_fail(err, WX_CAUSE_BAD_ARGUMENT, "texture: no UV channel %d or a bad size", uv);
    }
    const size_t texels = (size_t)width * (size_t)height;
    out->width = width;
    out->height = height;
    out->triangle = malloc(texels * sizeof *out->triangle);
    out->source = malloc(texels * sizeof *out->source);
    unsigned char *count = calloc(texels, 1);
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
    if (padding > 0 && out->covered > 0) {
        r = pad(out, padding, err);
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
    point2 p[3];
    for (int k = 0; k < 3; ++k) {
        p[k] = texel_of(&mesh->uvs[uv][2 * (size_t)idx[k]], raster->width, raster->height);
    }
    point2 c = { (double)(t % (size_t)raster->width), (double)(t / (size_t)raster->width) };
    double b[3] = { edge(p[1], p[2], c), edge(p[2], p[0], c), edge(p[0], p[1], c) };
    double sum = b[0] + b[1] + b[2];
    double n[3] = { 0.0, 0.0, 0.0 };
    for (int a = 0; a < 3; ++a) {
        position[a] = mesh->origin[a];
    }
    for (int k = 0; k < 3; ++k) {
        double w = b[k] / sum;
        const float *pk = &mesh->positions[3 * (size_t)idx[k]];
        const float *nk = &mesh->normals[3 * (size_t)idx[k]];
        for (int a = 0; a < 3; ++a) {
            position[a] += w * pk[a];
            n[a] += w * nk[a];
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

// ---------------------------------------------------------------------------
// The sampling.

// An input camera prepared for world points.
typedef struct view_sampler {
    double cx[4], cy[4], cd[4]; // [x y z 1] -> continuous texel x, y and depth
    int width, height;
    const float *depth, *normal;
    float ray[3];
    float tol_world;
} view_sampler;

typedef struct sample_job {
    const wx_texture_def *def;
    const view_sampler *views;
    float *const *out;
    float *seen;
    int64_t *seen_rows; // per row: covered texels seen
} sample_job;

// The values camera v holds at the point (world p, depth dp there, normal n),
// into values[c]; false when it does not see the point.
static bool sample_view(const sample_job *job, int v, const double p[3], const float n[3],
                        float *values)
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
        if (!(w > 0.0f)) {
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
                if (!sample_view(job, v, p, n, values)) {
                    continue;
                }
                // A camera that sees the surface head-on resolves it best.
                const float *ray = job->views[v].ray;
                float w = fabsf(n[0] * ray[0] + n[1] * ray[1] + n[2] * ray[2]);
                w = w > WX_GATHER_AREA_MIN_COS ? w : WX_GATHER_AREA_MIN_COS;
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
