// mesh_postprocess.c: normals and shared vertices of each imported aiMesh, in
// time linear in the triangles
//
// Assimp's aiProcess_GenSmoothNormals (with a smoothing angle) and
// aiProcess_JoinIdenticalVertices compare every vertex with every other one at
// the same position: an OBJ whose faces reuse a few positions took 2.8 s for
// 100 KB, 64 s for 400 KB and hours for 4 MB (issue 24). They are done here
// instead, with hash tables, on the triangles' corners:
// - a corner's normal is the file's normal of its vertex; where the file has
//   none, the sum of the face normals at the corner's position (bit for bit)
//   within WX_MESH_SMOOTHING_ANGLE_DEG of its own face's, normalised: what
//   Assimp computes for an unindexed mesh (an OBJ's), compared in float as
//   Assimp compares them. A position where more than PREP_EXACT_NORMALS
//   distinct face normals meet (a fan of hundreds of triangles) sums them by
//   cells of the sphere instead (PREP_CELLS a cube face), so that no position
//   costs more than that per corner;
// - corners with the same position, normal, UVs and colour become one vertex,
//   in the order of their first corner.
#include "io/mesh_postprocess.h"

#include <assimp/mesh.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "io/mesh_import.h"

enum {
    PREP_EXACT_NORMALS = 384, ///< distinct face normals at a position compared pairwise
    PREP_CELLS = 8,           ///< cells along a cube face's side for larger positions
    PREP_EMPTY = -1,
};

bool wx_mesh_is_triangle(const struct aiFace *f, unsigned vertex_count)
{
    return f->mNumIndices == 3 && f->mIndices[0] < vertex_count && f->mIndices[1] < vertex_count &&
           f->mIndices[2] < vertex_count;
}

void wx_mesh_prep_free(wx_mesh_prep *p)
{
    free(p->corner);
    free(p->source);
    free(p->normal);
    memset(p, 0, sizeof *p);
}

// The bits of a float, with -0 as +0 (the same position or normal).
static uint32_t float_bits(float f)
{
    uint32_t u;
    f = f == 0.0f ? 0.0f : f;
    memcpy(&u, &f, sizeof u);
    return u;
}

static uint64_t hash_mix(uint64_t h, uint32_t v)
{
    h ^= v + UINT64_C(0x9e3779b97f4a7c15) + (h << 6) + (h >> 2);
    h ^= h >> 31;
    return h * UINT64_C(0xbf58476d1ce4e5b9);
}

static uint64_t hash_floats(uint64_t h, const float *f, int n)
{
    for (int k = 0; k < n; ++k) {
        h = hash_mix(h, float_bits(f[k]));
    }
    return h;
}

static bool same_floats(const float *a, const float *b, int n)
{
    for (int k = 0; k < n; ++k) {
        if (float_bits(a[k]) != float_bits(b[k])) {
            return false;
        }
    }
    return true;
}

// An open-addressed table of ids (PREP_EMPTY: a free slot), at least twice
// as many slots as entries.
typedef struct id_table {
    int32_t *slot;
    size_t mask;
} id_table;

static bool table_init(id_table *t, size_t entries)
{
    size_t cap = 16;
    while (cap < 2 * entries) {
        cap *= 2;
    }
    t->slot = malloc(cap * sizeof *t->slot);
    t->mask = cap - 1;
    if (t->slot != NULL) {
        memset(t->slot, 0xff, cap * sizeof *t->slot); // PREP_EMPTY
    }
    return t->slot != NULL;
}

// Assimp's face normal (GenVertexNormalsProcess): the cross product of the
// edges from the first corner, normalised in float, 0 when it has no length.
static void face_normal(const struct aiMesh *mesh, const struct aiFace *face, float n[3])
{
    const struct aiVector3D *a = &mesh->mVertices[face->mIndices[0]];
    const struct aiVector3D *b = &mesh->mVertices[face->mIndices[1]];
    const struct aiVector3D *c = &mesh->mVertices[face->mIndices[face->mNumIndices - 1]];
    float e1[3] = { b->x - a->x, b->y - a->y, b->z - a->z };
    float e2[3] = { c->x - a->x, c->y - a->y, c->z - a->z };
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    float len = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (len > 0.0f) {
        float inv = 1.0f / len;
        n[0] *= inv;
        n[1] *= inv;
        n[2] *= inv;
    }
}

static float dot_f(const float *a, const float *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static bool is_nan3(const float *n)
{
    return isnan(n[0]) || isnan(n[1]) || isnan(n[2]);
}

// The cell of a unit vector on a cube of PREP_CELLS x PREP_CELLS cells a face.
static int normal_cell(const float *n)
{
    float ax = fabsf(n[0]), ay = fabsf(n[1]), az = fabsf(n[2]);
    int axis = ax >= ay && ax >= az ? 0 : ay >= az ? 1 : 2;
    float big = fmaxf(ax, fmaxf(ay, az));
    int face = 2 * axis + (n[axis] < 0.0f);
    float s = n[(axis + 1) % 3] / big, t = n[(axis + 2) % 3] / big; // in [-1, 1]
    int i = (int)fminf(PREP_CELLS - 1.0f, fmaxf(0.0f, (s + 1.0f) * 0.5f * PREP_CELLS));
    int j = (int)fminf(PREP_CELLS - 1.0f, fmaxf(0.0f, (t + 1.0f) * 0.5f * PREP_CELLS));
    return (face * PREP_CELLS + j) * PREP_CELLS + i;
}

// The smoothed normal of each distinct face normal of one position:
// dist[first..first+count) (indices into normal/weight), results into out.
// Sums in double; `limit` the cosine of the smoothing angle.
static void smooth_position(const uint32_t *members, size_t count, const float *normal,
                            const uint32_t *weight, float limit, float *out, double *cell_sum)
{
    if (count <= PREP_EXACT_NORMALS) {
        for (size_t a = 0; a < count; ++a) {
            const float *na = &normal[3 * members[a]];
            double s[3] = { 0.0, 0.0, 0.0 };
            for (size_t b = 0; b < count; ++b) {
                const float *nb = &normal[3 * members[b]];
                // As Assimp: within the angle of this face's normal (a NaN
                // normal of its own compares with nothing, so takes all), and
                // never a NaN one.
                if ((b != a && dot_f(nb, na) < limit) || is_nan3(nb)) {
                    continue;
                }
                for (int k = 0; k < 3; ++k) {
                    s[k] += (double)weight[members[b]] * nb[k];
                }
            }
            double len = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
            for (int k = 0; k < 3; ++k) {
                out[3 * members[a] + k] = len > 0.0 ? (float)(s[k] / len) : (float)s[k];
            }
        }
        return;
    }
    // Many directions at one point (a fan of hundreds of triangles): the
    // normals are summed by cells, and each cell takes the cells whose mean
    // direction lies within the angle of its own.
    enum { CELLS = 6 * PREP_CELLS * PREP_CELLS };
    memset(cell_sum, 0, 3 * CELLS * sizeof *cell_sum);
    bool used[CELLS] = { false };
    double all[3] = { 0.0, 0.0, 0.0 };
    for (size_t a = 0; a < count; ++a) {
        const float *n = &normal[3 * members[a]];
        if (is_nan3(n) || (n[0] == 0.0f && n[1] == 0.0f && n[2] == 0.0f)) {
            continue;
        }
        int c = normal_cell(n);
        used[c] = true;
        for (int k = 0; k < 3; ++k) {
            cell_sum[3 * c + k] += (double)weight[members[a]] * n[k];
            all[k] += (double)weight[members[a]] * n[k];
        }
    }
    float mean[CELLS][3];
    for (int c = 0; c < CELLS; ++c) {
        double len =
            sqrt(cell_sum[3 * c] * cell_sum[3 * c] + cell_sum[3 * c + 1] * cell_sum[3 * c + 1] +
                 cell_sum[3 * c + 2] * cell_sum[3 * c + 2]);
        for (int k = 0; k < 3; ++k) {
            mean[c][k] = len > 0.0 ? (float)(cell_sum[3 * c + k] / len) : 0.0f;
        }
    }
    for (size_t a = 0; a < count; ++a) {
        const float *n = &normal[3 * members[a]];
        double s[3] = { 0.0, 0.0, 0.0 };
        if (is_nan3(n)) {
            memcpy(s, all, sizeof s);
        } else if (n[0] != 0.0f || n[1] != 0.0f || n[2] != 0.0f) {
            int own = normal_cell(n);
            for (int c = 0; c < CELLS; ++c) {
                if (used[c] && (c == own || dot_f(mean[c], mean[own]) >= limit)) {
                    for (int k = 0; k < 3; ++k) {
                        s[k] += cell_sum[3 * c + k];
                    }
                }
            }
        }
        double len = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
        for (int k = 0; k < 3; ++k) {
            out[3 * members[a] + k] = len > 0.0 ? (float)(s[k] / len) : 0.0f;
        }
    }
}

// The vertices' normals of a mesh without normals in the file, as Assimp's
// GenVertexNormalsProcess makes them: each vertex takes the normal of the last
// face that uses it (not a number for a point or a line), then the sum of the
// normals of the vertices at its position within the smoothing angle of its
// own, normalised. (A quad's two triangles share its vertices, so it counts
// once at each corner, as a face of the file.) normal[3 * vertex].
static bool smooth_normals(const struct aiMesh *mesh, float *normal)
{
    const size_t V = mesh->mNumVertices;
    uint32_t *group = malloc(V * sizeof *group);       // vertex -> position
    uint32_t *distinct = malloc(V * sizeof *distinct); // vertex -> (position, normal)
    float *face = calloc(3 * V, sizeof *face);         // vertex -> its last face's normal
    uint32_t *rep = malloc(V * sizeof *rep);           // position -> a vertex there
    float *dnormal = malloc(3 * V * sizeof *dnormal);  // distinct -> its face normal
    uint32_t *dgroup = malloc(V * sizeof *dgroup);
    uint32_t *dcount = malloc(V * sizeof *dcount);
    uint32_t *start = calloc(V + 1, sizeof *start);
    uint32_t *members = malloc(V * sizeof *members);
    float *smoothed = malloc(3 * V * sizeof *smoothed);
    double *cell_sum = malloc(3 * 6 * PREP_CELLS * PREP_CELLS * sizeof *cell_sum);
    id_table table = { 0 };
    bool ok = group != NULL && distinct != NULL && face != NULL && rep != NULL && dnormal != NULL &&
              dgroup != NULL && dcount != NULL && start != NULL && members != NULL &&
              smoothed != NULL && cell_sum != NULL && table_init(&table, V);
    uint32_t groups = 0, distincts = 0;
    for (unsigned f = 0; ok && f < mesh->mNumFaces; ++f) {
        const struct aiFace *fc = &mesh->mFaces[f];
        float n[3] = { NAN, NAN, NAN };
        if (fc->mNumIndices >= 3) {
            face_normal(mesh, fc, n);
        }
        for (unsigned k = 0; k < fc->mNumIndices; ++k) {
            if (fc->mIndices[k] < V) {
                memcpy(&face[3 * (size_t)fc->mIndices[k]], n, sizeof n);
            }
        }
    }
    // Positions, bit for bit.
    for (size_t v = 0; ok && v < V; ++v) {
        const float *p = &mesh->mVertices[v].x;
        for (size_t s = hash_floats(1, p, 3) & table.mask;; s = (s + 1) & table.mask) {
            int32_t g = table.slot[s];
            if (g == PREP_EMPTY) {
                table.slot[s] = (int32_t)groups;
                rep[groups] = (uint32_t)v;
                group[v] = groups++;
                break;
            }
            if (same_floats(&mesh->mVertices[rep[g]].x, p, 3)) {
                group[v] = (uint32_t)g;
                break;
            }
        }
    }
    // Distinct face normals at each position, with how many vertices have them.
    if (ok) {
        memset(table.slot, 0xff, (table.mask + 1) * sizeof *table.slot);
    }
    for (size_t v = 0; ok && v < V; ++v) {
        const float *n = &face[3 * v];
        uint64_t h = hash_floats(hash_mix(2, group[v]), n, 3);
        for (size_t s = h & table.mask;; s = (s + 1) & table.mask) {
            int32_t d = table.slot[s];
            if (d == PREP_EMPTY) {
                table.slot[s] = (int32_t)distincts;
                memcpy(&dnormal[3 * (size_t)distincts], n, 3 * sizeof *n);
                dgroup[distincts] = group[v];
                dcount[distincts] = 1;
                distinct[v] = distincts++;
                break;
            }
            if (dgroup[d] == group[v] && same_floats(&dnormal[3 * (size_t)d], n, 3)) {
                dcount[d]++;
                distinct[v] = (uint32_t)d;
                break;
            }
        }
    }
    // The distinct normals of each position, together (a counting sort).
    for (uint32_t d = 0; ok && d < distincts; ++d) {
        start[dgroup[d] + 1]++;
    }
    for (uint32_t g = 0; ok && g < groups; ++g) {
        start[g + 1] += start[g];
    }
    for (uint32_t d = 0; ok && d < distincts; ++d) {
        members[start[dgroup[d]]++] = d;
    }
    for (uint32_t g = groups; ok && g > 0; --g) {
        start[g] = start[g - 1];
    }
    if (ok) {
        start[0] = 0;
    }
    const float limit = cosf(WX_MESH_SMOOTHING_ANGLE_DEG * 0.0174532925f);
    for (uint32_t g = 0; ok && g < groups; ++g) {
        smooth_position(&members[start[g]], start[g + 1] - start[g], dnormal, dcount, limit,
                        smoothed, cell_sum);
    }
    for (size_t v = 0; ok && v < V; ++v) {
        memcpy(&normal[3 * v], &smoothed[3 * (size_t)distinct[v]], 3 * sizeof *normal);
    }
    free(group);
    free(distinct);
    free(face);
    free(rep);
    free(dnormal);
    free(dgroup);
    free(dcount);
    free(start);
    free(members);
    free(smoothed);
    free(cell_sum);
    free(table.slot);
    return ok;
}

// The attributes two corners must share to be one vertex, besides the normal.
static uint64_t vertex_hash(const struct aiMesh *mesh, unsigned v, unsigned uv_channels,
                            const float *normal)
{
    uint64_t h = hash_floats(3, &mesh->mVertices[v].x, 3);
    h = hash_floats(h, normal, 3);
    for (unsigned c = 0; c < WX_MESH_MAX_UV_CHANNELS; ++c) {
        if ((uv_channels & (1u << c)) && mesh->mTextureCoords[c] != NULL) {
            h = hash_floats(h, &mesh->mTextureCoords[c][v].x, 2);
        }
    }
    if (mesh->mColors[0] != NULL) {
        h = hash_floats(h, &mesh->mColors[0][v].r, 4);
    }
    return h;
}

static bool same_vertex(const struct aiMesh *mesh, unsigned a, unsigned b, unsigned uv_channels)
{
    if (!same_floats(&mesh->mVertices[a].x, &mesh->mVertices[b].x, 3)) {
        return false;
    }
    for (unsigned c = 0; c < WX_MESH_MAX_UV_CHANNELS; ++c) {
        if ((uv_channels & (1u << c)) && mesh->mTextureCoords[c] != NULL &&
            !same_floats(&mesh->mTextureCoords[c][a].x, &mesh->mTextureCoords[c][b].x, 2)) {
            return false;
        }
    }
    return mesh->mColors[0] == NULL ||
           same_floats(&mesh->mColors[0][a].r, &mesh->mColors[0][b].r, 4);
}

// Numbers the corners of `mesh`'s triangles by joined vertex (see above).
// False when out of memory; a mesh of more corners than 32 bits hold is
// reported through *too_many.
bool wx_mesh_prepare(const struct aiMesh *mesh, unsigned uv_channels, wx_mesh_prep *out,
                     bool *too_many)
{
    memset(out, 0, sizeof *out);
    out->done = true;
    size_t tris = 0;
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
        tris += wx_mesh_is_triangle(&mesh->mFaces[f], mesh->mNumVertices);
    }
    if (tris == 0) {
        return true;
    }
    if (3 * tris >= (size_t)INT32_MAX) {
        *too_many = true;
        return true;
    }
    const size_t corners = 3 * tris;
    uint32_t *tri_face = malloc(tris * sizeof *tri_face);
    float *normal =
        mesh->mNormals == NULL ? malloc(3 * (size_t)mesh->mNumVertices * sizeof *normal) : NULL;
    out->corner = malloc(corners * sizeof *out->corner);
    out->source = malloc(corners * sizeof *out->source);
    out->normal = malloc(3 * corners * sizeof *out->normal);
    id_table table = { 0 };
    bool ok = tri_face != NULL && (normal != NULL || mesh->mNormals != NULL) &&
              out->corner != NULL && out->source != NULL && out->normal != NULL &&
              table_init(&table, corners);
    for (unsigned f = 0, t = 0; ok && f < mesh->mNumFaces; ++f) {
        if (wx_mesh_is_triangle(&mesh->mFaces[f], mesh->mNumVertices)) {
            tri_face[t++] = f;
        }
    }
    out->triangles = (uint32_t)tris;
    if (ok && mesh->mNormals == NULL) {
        ok = smooth_normals(mesh, normal);
    }
    const float *normals = mesh->mNormals != NULL ? &mesh->mNormals[0].x : normal;
    uint32_t joined = 0;
    for (size_t c = 0; ok && c < corners; ++c) {
        unsigned v = mesh->mFaces[tri_face[c / 3]].mIndices[c % 3];
        const float *n = &normals[3 * (size_t)v];
        for (size_t s = vertex_hash(mesh, v, uv_channels, n) & table.mask;;
             s = (s + 1) & table.mask) {
            int32_t j = table.slot[s];
            if (j == PREP_EMPTY) {
                table.slot[s] = (int32_t)joined;
                out->source[joined] = v;
                memcpy(&out->normal[3 * (size_t)joined], n, 3 * sizeof *n);
                out->corner[c] = joined++;
                break;
            }
            if (same_floats(&out->normal[3 * (size_t)j], n, 3) &&
                same_vertex(mesh, out->source[j], v, uv_channels)) {
                out->corner[c] = (uint32_t)j;
                break;
            }
        }
    }
    out->vertices = joined;
    free(tri_face);
    free(normal);
    free(table.slot);
    if (!ok) {
        wx_mesh_prep_free(out);
        out->done = true;
    }
    return ok;
}
