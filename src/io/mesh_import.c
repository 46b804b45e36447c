// mesh_import.c: Assimp import into flat arrays (see mesh.h).
//
// Assimp reads every file through mesh_io below, which hands it regular files
// only and, besides the mesh file, only files inside the mesh's folder. Two
// walks over the node tree: the first counts vertices and triangles, finds the
// materials in use and the world bounds; the second fills arrays allocated
// once. A mesh referenced by several nodes is instanced once per node.
// Each aiMesh's normals and shared vertices are computed by
// mesh_postprocess.c.
#define _XOPEN_SOURCE 700 // realpath
#include "io/mesh_import.h"

#include <assimp/cfileio.h>
#include <assimp/cimport.h>
#include <assimp/commonMetaData.h>
#include <assimp/material.h>
#include <assimp/metadata.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include "core/input_file.h"
#include "io/mesh_postprocess.h"

enum { MAX_NODE_DEPTH = 1024, PROBLEM_MAX = 256 };

// ---------------------------------------------------------------------------
// The file system Assimp reads through
//
// Assimp opens the mesh file and whatever it refers to (an OBJ's mtllib, a
// glTF's buffer URIs, ...) through these callbacks. Only regular files are
// opened, without blocking (wx_open_regular), and besides the mesh file itself
// only files that resolve (realpath) inside the mesh's folder. A refusal is
// recorded and fails the import even when Assimp carries on without the file.
// A name that is not there is no refusal: Assimp probes names (an OBJ without
// its .mtl, the fallback names of its FileSystemFilter) and does without them.

// One import's file system. `fio` comes first: Assimp's aiFileIO pointer is a
// pointer to this.
typedef struct mesh_io {
    struct aiFileIO fio;
    const char *mesh_path;   // the mesh file, as given to Assimp
    size_t folder_len;       // length of its folder prefix, '/' included (0: none)
    char *folder_real;       // realpath of that folder, NULL when it cannot be resolved
    int mesh_opens;          // times Assimp asked for the mesh file itself
    bool out_of_memory;      // an open failed for want of memory
    bool refused;            // a file was refused: the import fails with `refusal`
    wx_cause refusal_cause;  // WX_CAUSE_BAD_MESH, or what refused the mesh file itself
    char refusal[PROBLEM_MAX]; // what follows "mesh: " in the message
} mesh_io;

// One open file; `file` first, as above.
typedef struct mesh_file {
    struct aiFile file;
    FILE *stream;
    size_t size;
} mesh_file;

static FILE *stream_of(struct aiFile *f)
{
    return ((mesh_file *)(void *)f)->stream;
}

static size_t file_read(struct aiFile *f, char *buf, size_t size, size_t count)
{
    return size == 0 || count == 0 ? 0 : fread(buf, size, count, stream_of(f));
}

static size_t file_write(struct aiFile *f, const char *buf, size_t size, size_t count)
{
    (void)f;
    (void)buf;
    (void)size;
    (void)count;
    return 0; // opened for reading only
}

static size_t file_tell(struct aiFile *f)
{
    off_t at = ftello(stream_of(f));
    return at < 0 ? 0 : (size_t)at;
}

static size_t file_size(struct aiFile *f)
{
    return ((mesh_file *)(void *)f)->size;
}

static enum aiReturn file_seek(struct aiFile *f, size_t offset, enum aiOrigin origin)
{
    if (origin != aiOrigin_SET && origin != aiOrigin_CUR && origin != aiOrigin_END) {
        return aiReturn_FAILURE;
    }
    int whence = origin == aiOrigin_SET ? SEEK_SET : origin == aiOrigin_CUR ? SEEK_CUR : SEEK_END;
    // As Assimp's own DefaultIOStream: a step backwards arrives as a wrapped size_t.
    return fseeko(stream_of(f), (off_t)(int64_t)offset, whence) == 0 ? aiReturn_SUCCESS
                                                                     : aiReturn_FAILURE;
}

static void file_flush(struct aiFile *f)
{
    (void)f;
}

static void io_refuse(mesh_io *io, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

// Records a refusal; the first one is the one reported.
static void io_refuse(mesh_io *io, const char *fmt, ...)
{
    if (io->refused) {
        return;
    }
    io->refused = true;
    if (io->refusal_cause == WX_CAUSE_NONE) {
        io->refusal_cause = WX_CAUSE_BAD_MESH;
    }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(io->refusal, sizeof io->refusal, fmt, ap);
    va_end(ap);
    for (char *c = io->refusal; *c != '\0'; ++c) {
        *c = (unsigned char)*c < 0x20 || *c == 0x7f ? '?' : *c; // a name from the file: one line
    }
}

static void refuse_reason(mesh_io *io, const char *shown, const char *why)
{
    if (strncmp(why, "is ", 3) == 0) {
        // "refers to 'x.mtl', which is not a regular file (a FIFO)"
        io_refuse(io, "refers to '%.160s', which %s", shown, why);
    } else {
        io_refuse(io, "refers to '%.160s': %s", shown, why);
    }
}

static bool is_inside(const char *real, const char *folder)
{
    size_t n = strlen(folder);
    if (n == 1 && folder[0] == '/') {
        return true;
    }
    return strncmp(real, folder, n) == 0 && (real[n] == '/' || real[n] == '\0');
}

// Opens a file other than the mesh: a regular file inside the mesh's folder, or -1.
static int open_referenced(mesh_io *io, const char *name)
{
    // Assimp names referenced files as the mesh's folder followed by the
    // reference: shown to the user without that folder, as the file has it.
    size_t n = io->folder_len;
    const char *shown = strncmp(name, io->mesh_path, n) == 0 ? name + n : name;
    char why[WX_INPUT_WHY_MAX];
    wx_cause cause = WX_CAUSE_NONE;
    char *real = realpath(name, NULL);
    if (real == NULL) {
        int e = errno;
        if (e == ENOMEM) {
            io->out_of_memory = true;
            return -1;
        }
        if (e == ENOENT || e == ENOTDIR) {
            return -1; // not there: a probe
        }
        int fd = wx_open_regular(name, why, &cause); // for the reason: a loop, a permission
        if (fd >= 0) {
            close(fd);
            snprintf(why, sizeof why, "cannot be resolved (%s)", strerror(e));
        } else if (cause == WX_CAUSE_FILE_MISSING) {
            return -1;
        }
        refuse_reason(io, shown, why);
        return -1;
    }
    if (io->folder_real == NULL || !is_inside(real, io->folder_real)) {
        free(real);
        io_refuse(io, "refers to '%.160s', outside the mesh's folder", shown);
        return -1;
    }
    int fd = wx_open_regular(real, why, &cause);
    free(real);
    if (fd < 0 && cause != WX_CAUSE_FILE_MISSING) {
        refuse_reason(io, shown, why);
    }
    return fd;
}

static struct aiFile *io_open(struct aiFileIO *fio, const char *name, const char *mode)
{
    mesh_io *io = (mesh_io *)(void *)fio;
    if (name == NULL || mode == NULL || strpbrk(mode, "wa+") != NULL) {
        return NULL; // reading only
    }
    int fd;
    if (strcmp(name, io->mesh_path) == 0) {
        io->mesh_opens++;
        char why[WX_INPUT_WHY_MAX];
        wx_cause cause = WX_CAUSE_NONE;
        fd = wx_open_regular(name, why, &cause);
        if (fd < 0) {
            io->refusal_cause = cause;
            io_refuse(io, "%s", cause == WX_CAUSE_FILE_MISSING ? "not found" : why);
            return NULL;
        }
    } else if ((fd = open_referenced(io, name)) < 0) {
        return NULL;
    }
    mesh_file *mf = malloc(sizeof *mf);
    FILE *stream = mf != NULL ? fdopen(fd, "rb") : NULL;
    if (stream == NULL) {
        io->out_of_memory = true;
        free(mf);
        close(fd);
        return NULL;
    }
    struct stat st;
    *mf = (mesh_file){
        .file = { .ReadProc = file_read, .WriteProc = file_write, .TellProc = file_tell,
                  .FileSizeProc = file_size, .SeekProc = file_seek, .FlushProc = file_flush },
        .stream = stream,
        .size = fstat(fd, &st) == 0 ? (size_t)st.st_size : 0,
    };
    return &mf->file;
}

static void io_close(struct aiFileIO *fio, struct aiFile *f)
{
    (void)fio;
    if (f != NULL) {
        fclose(stream_of(f));
        free(f);
    }
}

// Prepares the file system for importing `path`. False when out of memory.
static bool io_init(mesh_io *io, const char *path)
{
    memset(io, 0, sizeof *io);
    io->fio.OpenProc = io_open;
    io->fio.CloseProc = io_close;
    io->mesh_path = path;
    const char *slash = strrchr(path, '/');
    io->folder_len = slash != NULL ? (size_t)(slash - path) + 1 : 0;
    size_t len = slash == NULL || slash == path ? 1 : (size_t)(slash - path);
    char *folder = malloc(len + 1);
    if (folder == NULL) {
        return false;
    }
    memcpy(folder, slash == NULL ? "." : path, len);
    folder[len] = '\0';
    io->folder_real = realpath(folder, NULL); // NULL: the mesh is not there either
    int e = errno;
    free(folder);
    return io->folder_real != NULL || e != ENOMEM;
}

static void io_free(mesh_io *io)
{
    free(io->folder_real);
    io->folder_real = NULL;
}

// The message for an import that gave no scene, or during which the file
// system refused a file or ran out of memory.
static wx_result import_failure(const mesh_io *io, const char *path, wx_error *err)
{
    if (io->refused) {
        return wx_fail(err, io->refusal_cause, "%s: %s", path, io->refusal);
    }
    if (io->out_of_memory) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY,
                       "%s: out of memory while opening the files of the mesh", path);
    }
    if (io->mesh_opens == 0) {
        // Assimp gave up before looking for the file: only an allocation fails
        // there (new Importer), and aiGetErrorString then still holds the
        // message of an earlier import.
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY,
                       "%s: out of memory (Assimp could not start the import)", path);
    }
    const char *why = aiGetErrorString();
    why = why != NULL && why[0] != '\0' ? why : "unknown reason";
    // Assimp 5.2.5 catches std::bad_alloc in an importer or a post-processing
    // step and reports what() ("std::bad_alloc"); anywhere else in
    // Importer::ReadFile (built without ASSIMP_CATCH_GLOBAL_EXCEPTIONS) it
    // reports "Unknown exception", which only a C++ exception such as
    // bad_alloc gives: parse errors arrive as DeadlyImportError with a message.
    if (strstr(why, "bad_alloc") != NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY,
                       "%s: out of memory while importing the mesh (Assimp: %s)", path, why);
    }
    if (strcmp(why, "Unknown exception") == 0) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY,
                       "%s: out of memory, or another failure inside Assimp, while "
                       "importing the mesh (Assimp: %s)",
                       path, why);
    }
    return wx_fail(err, WX_CAUSE_BAD_MESH, "%s: cannot import mesh: %s", path, why);
}

// ---------------------------------------------------------------------------
// From the aiScene to the arrays

typedef struct import_state {
    const struct aiScene *scene;
    wx_mesh_data *out;
    double unit_m;        // length of the file's unit in metres
    int *material_slot;   // per aiMaterial: index into out->material_names, -1 when unused
    int64_t vertices;     // running counts
    int64_t triangles;
    bool any_colors;
    wx_mesh_prep *prep;   // per aiMesh: its corners joined into vertices (normals and joining)
    bool too_many;        // an aiMesh with more corners than 32-bit indices hold
    bool out_of_memory;   // preparing an aiMesh ran out of memory
    unsigned uv_channels; // bit c: import UV channel c (refused where a mesh lacks it)
    unsigned uv_present;  // bit c: some triangle mesh had channel c
    bool missing_uvs;     // the problem is a missing UV channel
    bool fill;            // false: count and bound; true: fill the arrays
    char problem[PROBLEM_MAX]; // set when the file holds something we refuse
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

static bool finite3(double x, double y, double z)
{
    return isfinite(x) && isfinite(y) && isfinite(z);
}

static void count_mesh(import_state *st, unsigned index, const affine *xf)
{
    const struct aiMesh *mesh = st->scene->mMeshes[index];
    int64_t tris = 0;
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
        tris += wx_mesh_is_triangle(&mesh->mFaces[f], mesh->mNumVertices);
    }
    if (tris == 0) {
        return; // points and lines only: nothing to render
    }
    st->material_slot[mesh->mMaterialIndex] = 0; // in use; numbered later
    st->any_colors = st->any_colors || mesh->mColors[0] != NULL;
    for (unsigned c = 0; c < WX_MESH_MAX_UV_CHANNELS; ++c) {
        if (mesh->mTextureCoords[c] != NULL) {
            st->uv_present |= 1u << c;
        } else if (st->uv_channels & (1u << c)) {
            snprintf(st->problem, sizeof st->problem,
                     "part '%.64s' of the mesh has no texture coordinates in UV channel %u",
                     mesh->mName.length > 0 ? mesh->mName.data : "(unnamed)", c);
            st->missing_uvs = true;
            return;
        }
    }
    wx_mesh_data *out = st->out;
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
        const struct aiVector3D *local = &mesh->mVertices[v];
        const struct aiColor4D *c = mesh->mColors[0] != NULL ? &mesh->mColors[0][v] : NULL;
        if (c != NULL && !(finite3(c->r, c->g, c->b) && isfinite(c->a))) {
            snprintf(st->problem, sizeof st->problem,
                     "the vertex at (%g, %g, %g) has a colour that is not a finite number "
                     "(%g, %g, %g, %g)",
                     local->x, local->y, local->z, c->r, c->g, c->b, c->a);
            return;
        }
        for (unsigned u = 0; u < WX_MESH_MAX_UV_CHANNELS; ++u) {
            const struct aiVector3D *t = (st->uv_channels & (1u << u)) ? mesh->mTextureCoords[u]
                                                                      : NULL;
            if (t != NULL && !(isfinite(t[v].x) && isfinite(t[v].y))) {
                snprintf(st->problem, sizeof st->problem,
                         "the vertex at (%g, %g, %g) has texture coordinates that are not finite "
                         "numbers (%g, %g)",
                         local->x, local->y, local->z, t[v].x, t[v].y);
                return;
            }
        }
        // Normals come from the file only (the import generates none).
        const struct aiVector3D *n = mesh->mNormals != NULL ? &mesh->mNormals[v] : NULL;
        if (n != NULL && !finite3(n->x, n->y, n->z)) {
            snprintf(st->problem, sizeof st->problem,
                     "the vertex at (%g, %g, %g) has a normal that is not a finite number "
                     "(%g, %g, %g)",
                     local->x, local->y, local->z, n->x, n->y, n->z);
            return;
        }
        double p[3];
        transform_point(xf, local, p);
        for (int i = 0; i < 3; ++i) {
            if (!isfinite(p[i])) {
                snprintf(st->problem, sizeof st->problem,
                         "the file holds a vertex position that is not a finite number");
                return;
            }
            out->bounds_min[i] = p[i] < out->bounds_min[i] ? p[i] : out->bounds_min[i];
            out->bounds_max[i] = p[i] > out->bounds_max[i] ? p[i] : out->bounds_max[i];
        }
    }
    wx_mesh_prep *prep = &st->prep[index];
    if (!prep->done && !wx_mesh_prepare(mesh, st->uv_channels, prep, &st->too_many)) {
        st->out_of_memory = true;
        return;
    }
    st->triangles += prep->triangles;
    st->vertices += prep->vertices;
}

static void fill_mesh(import_state *st, unsigned index, const affine *xf)
{
    const struct aiMesh *mesh = st->scene->mMeshes[index];
    const wx_mesh_prep *prep = &st->prep[index];
    wx_mesh_data *out = st->out;
    if (prep->triangles == 0) {
        return;
    }
    for (uint32_t t = 0; t < prep->triangles; ++t) {
        uint32_t *idx = &out->indices[3 * st->triangles];
        for (int k = 0; k < 3; ++k) {
            idx[k] = (uint32_t)(st->vertices + prep->corner[3 * (size_t)t + (size_t)k]);
        }
        out->materials[st->triangles] = (uint16_t)st->material_slot[mesh->mMaterialIndex];
        st->triangles++;
    }
    double nm[3][3];
    normal_matrix(xf, nm);
    int slot = st->material_slot[mesh->mMaterialIndex];
    if (mesh->mColors[0] == NULL) {
        out->material_colored[slot] = false;
    }
    for (uint32_t j = 0; j < prep->vertices; ++j) {
        int64_t o = st->vertices + j;
        unsigned v = prep->source[j];
        double p[3];
        transform_point(xf, &mesh->mVertices[v], p);
        for (int i = 0; i < 3; ++i) {
            out->positions[3 * o + i] = (float)(p[i] - out->origin[i]);
        }
        const float *s = &prep->normal[3 * (size_t)j];
        double n[3];
        for (int i = 0; i < 3; ++i) {
            n[i] = nm[i][0] * s[0] + nm[i][1] * s[1] + nm[i][2] * s[2];
        }
        double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int i = 0; i < 3; ++i) {
            out->normals[3 * o + i] = len > 0.0 && isfinite(len) ? (float)(n[i] / len) : 0.0f;
        }
        for (int c = 0; c < WX_MESH_MAX_UV_CHANNELS; ++c) {
            if (out->uvs[c] != NULL) {
                out->uvs[c][2 * o] = mesh->mTextureCoords[c][v].x;
                out->uvs[c][2 * o + 1] = mesh->mTextureCoords[c][v].y;
            }
        }
        if (out->colors != NULL) {
            float *c = &out->colors[4 * o];
            if (mesh->mColors[0] != NULL) {
                const struct aiColor4D *col = &mesh->mColors[0][v];
                c[0] = col->r;
                c[1] = col->g;
                c[2] = col->b;
                c[3] = col->a;
            } else {
                c[0] = c[1] = c[2] = 0.0f;
                c[3] = 1.0f;
            }
        }
    }
    st->vertices += prep->vertices;
}

static void walk(import_state *st, const struct aiNode *node, const affine *parent, int depth)
{
    if (node == NULL || st->problem[0] != '\0' || st->out_of_memory || st->too_many) {
        return;
    }
    if (depth > MAX_NODE_DEPTH) {
        snprintf(st->problem, sizeof st->problem,
                 "the file holds a node hierarchy deeper than %d levels", MAX_NODE_DEPTH);
        return;
    }
    affine local = affine_from_ai(&node->mTransformation);
    affine xf = affine_mul(parent, &local);
    for (unsigned i = 0; i < node->mNumMeshes && st->problem[0] == '\0' && !st->out_of_memory &&
                         !st->too_many;
         ++i) {
        unsigned index = node->mMeshes[i];
        if (index >= st->scene->mNumMeshes) {
            continue;
        }
        const struct aiMesh *mesh = st->scene->mMeshes[index];
        if (mesh->mMaterialIndex >= st->scene->mNumMaterials) {
            snprintf(st->problem, sizeof st->problem,
                     "the file holds a mesh whose material index is out of range");
            return;
        }
        if (st->fill) {
            fill_mesh(st, index, &xf);
        } else {
            count_mesh(st, index, &xf);
        }
    }
    for (unsigned i = 0; i < node->mNumChildren && st->problem[0] == '\0'; ++i) {
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
        return wx_fail(err, WX_CAUSE_TOO_MANY, "%s: uses more than %d materials", path,
                            WX_MESH_MAX_MATERIALS);
    }
    out->material_names = calloc(used > 0 ? (size_t)used : 1, sizeof *out->material_names);
    out->material_colored = calloc(used > 0 ? (size_t)used : 1, sizeof *out->material_colored);
    if (out->material_names == NULL || out->material_colored == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", path);
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

// The length of the file's unit in metres. Only FBX states one that Assimp
// 5.2.5 leaves to us: its global setting UnitScaleFactor, in centimetres per
// file unit, arrives as scene metadata (Blender writes 1: its FBX files are in
// centimetres, with the objects scaled by 100). Assimp would apply it only with
// aiProcess_GlobalScale, which rebuilds every node transform from a float
// decomposition; AI_CONFIG_FBX_CONVERT_TO_M is read and ignored. Collada's
// <unit> and 3DS's master scale are applied by Assimp itself, glTF is in metres
// by definition, OBJ, PLY and STL carry no unit: all of those give 1.
static wx_result file_unit_m(const struct aiScene *scene, const char *path, double *unit_m,
                             wx_error *err)
{
    *unit_m = 1.0;
    const struct aiMetadata *md = scene->mMetaData;
    bool fbx = false, stated = false;
    double cm = 0.0;
    for (unsigned i = 0; md != NULL && i < md->mNumProperties; ++i) {
        const char *key = md->mKeys[i].data;
        const struct aiMetadataEntry *e = &md->mValues[i];
        if (e->mData == NULL) {
            continue;
        }
        if (strcmp(key, AI_METADATA_SOURCE_FORMAT) == 0 && e->mType == AI_AISTRING) {
            fbx = strstr(((const struct aiString *)e->mData)->data, "FBX") != NULL;
        } else if (strcmp(key, "UnitScaleFactor") == 0 && e->mType == AI_FLOAT) {
            stated = true;
            cm = *(const float *)e->mData;
        } else if (strcmp(key, "UnitScaleFactor") == 0 && e->mType == AI_DOUBLE) {
            stated = true;
            cm = *(const double *)e->mData;
        }
    }
    if (!fbx || !stated) {
        return WX_OK;
    }
    if (!(isfinite(cm) && cm > 0.0)) {
        return wx_fail(err, WX_CAUSE_BAD_MESH,
                       "%s: the FBX unit (UnitScaleFactor %g centimetres) is not a positive "
                       "number",
                       path, cm);
    }
    *unit_m = cm / 100.0;
    return WX_OK;
}

static wx_result build_arrays(import_state *st, const char *path, wx_error *err)
{
    const struct aiScene *scene = st->scene;
    wx_mesh_data *out = st->out;
    st->material_slot = malloc((scene->mNumMaterials > 0 ? scene->mNumMaterials : 1) *
                               sizeof *st->material_slot);
    st->prep = calloc(scene->mNumMeshes > 0 ? scene->mNumMeshes : 1, sizeof *st->prep);
    if (st->material_slot == NULL || st->prep == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    for (unsigned m = 0; m < scene->mNumMaterials; ++m) {
        st->material_slot[m] = -1;
    }
    for (int i = 0; i < 3; ++i) {
        out->bounds_min[i] = INFINITY;
        out->bounds_max[i] = -INFINITY;
    }
    // The file's unit, applied above the root node: positions come out in metres.
    double u = st->unit_m;
    affine root = { { { u, 0, 0, 0 }, { 0, u, 0, 0 }, { 0, 0, u, 0 } } };
    walk(st, scene->mRootNode, &root, 0);
    if (st->problem[0] != '\0') {
        return wx_fail(err, st->missing_uvs ? WX_CAUSE_NO_UVS : WX_CAUSE_BAD_MESH, "%s: %s", path,
                       st->problem);
    }
    if (st->out_of_memory) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory (joining vertices)", path);
    }
    if (st->too_many) {
        return wx_fail(err, WX_CAUSE_TOO_MANY, "%s: a part of the mesh has more than %d triangles",
                       path, INT32_MAX / 3);
    }
    if (st->vertices > (int64_t)UINT32_MAX) {
        return wx_fail(err, WX_CAUSE_TOO_MANY, "%s: more than %u vertices", path, UINT32_MAX);
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
    bool uvs_ok = true;
    for (int c = 0; c < WX_MESH_MAX_UV_CHANNELS; ++c) {
        if (st->uv_channels & (1u << c)) {
            out->uvs[c] = malloc(2 * nv * sizeof *out->uvs[c]);
            uvs_ok = uvs_ok && out->uvs[c] != NULL;
        }
    }
    if (out->positions == NULL || out->normals == NULL || out->indices == NULL ||
        out->materials == NULL || (st->any_colors && out->colors == NULL) || !uvs_ok) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory for %lld triangles", path,
                            (long long)nt);
    }
    st->fill = true;
    st->vertices = 0;
    st->triangles = 0;
    walk(st, scene->mRootNode, &root, 0);
    return WX_OK;
}

wx_result wx_mesh_import(const char *path, wx_mesh_data *out, wx_error *err)
{
    return wx_mesh_import_uvs(path, 0u, out, err);
}

// The faces of the scene: the largest, in vertices, and whether Assimp's
// triangulation of its polygons would take time linear in the file: the sum
// of the squares of the polygons' vertices within WX_MESH_POLYGON_WORK per
// vertex of a face, plus WX_MESH_POLYGON_FREE.
static bool polygons_fit(const struct aiScene *scene, unsigned *largest)
{
    double work = 0.0, vertices = 0.0;
    *largest = 0;
    for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
        const struct aiMesh *mesh = scene->mMeshes[m];
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            double n = mesh->mFaces[f].mNumIndices;
            vertices += n;
            work += n > 3.0 ? n * n : 0.0;
            *largest = mesh->mFaces[f].mNumIndices > *largest ? mesh->mFaces[f].mNumIndices
                                                              : *largest;
        }
    }
    return work <= WX_MESH_POLYGON_WORK * vertices + WX_MESH_POLYGON_FREE;
}

// Assimp reads the file; `triangulate` adds its triangulation (ear cutting).
static const struct aiScene *read_scene(const char *path, bool triangulate, mesh_io *io)
{
    unsigned flags = aiProcess_ValidateDataStructure | (triangulate ? aiProcess_Triangulate : 0u);
    return aiImportFileEx(path, flags, &io->fio);
}

wx_result wx_mesh_import_uvs(const char *path, unsigned uv_channels, wx_mesh_data *out,
                             wx_error *err)
{
    memset(out, 0, sizeof *out);
    mesh_io io;
    if (!io_init(&io, path)) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    // The file as it is: triangles are used as they come. Polygons are
    // triangulated by a second reading with Assimp's triangulation, whose time
    // grows with the square of a face's vertices: polygons too large for that
    // to stay linear in the file are refused instead (a 32400-vertex polygon
    // took 40 s). Assimp's normals and joining are not used (see above).
    const struct aiScene *scene = read_scene(path, false, &io);
    wx_result r = WX_OK;
    if (scene == NULL || io.refused || io.out_of_memory) {
        r = import_failure(&io, path, err);
    } else {
        unsigned largest = 0;
        if (!polygons_fit(scene, &largest)) {
            r = wx_fail(err, WX_CAUSE_TOO_MANY,
                        "%s: its polygons are too large to triangulate (the largest has %u "
                        "vertices; triangulating a face takes time growing with the square of "
                        "its vertices); triangulate the mesh in the program that made it",
                        path, largest);
        } else if (largest > 3) {
            aiReleaseImport(scene);
            io_free(&io);
            if (!io_init(&io, path)) {
                return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", path);
            }
            scene = read_scene(path, true, &io);
            if (scene == NULL || io.refused || io.out_of_memory) {
                r = import_failure(&io, path, err);
            }
        }
    }
    import_state st = { .scene = scene, .out = out, .uv_channels = uv_channels };
    if (r == WX_OK && (r = file_unit_m(scene, path, &st.unit_m, err)) == WX_OK) {
        r = build_arrays(&st, path, err);
    }
    // Assimp's scene is released first: the orientation's work arrays (about
    // 84 bytes a triangle) come after it, within the 300-400 bytes a triangle
    // pipeline/memory.c counts for the import.
    for (unsigned m = 0; st.prep != NULL && m < scene->mNumMeshes; ++m) {
        wx_mesh_prep_free(&st.prep[m]);
    }
    free(st.prep);
    st.prep = NULL;
    aiReleaseImport(scene);
    scene = NULL;
    if (r == WX_OK) {
        r = wx_mesh_orient_outwards(out, &out->parts_turned, err);
    }
    if (r == WX_OK) {
        r = wx_mesh_find_creases(out, err); // after the turn: it compares normals
    }
    free(st.material_slot);
    io_free(&io);
    if (r != WX_OK) {
        wx_mesh_data_free(out);
    }
    return r;
}
