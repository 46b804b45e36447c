// mesh.c: Assimp import into flat arrays (see mesh.h).
//
// Two walks over the node tree: the first counts vertices and triangles, finds
// the materials in use and the world bounds; the second fills arrays allocated
// once. A mesh referenced by several nodes is instanced once per node.
#include "mesh.h"

#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { MAX_NODE_DEPTH = 1024 };

typedef struct import_state {
    const struct aiScene *scene;
    wx_mesh_data *out;
    int *material_slot;   // per aiMaterial: index into out->material_names, -1 when unused
    int64_t vertices;     // running counts
    int64_t triangles;
    bool any_colors;
    bool fill;            // false: count and bound; true: fill the arrays
    const char *problem;  // set when the file holds something we refuse
} import_state;

// A 4x4 affine transform for column vectors, as Assimp stores it (a4, b4, c4 =
// translation), in double.
typedef struct affine {
    double m[3][4];
} affine;

static affine affine_from_ai(const struct aiMatrix4x4 *t)
{
    affine a = { { { t->a1, t->a2, t->a3, t->a4 },
                   { t->b1, t->b2, t->b3, t->b4 },
                   { t->c1, t->c2, t->c3, t->c4 } } };
    return a;
}

static affine affine_mul(const affine *p, const affine *c)
{
    affine r;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 4; ++j) {
            double s = p->m[i][0] * c->m[0][j] + p->m[i][1] * c->m[1][j] + p->m[i][2] * c->m[2][j];
            r.m[i][j] = j == 3 ? s + p->m[i][3] : s;
        }
    }
    return r;
}

// Cofactor matrix of the upper 3x3 times the sign of its determinant: the
// inverse transpose up to a positive scale, which normalisation removes.
static void normal_matrix(const affine *a, double n[3][3])
{
    const double(*m)[4] = a->m;
    n[0][0] = m[1][1] * m[2][2] - m[1][2] * m[2][1];
    n[0][1] = m[1][2] * m[2][0] - m[1][0] * m[2][2];
    n[0][2] = m[1][0] * m[2][1] - m[1][1] * m[2][0];
    n[1][0] = m[0][2] * m[2][1] - m[0][1] * m[2][2];
    n[1][1] = m[0][0] * m[2][2] - m[0][2] * m[2][0];
    n[1][2] = m[0][1] * m[2][0] - m[0][0] * m[2][1];
    n[2][0] = m[0][1] * m[1][2] - m[0][2] * m[1][1];
    n[2][1] = m[0][2] * m[1][0] - m[0][0] * m[1][2];
    n[2][2] = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    double det = m[0][0] * n[0][0] + m[0][1] * n[0][1] + m[0][2] * n[0][2];
    double sign = det < 0.0 ? -1.0 : 1.0;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            n[i][j] *= sign;
        }
    }
}

static void transform_point(const affine *a, const struct aiVector3D *v, double out[3])
{
    for (int i = 0; i < 3; ++i) {
        out[i] = a->m[i][0] * v->x + a->m[i][1] * v->y + a->m[i][2] * v->z + a->m[i][3];
    }
}

static bool is_triangle(const struct aiFace *f, unsigned vertex_count)
{
    return f->mNumIndices == 3 && f->mIndices[0] < vertex_count &&
           f->mIndices[1] < vertex_count && f->mIndices[2] < vertex_count;
}

static void count_mesh(import_state *st, const struct aiMesh *mesh, const affine *xf)
{
    int64_t tris = 0;
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
        tris += is_triangle(&mesh->mFaces[f], mesh->mNumVertices);
    }
    if (tris == 0) {
        return; // points and lines only: nothing to render
    }
    st->triangles += tris;
    st->vertices += mesh->mNumVertices;
    st->material_slot[mesh->mMaterialIndex] = 0; // in use; numbered later
    st->any_colors = st->any_colors || mesh->mColors[0] != NULL;
    wx_mesh_data *out = st->out;
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
        double p[3];
        transform_point(xf, &mesh->mVertices[v], p);
        for (int i = 0; i < 3; ++i) {
            if (!isfinite(p[i])) {
                st->problem = "a vertex position that is not a finite number";
                return;
            }
            out->bounds_min[i] = p[i] < out->bounds_min[i] ? p[i] : out->bounds_min[i];
            out->bounds_max[i] = p[i] > out->bounds_max[i] ? p[i] : out->bounds_max[i];
        }
    }
}

static void fill_mesh(import_state *st, const struct aiMesh *mesh, const affine *xf)
{
    wx_mesh_data *out = st->out;
    int64_t first_tri = st->triangles;
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
        const struct aiFace *face = &mesh->mFaces[f];
        if (!is_triangle(face, mesh->mNumVertices)) {
            continue;
        }
        uint32_t *idx = &out->indices[3 * st->triangles];
        for (int k = 0; k < 3; ++k) {
            idx[k] = (uint32_t)(st->vertices + face->mIndices[k]);
        }
        out->materials[st->triangles] = (uint16_t)st->material_slot[mesh->mMaterialIndex];
        st->triangles++;
    }
    if (st->triangles == first_tri) {
        return;
    }
    double nm[3][3];
    normal_matrix(xf, nm);
    int slot = st->material_slot[mesh->mMaterialIndex];
    if (mesh->mColors[0] == NULL) {
        out->material_colored[slot] = false;
    }
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
        int64_t o = st->vertices + v;
        double p[3];
        transform_point(xf, &mesh->mVertices[v], p);
        for (int i = 0; i < 3; ++i) {
            out->positions[3 * o + i] = (float)(p[i] - out->origin[i]);
        }
        double n[3] = { 0.0, 0.0, 0.0 };
        if (mesh->mNormals != NULL) {
            const struct aiVector3D *s = &mesh->mNormals[v];
            for (int i = 0; i < 3; ++i) {
                n[i] = nm[i][0] * s->x + nm[i][1] * s->y + nm[i][2] * s->z;
            }
        }
        double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int i = 0; i < 3; ++i) {
            out->normals[3 * o + i] = len > 0.0 && isfinite(len) ? (float)(n[i] / len) : 0.0f;
        }
        if (out->colors != NULL) {
            float *c = &out->colors[4 * o];
            if (mesh->mColors[0] != NULL) {
                const struct aiColor4D *s = &mesh->mColors[0][v];
                c[0] = s->r;
                c[1] = s->g;
                c[2] = s->b;
                c[3] = s->a;
            } else {
                c[0] = c[1] = c[2] = 0.0f;
                c[3] = 1.0f;
            }
        }
    }
    st->vertices += mesh->mNumVertices;
}

static void walk(import_state *st, const struct aiNode *node, const affine *parent, int depth)
{
    if (node == NULL || st->problem != NULL) {
        return;
    }
    if (depth > MAX_NODE_DEPTH) {
        st->problem = "a node hierarchy deeper than 1024 levels";
        return;
    }
    affine local = affine_from_ai(&node->mTransformation);
    affine xf = affine_mul(parent, &local);
    for (unsigned i = 0; i < node->mNumMeshes && st->problem == NULL; ++i) {
        unsigned index = node->mMeshes[i];
        if (index >= st->scene->mNumMeshes) {
            continue;
        }
        const struct aiMesh *mesh = st->scene->mMeshes[index];
        if (mesh->mMaterialIndex >= st->scene->mNumMaterials) {
            st->problem = "a mesh whose material index is out of range";
            return;
        }
        if (st->fill) {
            fill_mesh(st, mesh, &xf);
        } else {
            count_mesh(st, mesh, &xf);
        }
    }
    for (unsigned i = 0; i < node->mNumChildren && st->problem == NULL; ++i) {
        walk(st, node->mChildren[i], &xf, depth + 1);
    }
}

static void material_name(const struct aiMaterial *mat, unsigned index,
                          char name[WX_MATERIAL_NAME_MAX])
{
    struct aiString s;
    if (aiGetMaterialString(mat, AI_MATKEY_NAME, &s) == aiReturn_SUCCESS && s.length > 0) {
        size_t n = s.length < WX_MATERIAL_NAME_MAX - 1 ? s.length : WX_MATERIAL_NAME_MAX - 1;
        memcpy(name, s.data, n);
        name[n] = '\0';
    } else {
        snprintf(name, WX_MATERIAL_NAME_MAX, "material%u", index);
    }
}

// Numbers the materials in use by distinct name, in the file's order.
static wx_result name_materials(import_state *st, const char *path, wx_error *err)
{
    const struct aiScene *scene = st->scene;
    wx_mesh_data *out = st->out;
    int used = 0;
    for (unsigned m = 0; m < scene->mNumMaterials; ++m) {
        used += st->material_slot[m] >= 0;
    }
    if (used > WX_MESH_MAX_MATERIALS) {
        return wx_error_set(err, WX_BAD_INPUT, "%s: uses more than %d materials", path,
                            WX_MESH_MAX_MATERIALS);
    }
    out->material_names = calloc(used > 0 ? (size_t)used : 1, sizeof *out->material_names);
    out->material_colored = calloc(used > 0 ? (size_t)used : 1, sizeof *out->material_colored);
    if (out->material_names == NULL || out->material_colored == NULL) {
        return wx_error_set(err, WX_FAIL, "%s: out of memory", path);
    }
    for (unsigned m = 0; m < scene->mNumMaterials; ++m) {
        if (st->material_slot[m] < 0) {
            continue;
        }
        char name[WX_MATERIAL_NAME_MAX];
        material_name(scene->mMaterials[m], m, name);
        int slot = 0;
        while (slot < out->material_count && strcmp(out->material_names[slot], name) != 0) {
            slot++;
        }
        if (slot == out->material_count) {
            memcpy(out->material_names[slot], name, sizeof name);
            out->material_colored[slot] = st->any_colors;
            out->material_count++;
        }
        st->material_slot[m] = slot;
    }
    return WX_OK;
}

static wx_result build_arrays(import_state *st, const char *path, wx_error *err)
{
    const struct aiScene *scene = st->scene;
    wx_mesh_data *out = st->out;
    st->material_slot = malloc((scene->mNumMaterials > 0 ? scene->mNumMaterials : 1) *
                               sizeof *st->material_slot);
    if (st->material_slot == NULL) {
        return wx_error_set(err, WX_FAIL, "%s: out of memory", path);
    }
    for (unsigned m = 0; m < scene->mNumMaterials; ++m) {
        st->material_slot[m] = -1;
    }
    for (int i = 0; i < 3; ++i) {
        out->bounds_min[i] = INFINITY;
        out->bounds_max[i] = -INFINITY;
    }
    affine identity = { { { 1, 0, 0, 0 }, { 0, 1, 0, 0 }, { 0, 0, 1, 0 } } };
    walk(st, scene->mRootNode, &identity, 0);
    if (st->problem != NULL) {
        return wx_error_set(err, WX_BAD_INPUT, "%s: the file holds %s", path, st->problem);
    }
    if (st->vertices > (int64_t)UINT32_MAX) {
        return wx_error_set(err, WX_BAD_INPUT, "%s: more than %u vertices", path, UINT32_MAX);
    }
    out->vertex_count = st->vertices;
    out->triangle_count = st->triangles;
    if (st->triangles == 0) {
        for (int i = 0; i < 3; ++i) {
            out->bounds_min[i] = out->bounds_max[i] = 0.0;
        }
        return WX_OK;
    }
    for (int i = 0; i < 3; ++i) {
        out->origin[i] = 0.5 * (out->bounds_min[i] + out->bounds_max[i]);
    }
    wx_result r = name_materials(st, path, err);
    if (r != WX_OK) {
        return r;
    }
    size_t nv = (size_t)st->vertices, nt = (size_t)st->triangles;
    out->positions = malloc(3 * nv * sizeof *out->positions);
    out->normals = malloc(3 * nv * sizeof *out->normals);
    out->indices = malloc(3 * nt * sizeof *out->indices);
    out->materials = malloc(nt * sizeof *out->materials);
    out->colors = st->any_colors ? malloc(4 * nv * sizeof *out->colors) : NULL;
    if (out->positions == NULL || out->normals == NULL || out->indices == NULL ||
        out->materials == NULL || (st->any_colors && out->colors == NULL)) {
        return wx_error_set(err, WX_FAIL, "%s: out of memory for %lld triangles", path,
                            (long long)nt);
    }
    st->fill = true;
    st->vertices = 0;
    st->triangles = 0;
    walk(st, scene->mRootNode, &identity, 0);
    return WX_OK;
}

wx_result wx_mesh_import(const char *path, wx_mesh_data *out, wx_error *err)
{
    memset(out, 0, sizeof *out);
    struct aiPropertyStore *props = aiCreatePropertyStore();
    if (props == NULL) {
        return wx_error_set(err, WX_FAIL, "%s: out of memory", path);
    }
    aiSetImportPropertyFloat(props, AI_CONFIG_PP_GSN_MAX_SMOOTHING_ANGLE,
                             WX_MESH_SMOOTHING_ANGLE_DEG);
    unsigned flags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                     aiProcess_GenSmoothNormals | aiProcess_ValidateDataStructure;
    const struct aiScene *scene = aiImportFileExWithProperties(path, flags, NULL, props);
    aiReleasePropertyStore(props);
    if (scene == NULL) {
        const char *why = aiGetErrorString();
        return wx_error_set(err, WX_BAD_INPUT, "%s: cannot import mesh: %s", path,
                            why != NULL && why[0] != '\0' ? why : "unknown reason");
    }
    import_state st = { .scene = scene, .out = out };
    wx_result r = build_arrays(&st, path, err);
    free(st.material_slot);
    aiReleaseImport(scene);
    if (r != WX_OK) {
        wx_mesh_data_free(out);
    }
    return r;
}

void wx_mesh_data_release_arrays(wx_mesh_data *mesh)
{
    free(mesh->positions);
    free(mesh->normals);
    free(mesh->colors);
    free(mesh->indices);
    free(mesh->materials);
    mesh->positions = mesh->normals = mesh->colors = NULL;
    mesh->indices = NULL;
    mesh->materials = NULL;
}

void wx_mesh_data_free(wx_mesh_data *mesh)
{
    wx_mesh_data_release_arrays(mesh);
    free(mesh->material_names);
    free(mesh->material_colored);
    memset(mesh, 0, sizeof *mesh);
}
