// mesh.c: the memory of a triangle mesh (mesh.h).
#include "model/mesh.h"

#include <math.h>

#include <stdlib.h>
#include <string.h>

#include "core/matrix.h"

void wx_mesh_data_release_arrays(wx_mesh_data *mesh)
{
    free(mesh->positions);
    free(mesh->normals);
    free(mesh->colors);
    free(mesh->indices);
    free(mesh->materials);
    free(mesh->creases);
    mesh->positions = mesh->normals = mesh->colors = NULL;
    mesh->indices = NULL;
    mesh->materials = NULL;
    mesh->creases = NULL;
    for (int c = 0; c < WX_MESH_MAX_UV_CHANNELS; ++c) {
        free(mesh->uvs[c]);
        mesh->uvs[c] = NULL;
    }
}

void wx_mesh_data_free(wx_mesh_data *mesh)
{
    wx_mesh_data_release_arrays(mesh);
    free(mesh->material_names);
    free(mesh->material_colored);
    memset(mesh, 0, sizeof *mesh);
}

// Whether vertex a comes after vertex b: by position, then normal.
static bool corner_after(const wx_mesh_data *mesh, uint32_t a, uint32_t b)
{
    const float *pa = &mesh->positions[3 * (size_t)a], *pb = &mesh->positions[3 * (size_t)b];
    const float *na = &mesh->normals[3 * (size_t)a], *nb = &mesh->normals[3 * (size_t)b];
    const float ka[6] = { pa[0], pa[1], pa[2], na[0], na[1], na[2] };
    const float kb[6] = { pb[0], pb[1], pb[2], nb[0], nb[1], nb[2] };
    for (int k = 0; k < 6; ++k) {
        if (ka[k] != kb[k]) {
            return ka[k] > kb[k];
        }
    }
    return false;
}

// Corner v's position and unit normal (0 when it has none), in double.
static void unit_corner(const wx_mesh_data *mesh, uint32_t v, double p[3], double n[3])
{
    const float *pv = &mesh->positions[3 * (size_t)v];
    const float *nv = &mesh->normals[3 * (size_t)v];
    double len = sqrt((double)nv[0] * nv[0] + (double)nv[1] * nv[1] + (double)nv[2] * nv[2]);
    for (int a = 0; a < 3; ++a) {
        p[a] = pv[a];
        n[a] = len > 1e-6 ? nv[a] / len : 0.0;
    }
}

// The crease bit of the edge between corners j and l of a triangle: bit k
// is the edge from corner k to corner k + 1 (mod 3).
static inline uint8_t edge_bit(int j, int l)
{
    return (uint8_t)(1u << (l == (j + 1) % 3 ? j : l));
}

// The Phong displacement of edge kl: E = (e . n_k) n_k - (e . n_l) n_l with
// e = p_l - p_k, so that the point of weights w moves by -sum w_k w_l E_kl
// (the flat point minus p_k is the sum over l of w_l (p_l - p_k)). 0 when the
// two normals are equal.
static void phong_edge(const double pk[3], const double nk[3], const double pl[3],
                       const double nl[3], double out[3])
{
    double e[3] = { pl[0] - pk[0], pl[1] - pk[1], pl[2] - pk[2] };
    double ek = e[0] * nk[0] + e[1] * nk[1] + e[2] * nk[2];
    double el = e[0] * nl[0] + e[1] * nl[1] + e[2] * nl[2];
    for (int a = 0; a < 3; ++a) {
        out[a] = ek * nk[a] - el * nl[a];
    }
}

void wx_mesh_phong_point(const wx_mesh_data *mesh, int64_t tri, const double w[3],
                         double out[3])
{
    // The corners in a canonical order (by position, then normal), so that a
    // point of an edge comes out bit for bit the same from both triangles that
    // share it, also where they reach it through different vertices of the
    // same position and normal (a UV seam); a weight of 0 adds an exact 0
    // wherever it stands.
    const uint32_t *tri_idx = &mesh->indices[3 * (size_t)tri];
    int order[3] = { 0, 1, 2 };
    for (int a = 1; a < 3; ++a) {
        for (int b = a; b > 0 && corner_after(mesh, tri_idx[order[b - 1]], tri_idx[order[b]]); --b) {
            int swap = order[b];
            order[b] = order[b - 1];
            order[b - 1] = swap;
        }
    }
    double flat[3] = { 0.0, 0.0, 0.0 }, p[3][3], n[3][3];
    for (int j = 0; j < 3; ++j) {
        unit_corner(mesh, tri_idx[order[j]], p[j], n[j]);
        for (int a = 0; a < 3; ++a) {
            flat[a] += w[order[j]] * p[j][a];
        }
    }
    // Projected onto each corner's tangent plane and blended, the flat point
    // moves by -sum over the edges kl of w_k w_l E_kl (phong_edge): on an
    // edge only its own term is left, so its curve depends on the edge alone,
    // and a crease's is left out on both sides.
    uint8_t creases = mesh->creases != NULL ? mesh->creases[tri] : 0;
    double q[3] = { 0.0, 0.0, 0.0 };
    for (int j = 0; j < 2; ++j) {
        for (int l = j + 1; l < 3; ++l) {
            if (creases & edge_bit(order[j], order[l])) {
                continue;
            }
            double e[3];
            phong_edge(p[j], n[j], p[l], n[l], e);
            double wjl = w[order[j]] * w[order[l]];
            for (int a = 0; a < 3; ++a) {
                q[a] -= wjl * e[a];
            }
        }
    }
    for (int a = 0; a < 3; ++a) {
        out[a] = flat[a] + WX_PHONG_SHAPE * q[a];
    }
}

void wx_mesh_phong_normal(const wx_mesh_data *mesh, int64_t tri, const double w[3],
                          float out[3])
{
    // p(w) = flat(w) - s sum over the edges kl (not creases) of w_k w_l E_kl,
    // flat(w) = sum w_k p_k (s = WX_PHONG_SHAPE, wx_mesh_phong_point); its
    // derivatives along w1 - w0 and w2 - w0 span the tangent plane.
    const uint32_t *idx = &mesh->indices[3 * (size_t)tri];
    double p[3][3], n[3][3], interpolated[3] = { 0, 0, 0 };
    for (int k = 0; k < 3; ++k) {
        unit_corner(mesh, idx[k], p[k], n[k]);
        for (int a = 0; a < 3; ++a) {
            interpolated[a] += w[k] * mesh->normals[3 * (size_t)idx[k] + (size_t)a];
        }
    }
    uint8_t creases = mesh->creases != NULL ? mesh->creases[tri] : 0;
    double tangent[2][3];
    for (int d = 0; d < 2; ++d) {
        int to = d + 1; // the derivative along w_to - w0
        double dw[3] = { -1.0, to == 1 ? 1.0 : 0.0, to == 2 ? 1.0 : 0.0 };
        for (int a = 0; a < 3; ++a) {
            tangent[d][a] = p[to][a] - p[0][a];
        }
        for (int k = 0; k < 2; ++k) {
            for (int l = k + 1; l < 3; ++l) {
                if (creases & edge_bit(k, l)) {
                    continue;
                }
                double e[3];
                phong_edge(p[k], n[k], p[l], n[l], e);
                double dkl = dw[k] * w[l] + w[k] * dw[l];
                for (int a = 0; a < 3; ++a) {
                    tangent[d][a] -= WX_PHONG_SHAPE * dkl * e[a];
                }
            }
        }
    }
    double c[3] = { tangent[0][1] * tangent[1][2] - tangent[0][2] * tangent[1][1],
                    tangent[0][2] * tangent[1][0] - tangent[0][0] * tangent[1][2],
                    tangent[0][0] * tangent[1][1] - tangent[0][1] * tangent[1][0] };
    double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    double sign = c[0] * interpolated[0] + c[1] * interpolated[1] + c[2] * interpolated[2] < 0.0
                      ? -1.0
                      : 1.0;
    for (int a = 0; a < 3; ++a) {
        out[a] = len > 0.0 ? (float)(sign * c[a] / len) : (float)interpolated[a];
    }
}

// Whether edge k of triangle t (corner k to corner k + 1) bends the smooth
// surface: its two normals differ and it is not a crease.
static bool edge_curves(const wx_mesh_data *mesh, int64_t t, int k)
{
    if (mesh->creases != NULL && (mesh->creases[t] >> k & 1u)) {
        return false;
    }
    const uint32_t *idx = &mesh->indices[3 * t];
    const float *na = &mesh->normals[3 * (size_t)idx[k]];
    const float *nb = &mesh->normals[3 * (size_t)idx[(k + 1) % 3]];
    return na[0] != nb[0] || na[1] != nb[1] || na[2] != nb[2];
}

bool wx_mesh_triangle_curves(const wx_mesh_data *mesh, int64_t t)
{
    return edge_curves(mesh, t, 0) || edge_curves(mesh, t, 1) || edge_curves(mesh, t, 2);
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double wx_mesh_curved_edge_length(const wx_mesh_data *mesh, double quantile)
{
    size_t count = 0;
    double *lengths = malloc((size_t)(mesh->triangle_count > 0 ? mesh->triangle_count : 1) * 3 *
                             sizeof *lengths);
    double longest = 0.0;
    for (int64_t t = 0; t < mesh->triangle_count; ++t) {
        const uint32_t *idx = &mesh->indices[3 * t];
        for (int k = 0; k < 3; ++k) {
            uint32_t a = idx[k], b = idx[(k + 1) % 3];
            if (!edge_curves(mesh, t, k)) {
                continue;
            }
            const float *pa = &mesh->positions[3 * (size_t)a];
            const float *pb = &mesh->positions[3 * (size_t)b];
            double dx = (double)pb[0] - pa[0], dy = (double)pb[1] - pa[1],
                   dz = (double)pb[2] - pa[2];
            double len = sqrt(dx * dx + dy * dy + dz * dz);
            longest = len > longest ? len : longest;
            if (lengths != NULL) {
                lengths[count++] = len;
            }
        }
    }
    if (lengths == NULL || count == 0 || quantile >= 1.0) {
        free(lengths);
        return longest; // out of memory: the longest, found on the way
    }
    qsort(lengths, count, sizeof *lengths, compare_doubles);
    double q = lengths[(size_t)(quantile * (double)(count - 1))];
    free(lengths);
    return q;
}

int64_t wx_mesh_curved_triangles(const wx_mesh_data *mesh)
{
    int64_t n = 0;
    for (int64_t t = 0; t < mesh->triangle_count; ++t) {
        n += wx_mesh_triangle_curves(mesh, t);
    }
    return n;
}

wx_result wx_mesh_smooth_subdivide(wx_mesh_data *mesh, int level, wx_error *err)
{
    if (level <= 1 || mesh->triangle_count == 0) {
        return WX_OK;
    }
    int64_t curved = wx_mesh_curved_triangles(mesh);
    int64_t per_tri_v = (int64_t)(level + 1) * (level + 2) / 2;
    int64_t per_tri_t = (int64_t)level * level;
    int64_t flat = mesh->triangle_count - curved;
    int64_t nv = mesh->vertex_count + curved * per_tri_v;
    int64_t nt = flat + curved * per_tri_t;
    if (nv > UINT32_MAX || nt * 3 > INT32_MAX) {
        return wx_fail(err, WX_CAUSE_BAD_MESH, "the smooth surface of %lld triangles cut %d x %d "
                       "is more than one draw takes", (long long)curved, level, level);
    }
    float *positions = malloc((size_t)nv * 3 * sizeof *positions);
    float *normals = malloc((size_t)nv * 3 * sizeof *normals);
    float *colors = mesh->colors != NULL ? malloc((size_t)nv * 4 * sizeof *colors) : NULL;
    uint32_t *indices = malloc((size_t)nt * 3 * sizeof *indices);
    uint16_t *materials = malloc((size_t)nt * sizeof *materials);
    if (positions == NULL || normals == NULL || (mesh->colors != NULL && colors == NULL) ||
        indices == NULL || materials == NULL) {
        free(positions);
        free(normals);
        free(colors);
        free(indices);
        free(materials);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY,
                       "out of memory for the smooth surface (%lld triangles)", (long long)nt);
    }
    size_t old_v = (size_t)mesh->vertex_count;
    memcpy(positions, mesh->positions, old_v * 3 * sizeof *positions);
    memcpy(normals, mesh->normals, old_v * 3 * sizeof *normals);
    if (colors != NULL) {
        memcpy(colors, mesh->colors, old_v * 4 * sizeof *colors);
    }
    size_t v = old_v, t_out = 0;
    for (int64_t t = 0; t < mesh->triangle_count; ++t) {
        const uint32_t *idx = &mesh->indices[3 * t];
        if (!wx_mesh_triangle_curves(mesh, t)) {
            memcpy(&indices[3 * t_out], idx, 3 * sizeof *idx);
            materials[t_out++] = mesh->materials[t];
            continue;
        }
        // Grid point (i, j), 0 <= i + j <= level: weights (level-i-j, i, j) / level.
        size_t base = v;
        for (int j = 0; j <= level; ++j) {
            for (int i = 0; i + j <= level; ++i) {
                double w[3] = { (double)(level - i - j) / level, (double)i / level,
                                (double)j / level };
                double p[3];
                wx_mesh_phong_point(mesh, t, w, p);
                wx_mesh_phong_normal(mesh, t, w, &normals[3 * v]);
                for (int a = 0; a < 3; ++a) {
                    positions[3 * v + (size_t)a] = (float)p[a];
                }
                for (int a = 0; a < 4 && colors != NULL; ++a) {
                    double c = 0.0;
                    for (int k = 0; k < 3; ++k) {
                        c += w[k] * mesh->colors[4 * (size_t)idx[k] + (size_t)a];
                    }
                    colors[4 * v + (size_t)a] = (float)c;
                }
                v++;
            }
        }
        // Row j starts at base + j*(level+1) - j*(j-1)/2 and holds level+1-j points.
        for (int j = 0; j < level; ++j) {
            size_t row = base + (size_t)(j * (level + 1) - j * (j - 1) / 2);
            size_t next = row + (size_t)(level + 1 - j);
            for (int i = 0; i + j < level; ++i) {
                uint32_t a = (uint32_t)(row + (size_t)i), b = a + 1, c = (uint32_t)(next + (size_t)i);
                indices[3 * t_out] = a;
                indices[3 * t_out + 1] = b;
                indices[3 * t_out + 2] = c;
                materials[t_out++] = mesh->materials[t];
                if (i + j + 1 < level) {
                    indices[3 * t_out] = b;
                    indices[3 * t_out + 1] = c + 1;
                    indices[3 * t_out + 2] = c;
                    materials[t_out++] = mesh->materials[t];
                }
            }
        }
    }
    free(mesh->positions);
    free(mesh->normals);
    free(mesh->colors);
    free(mesh->indices);
    free(mesh->materials);
    free(mesh->creases); // the pieces are drawn, not cut again
    mesh->positions = positions;
    mesh->normals = normals;
    mesh->colors = colors;
    mesh->indices = indices;
    mesh->materials = materials;
    mesh->creases = NULL;
    mesh->vertex_count = (int64_t)v;
    mesh->triangle_count = (int64_t)t_out;
    return WX_OK;
}

// --- creases ---------------------------------------------------------------------

// One edge of a triangle: hashes of its ends' positions and of the normals the
// triangle gives them, both in the order corner_after puts the ends (-0 as +0).
typedef struct edge_record {
    uint64_t where, normals;
    uint32_t tri;
    uint8_t k; ///< the edge from corner k to corner k + 1
} edge_record;

// The bits of a coordinate, -0 as +0 (the same position or normal).
static uint32_t coordinate_bits(float f)
{
    f = f == 0.0f ? 0.0f : f;
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

static uint64_t mix64(uint64_t h, const float *v)
{
    for (int a = 0; a < 3; ++a) {
        h ^= coordinate_bits(v[a]);
        h *= 0x9E3779B97F4A7C15ull;
        h ^= h >> 29;
    }
    return h;
}

static int compare_records(const void *a, const void *b)
{
    const edge_record *x = a, *y = b;
    if (x->where != y->where) {
        return x->where < y->where ? -1 : 1;
    }
    if (x->normals != y->normals) {
        return x->normals < y->normals ? -1 : 1;
    }
    return x->tri != y->tri ? (x->tri < y->tri ? -1 : 1) : (int)x->k - (int)y->k;
}

wx_result wx_mesh_find_creases(wx_mesh_data *mesh, wx_error *err)
{
    free(mesh->creases);
    mesh->creases = NULL;
    size_t T = (size_t)mesh->triangle_count;
    if (T == 0 || mesh->normals == NULL) {
        return WX_OK;
    }
    edge_record *rec = malloc(3 * T * sizeof *rec);
    uint8_t *creases = calloc(T, 1);
    if (rec == NULL || creases == NULL) {
        free(rec);
        free(creases);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory finding the mesh's creases");
    }
    size_t n = 0;
    for (size_t t = 0; t < T; ++t) {
        const uint32_t *idx = &mesh->indices[3 * t];
        for (int k = 0; k < 3; ++k) {
            uint32_t lo = idx[k], hi = idx[(k + 1) % 3];
            const float *pl = &mesh->positions[3 * (size_t)lo];
            const float *ph = &mesh->positions[3 * (size_t)hi];
            if (pl[0] == ph[0] && pl[1] == ph[1] && pl[2] == ph[2]) {
                continue; // no length: nothing to bend
            }
            if (pl[0] > ph[0] ||
                (pl[0] == ph[0] && (pl[1] > ph[1] || (pl[1] == ph[1] && pl[2] > ph[2])))) {
                uint32_t swap = lo;
                lo = hi;
                hi = swap;
            }
            const uint64_t seed = 0x243F6A8885A308D3ull;
            uint64_t where = mix64(mix64(seed, &mesh->positions[3 * (size_t)lo]),
                                   &mesh->positions[3 * (size_t)hi]);
            uint64_t normals =
                mix64(mix64(seed, &mesh->normals[3 * (size_t)lo]), &mesh->normals[3 * (size_t)hi]);
            rec[n++] = (edge_record){ where, normals, (uint32_t)t, (uint8_t)k };
        }
    }
    // Sorted, an edge's triangles lie together (the ones that give it the same
    // normals together too): it is a crease when its first and last differ.
    // Two edges whose positions share a hash would only both be kept
    // straight, on both sides alike: no crack either way.
    qsort(rec, n, sizeof *rec, compare_records);
    bool any = false;
    for (size_t a = 0; a < n;) {
        size_t b = a + 1;
        while (b < n && rec[b].where == rec[a].where) {
            b++;
        }
        if (rec[b - 1].normals != rec[a].normals) {
            for (size_t i = a; i < b; ++i) {
                creases[rec[i].tri] |= (uint8_t)(1u << rec[i].k);
            }
            any = true;
        }
        a = b;
    }
    free(rec);
    if (any) {
        mesh->creases = creases;
    } else {
        free(creases);
    }
    return WX_OK;
}

// --- parts wound inwards ---------------------------------------------------------

typedef struct position_key {
    uint32_t bits[3]; // the coordinates' bits, -0 as +0
    uint32_t vertex;
} position_key;

typedef struct edge_key {
    uint64_t ends;    // the smaller position id in the high half
    uint32_t forward; // 1 when the triangle runs from the smaller id to the larger
    uint32_t part;
} edge_key;

static int compare_positions(const void *a, const void *b)
{
    const position_key *x = a, *y = b;
    for (int k = 0; k < 3; ++k) {
        if (x->bits[k] != y->bits[k]) {
            return x->bits[k] < y->bits[k] ? -1 : 1;
        }
    }
    return x->vertex < y->vertex ? -1 : x->vertex > y->vertex;
}

static int compare_edges(const void *a, const void *b)
{
    const edge_key *x = a, *y = b;
    if (x->ends != y->ends) {
        return x->ends < y->ends ? -1 : 1;
    }
    return x->forward < y->forward ? -1 : x->forward > y->forward;
}

static uint32_t find_root(uint32_t *parent, uint32_t i)
{
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

typedef struct part_sums {
    double volume;  // six times the signed volume of the triangles' winding
    double flux;    // sum of area x (centroid . mean corner normal)
    double lo[3], hi[3];
    int64_t first;  // its first triangle
    bool open;
    bool mixed;     // an edge two triangles run the same way
} part_sums;

// Closed, and of a volume above a millionth of its bounding box's.
static bool part_bounds_a_volume(const part_sums *s)
{
    double box = (s->hi[0] - s->lo[0]) * (s->hi[1] - s->lo[1]) * (s->hi[2] - s->lo[2]);
    return !s->open && fabs(s->volume) > 6e-6 * box;
}

// Whether point x lies inside closed part `r`: a ray from x crosses its
// triangles an odd number of times (its direction skewed off the axes, so
// that it meets no edge of an axis-aligned model).
static bool inside_part(const wx_mesh_data *mesh, const uint32_t *part_of_triangle, int64_t T,
                        uint32_t r, const double x[3])
{
    static const double dir[3] = { 0.8017837257372732, 0.5345224838248488,
                                   0.2672612419124244 };
    int crossings = 0;
    for (int64_t t = 0; t < T; ++t) {
        if (part_of_triangle[t] != r) {
            continue;
        }
        double p[3][3];
        for (int c = 0; c < 3; ++c) {
            for (int k = 0; k < 3; ++k) {
                p[c][k] = mesh->positions[3 * (size_t)mesh->indices[3 * t + c] + k];
            }
        }
        // Moller and Trumbore.
        double e1[3], e2[3], h[3], s[3], q[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = p[1][k] - p[0][k];
            e2[k] = p[2][k] - p[0][k];
            s[k] = x[k] - p[0][k];
        }
        h[0] = dir[1] * e2[2] - dir[2] * e2[1];
        h[1] = dir[2] * e2[0] - dir[0] * e2[2];
        h[2] = dir[0] * e2[1] - dir[1] * e2[0];
        double a = e1[0] * h[0] + e1[1] * h[1] + e1[2] * h[2];
        if (fabs(a) < 1e-300) {
            continue;
        }
        double u = (s[0] * h[0] + s[1] * h[1] + s[2] * h[2]) / a;
        q[0] = s[1] * e1[2] - s[2] * e1[1];
        q[1] = s[2] * e1[0] - s[0] * e1[2];
        q[2] = s[0] * e1[1] - s[1] * e1[0];
        double v = (dir[0] * q[0] + dir[1] * q[1] + dir[2] * q[2]) / a;
        double along = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / a;
        crossings += u >= 0.0 && v >= 0.0 && u + v <= 1.0 && along > 0.0;
    }
    return crossings % 2 == 1;
}

wx_result wx_mesh_orient_outwards(wx_mesh_data *mesh, int64_t *turned, wx_error *err)
{
    if (turned != NULL) {
        *turned = 0;
    }
    mesh->parts_wound_both_ways = 0;
    const int64_t V = mesh->vertex_count, T = mesh->triangle_count;
    if (V <= 0 || T <= 0 || mesh->positions == NULL || mesh->indices == NULL ||
        V > (int64_t)UINT32_MAX || T > INT64_MAX / 48) {
        return WX_OK;
    }
    // Position ids: vertices at the same position share one.
    position_key *keys = malloc((size_t)V * sizeof *keys);
    uint32_t *pid = malloc((size_t)V * sizeof *pid);
    if (keys == NULL || pid == NULL) {
        free(keys);
        free(pid);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (mesh orientation)");
    }
    for (int64_t v = 0; v < V; ++v) {
        for (int k = 0; k < 3; ++k) {
            keys[v].bits[k] = coordinate_bits(mesh->positions[3 * v + k]);
        }
        keys[v].vertex = (uint32_t)v;
    }
    qsort(keys, (size_t)V, sizeof *keys, compare_positions);
    uint32_t P = 0;
    for (int64_t i = 0; i < V; ++i) {
        if (i > 0 && memcmp(keys[i].bits, keys[i - 1].bits, sizeof keys[i].bits) != 0) {
            ++P;
        }
        pid[keys[i].vertex] = P;
    }
    ++P;
    free(keys);

    // Parts: positions joined by the triangles' edges.
    uint32_t *parent = malloc((size_t)P * sizeof *parent);
    edge_key *edges = malloc((size_t)T * 3 * sizeof *edges);
    uint32_t *part_of = malloc((size_t)P * sizeof *part_of);
    uint32_t *part_of_triangle = malloc((size_t)T * sizeof *part_of_triangle);
    part_sums *parts = NULL;
    bool *flip_normals = NULL, *flip_winding = NULL;
    wx_result r = WX_OK;
    if (parent == NULL || edges == NULL || part_of == NULL || part_of_triangle == NULL) {
        r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (mesh orientation)");
        goto done;
    }
    for (uint32_t p = 0; p < P; ++p) {
        parent[p] = p;
    }
    const uint32_t *idx = mesh->indices;
    for (int64_t t = 0; t < T; ++t) {
        uint32_t a = find_root(parent, pid[idx[3 * t]]);
        for (int k = 1; k < 3; ++k) {
            uint32_t b = find_root(parent, pid[idx[3 * t + k]]);
            if (a != b) {
                parent[b] = a;
            }
        }
    }
    uint32_t part_count = 0;
    for (uint32_t p = 0; p < P; ++p) {
        part_of[p] = UINT32_MAX;
    }
    for (uint32_t p = 0; p < P; ++p) {
        uint32_t root = find_root(parent, p);
        if (part_of[root] == UINT32_MAX) {
            part_of[root] = part_count++;
        }
        part_of[p] = part_of[root];
    }
    for (int64_t t = 0; t < T; ++t) {
        part_of_triangle[t] = part_of[pid[idx[3 * t]]];
    }
    parts = calloc(part_count, sizeof *parts);
    flip_normals = calloc(part_count, sizeof *flip_normals);
    flip_winding = calloc(part_count, sizeof *flip_winding);
    if (parts == NULL || flip_normals == NULL || flip_winding == NULL) {
        r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (mesh orientation)");
        goto done;
    }
    for (uint32_t q = 0; q < part_count; ++q) {
        for (int k = 0; k < 3; ++k) {
            parts[q].lo[k] = INFINITY;
            parts[q].hi[k] = -INFINITY;
        }
        parts[q].first = -1;
    }

    // Closed: every edge shared by exactly two triangles running opposite ways.
    // A triangle with two corners at one position bounds nothing: left out.
    int64_t E = 0;
    for (int64_t t = 0; t < T; ++t) {
        uint32_t c0 = pid[idx[3 * t]], c1 = pid[idx[3 * t + 1]], c2 = pid[idx[3 * t + 2]];
        if (c0 == c1 || c1 == c2 || c2 == c0) {
            continue;
        }
        for (int k = 0; k < 3; ++k) {
            uint32_t a = pid[idx[3 * t + k]], b = pid[idx[3 * t + (k + 1) % 3]];
            edge_key *e = &edges[E++];
            e->ends = a < b ? ((uint64_t)a << 32) | b : ((uint64_t)b << 32) | a;
            e->forward = a < b;
            e->part = part_of_triangle[t];
        }
    }
    qsort(edges, (size_t)E, sizeof *edges, compare_edges);
    for (int64_t i = 0; i < E;) {
        int64_t j = i + 1;
        while (j < E && edges[j].ends == edges[i].ends) {
            ++j;
        }
        if (j - i != 2 || edges[i].forward == edges[i + 1].forward) {
            parts[edges[i].part].open = true;
        }
        if (j - i == 2 && edges[i].forward == edges[i + 1].forward) {
            parts[edges[i].part].mixed = true;
        }
        i = j;
    }
    for (uint32_t q = 0; q < part_count; ++q) {
        mesh->parts_wound_both_ways += parts[q].mixed;
    }

    // The sums per part.
    for (int64_t t = 0; t < T; ++t) {
        part_sums *s = &parts[part_of_triangle[t]];
        s->first = s->first < 0 ? t : s->first;
        double p[3][3], n[3] = { 0.0, 0.0, 0.0 };
        for (int c = 0; c < 3; ++c) {
            uint32_t v = idx[3 * t + c];
            for (int k = 0; k < 3; ++k) {
                p[c][k] = mesh->positions[3 * (size_t)v + k];
                n[k] += mesh->normals != NULL ? mesh->normals[3 * (size_t)v + k] : 0.0;
                s->lo[k] = fmin(s->lo[k], p[c][k]);
                s->hi[k] = fmax(s->hi[k], p[c][k]);
            }
        }
        double e1[3], e2[3], cr[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = p[1][k] - p[0][k];
            e2[k] = p[2][k] - p[0][k];
        }
        cr[0] = e1[1] * e2[2] - e1[2] * e2[1];
        cr[1] = e1[2] * e2[0] - e1[0] * e2[2];
        cr[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double area2 = sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
        double nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        double centroid_n = 0.0, centroid_cr = 0.0;
        for (int k = 0; k < 3; ++k) {
            double c = (p[0][k] + p[1][k] + p[2][k]) / 3.0;
            centroid_n += c * n[k];
            centroid_cr += c * cr[k];
        }
        s->volume += centroid_cr; // 3 x (centroid . cross) / 3 = p0 . (p1 x p2) summed
        // Without usable corner normals the renderer uses the triangle's plane.
        s->flux += nl > 1e-12 ? area2 * centroid_n / nl : centroid_cr;
    }

    // Turn what points in.
    bool any = false;
    for (uint32_t q = 0; q < part_count; ++q) {
        const part_sums *s = &parts[q];
        if (!part_bounds_a_volume(s) || !(s->flux < 0.0 || s->volume < 0.0)) {
            continue;
        }
        // A closed part inside another closed part is a cavity (a room's
        // walls seen from inside, the inner shell of a hollow ball): its
        // normals point into it by design.
        bool cavity = false;
        for (uint32_t o = 0; o < part_count && !cavity; ++o) {
            const part_sums *so = &parts[o];
            bool around = o != q && part_bounds_a_volume(so);
            for (int k = 0; k < 3 && around; ++k) {
                around = so->lo[k] <= s->lo[k] && so->hi[k] >= s->hi[k];
            }
            if (!around) {
                continue;
            }
            double x[3];
            for (int k = 0; k < 3; ++k) {
                x[k] = mesh->positions[3 * (size_t)idx[3 * s->first] + k];
            }
            cavity = inside_part(mesh, part_of_triangle, T, o, x);
        }
        if (cavity) {
            continue;
        }
        flip_normals[q] = s->flux < 0.0 && mesh->normals != NULL;
        flip_winding[q] = s->volume < 0.0;
        any |= flip_normals[q] || flip_winding[q];
        if (turned != NULL) {
            *turned += flip_normals[q];
        }
    }
    if (any) {
        for (int64_t v = 0; v < V; ++v) {
            if (flip_normals[part_of[pid[v]]]) {
                for (int k = 0; k < 3; ++k) {
                    mesh->normals[3 * v + k] = -mesh->normals[3 * v + k];
                }
            }
        }
        for (int64_t t = 0; t < T; ++t) {
            if (flip_winding[part_of_triangle[t]]) {
                uint32_t swap = mesh->indices[3 * t + 1];
                mesh->indices[3 * t + 1] = mesh->indices[3 * t + 2];
                mesh->indices[3 * t + 2] = swap;
            }
        }
    }
done:
    free(flip_normals);
    free(flip_winding);
    free(part_of_triangle);
    free(parts);
    free(part_of);
    free(edges);
    free(parent);
    free(pid);
    return r;
}

int wx_mesh_depth_complexity(const wx_mesh_data *mesh, const double axis[3], int grid)
{
    if (mesh->triangle_count <= 0 || mesh->positions == NULL || grid < 1) {
        return 0;
    }
    // A basis (a, b) of the plane across the axis.
    double a[3], b[3];
    wx_perpendicular_basis(axis, a, b);
    double lo[2] = { INFINITY, INFINITY }, hi[2] = { -INFINITY, -INFINITY };
    for (int64_t v = 0; v < mesh->vertex_count; ++v) {
        const float *p = &mesh->positions[3 * v];
        double x = p[0] * a[0] + p[1] * a[1] + p[2] * a[2];
        double y = p[0] * b[0] + p[1] * b[1] + p[2] * b[2];
        lo[0] = fmin(lo[0], x);
        hi[0] = fmax(hi[0], x);
        lo[1] = fmin(lo[1], y);
        hi[1] = fmax(hi[1], y);
    }
    double cell[2] = { (hi[0] - lo[0]) / grid, (hi[1] - lo[1]) / grid };
    if (!(cell[0] > 0.0) || !(cell[1] > 0.0)) {
        return 1; // a flat mesh seen edge-on, or a single point
    }
    uint16_t *count = calloc((size_t)grid * (size_t)grid, sizeof *count);
    if (count == NULL) {
        return -1;
    }
    // Ray (i, j) passes through lo + (i + f, j + f) * cell; f off one half so
    // that the rays miss the edges a regular mesh puts on the cells' centres.
    const double f = 0.5 + 0.0137;
    int most = 0;
    for (int64_t t = 0; t < mesh->triangle_count; ++t) {
        double x[3], y[3];
        for (int k = 0; k < 3; ++k) {
            const float *p = &mesh->positions[3 * (size_t)mesh->indices[3 * t + k]];
            x[k] = (p[0] * a[0] + p[1] * a[1] + p[2] * a[2] - lo[0]) / cell[0] - f;
            y[k] = (p[0] * b[0] + p[1] * b[1] + p[2] * b[2] - lo[1]) / cell[1] - f;
        }
        double area = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
        if (!(fabs(area) > 0.0)) {
            continue; // edge-on: no ray crosses it
        }
        int i0 = (int)fmax(0.0, ceil(fmin(x[0], fmin(x[1], x[2]))));
        int i1 = (int)fmin(grid - 1.0, floor(fmax(x[0], fmax(x[1], x[2]))));
        int j0 = (int)fmax(0.0, ceil(fmin(y[0], fmin(y[1], y[2]))));
        int j1 = (int)fmin(grid - 1.0, floor(fmax(y[0], fmax(y[1], y[2]))));
        double s = area > 0.0 ? 1.0 : -1.0;
        for (int j = j0; j <= j1; ++j) {
            for (int i = i0; i <= i1; ++i) {
                double e0 = s * ((x[1] - x[0]) * (j - y[0]) - (i - x[0]) * (y[1] - y[0]));
                double e1 = s * ((x[2] - x[1]) * (j - y[1]) - (i - x[1]) * (y[2] - y[1]));
                double e2 = s * ((x[0] - x[2]) * (j - y[2]) - (i - x[2]) * (y[0] - y[2]));
                if (e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0) {
                    uint16_t *c = &count[(size_t)j * (size_t)grid + (size_t)i];
                    *c = *c < UINT16_MAX ? (uint16_t)(*c + 1) : *c;
                    most = *c > most ? *c : most;
                }
            }
        }
    }
    free(count);
    return most;
}
