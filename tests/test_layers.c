// test_layers.c: the layers of src/ stay layers (docs/architecture.md). Each
// folder may include its own headers and those of the layers below it:
//
//   core <- model <- io, raster, sim, gather <- pipeline <- cli, viewer
//
// and the compute layers (raster, sim, gather) never open a file themselves:
// they take and return memory, the pipeline reads and writes. Each third-party
// library is included by the few files of one concept only: libxml2 by the scene
// loader (scene_xml.c and its table engine's header, which the element groups
// include), Assimp by the mesh importer, OpenEXR by the EXR files of io/, OSMesa
// and GL by the bake's GL side, libpng by io/png_preview.c, MPI by core/dist.c
// (the ranks of `make mpi`'s program; docs/scale-out.md). A folder's private
// header (NAME_internal.h) is included by the files of that folder only.
#include <dirent.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ensure.h"

typedef struct layer {
    const char *name;
    const char *may_include; ///< space-separated layers below it (itself included)
} layer;

static const layer layers[] = {
    { "core", "core" },
    { "model", "core model" },
    { "io", "core model io" },
    { "raster", "core model raster" },
    { "sim", "core model sim" },
    { "gather", "core model gather" },
    { "pipeline", "core model io raster sim gather pipeline" },
};
enum { LAYER_COUNT = sizeof layers / sizeof layers[0] };

// Calls that open, read or write files: none of them in a compute layer.
static const char *const file_calls[] = { "fopen(", "open(",        "opendir(",
                                          "wx_exr_", "wx_maps_load", "wx_mesh_import",
                                          "wx_write_file_atomic", "xmlRead", "unlink(",
                                          "rename(", "mkdir(" };

static char *source_text(const char *path)
{
    char *text = ensure_read_file(path);
    if (text == NULL) {
        fprintf(stderr, "        cannot read %s\n", path);
    }
    return text;
}

// A check of one source file: `rel` its path as messages show it
// ("sim/step.c", "cli/main.c"), `name` its file name, `ctx` the check's own
// data. Returns the number of violations (printed).
typedef int (*source_check)(const char *rel, const char *name, const char *text, const void *ctx);

// Runs `check` on every .c and .h file directly in `dir`, shown as
// `shown`/NAME, and counts them in *files. A folder or a file that cannot be
// read is a violation. Returns the number of violations.
static int check_folder(const char *dir, const char *shown, source_check check, const void *ctx,
                        int *files)
{
    DIR *d = opendir(dir);
    if (d == NULL) {
        fprintf(stderr, "        cannot open %s\n", dir);
        return 1;
    }
    int bad = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        size_t n = strlen(e->d_name);
        if (n < 3 || e->d_name[n - 2] != '.' ||
            (e->d_name[n - 1] != 'c' && e->d_name[n - 1] != 'h')) {
            continue;
        }
        char path[4500], rel[300];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        snprintf(rel, sizeof rel, "%s/%s", shown, e->d_name);
        char *text = source_text(path);
        if (text == NULL) {
            bad++;
            continue;
        }
        bad += check(rel, e->d_name, text, ctx);
        free(text);
        ++*files;
    }
    closedir(d);
    return bad;
}

// True when the first `len` characters of `name` are one of the words of `list`.
static bool listed(const char *list, const char *name, size_t len)
{
    for (const char *word = list; *word != '\0';) {
        size_t n = strcspn(word, " ");
        if (n == len && strncmp(word, name, len) == 0) {
            return true;
        }
        word += n;
        word += *word == ' ';
    }
    return false;
}

// Every `#include "X/..."` of one file names an allowed layer X; returns the
// number of violations (printed).
static int check_includes(const char *path, const char *text, const layer *own)
{
    int bad = 0;
    for (const char *p = text; (p = strstr(p, "#include \"")) != NULL; p += 10) {
        const char *name = p + 10;
        const char *slash = strchr(name, '/');
        const char *quote = strchr(name, '"');
        if (slash == NULL || quote == NULL || slash > quote) {
            continue; // a header of the same folder by plain name, or a generated one
        }
        size_t len = (size_t)(slash - name);
        if (!listed(own->may_include, name, len)) {
            fprintf(stderr, "        %s includes \"%.*s\": %s may include only %s\n", path,
                    (int)(quote - name), name, own->name, own->may_include);
            bad++;
        }
    }
    return bad;
}

static bool is_compute(const layer *l)
{
    return strcmp(l->name, "raster") == 0 || strcmp(l->name, "sim") == 0 ||
           strcmp(l->name, "gather") == 0;
}

// A compute layer calls nothing that touches a file.
static int check_no_file_io(const char *path, const char *text)
{
    int bad = 0;
    for (size_t k = 0; k < sizeof file_calls / sizeof file_calls[0]; ++k) {
        for (const char *p = text; (p = strstr(p, file_calls[k])) != NULL; ++p) {
            bool word = p == text || !(p[-1] == '_' || (p[-1] >= 'a' && p[-1] <= 'z'));
            if (word) {
                fprintf(stderr, "        %s (a compute layer) calls %s\n", path, file_calls[k]);
                bad++;
                break;
            }
        }
    }
    return bad;
}

// Third-party headers that belong to a few files each: `owners` lists them,
// space-separated (a library whose code is split by concept lives in several
// files of one folder); any other file that names the header is a violation.
static int check_library(const char *rel, const char *text, const char *header, const char *owners)
{
    if (strstr(text, header) != NULL && !listed(owners, rel, strlen(rel))) {
        fprintf(stderr, "        %s includes %s, which only %s may\n", rel, header, owners);
        return 1;
    }
    return 0;
}

// ---------------------------------------------------------------------------
// The scene reader's files (io/scene_xml*.c, issue 27): libxml2 only in the
// one that reads the document and in the table engine's header.
static const char *const libxml_owners = "io/scene_xml.c io/scene_xml_table.h";

// MPI (issue 29): one file, whose functions the normal build compiles as one
// rank of one, so that nothing else depends on which build it is.
static const char *const mpi_owner = "core/dist.c";

// The command line (cli/, issue 27) stands on the pipeline: it may include
// core, model and pipeline headers, and of io only the scene loader and the
// statistics writer; the maps, meshes and EXR files it reaches through the
// pipeline, never sim, raster or gather.
static const char *const cli_layers = "core model pipeline";
static const char *const cli_io_headers = "io/scene_xml.h io/stats_json.h";

// Every `#include "X/..."` of a cli file names a layer of cli_layers or a
// header of cli_io_headers; returns the number of violations (printed).
static int check_cli_includes(const char *path, const char *text)
{
    int bad = 0;
    for (const char *p = text; (p = strstr(p, "#include \"")) != NULL; p += 10) {
        const char *name = p + 10;
        const char *slash = strchr(name, '/');
        const char *quote = strchr(name, '"');
        if (slash == NULL || quote == NULL || slash > quote) {
            continue; // cli.h, by plain name
        }
        if (!listed(cli_layers, name, (size_t)(slash - name)) &&
            !listed(cli_io_headers, name, (size_t)(quote - name))) {
            fprintf(stderr, "        %s includes \"%.*s\": cli may include only %s and %s\n", path,
                    (int)(quote - name), name, cli_layers, cli_io_headers);
            bad++;
        }
    }
    return bad;
}

static int check_cli_file(const char *rel, const char *name, const char *text, const void *ctx)
{
    (void)name;
    (void)ctx;
    return check_cli_includes(rel, text) + check_library(rel, text, "<libxml/", libxml_owners) +
           check_library(rel, text, "<openexr.h>", "io/exr.c") +
           check_library(rel, text, "<mpi.h>", mpi_owner);
}

TEST(the_command_line_stands_on_the_pipeline)
{
    char folder[4200];
    snprintf(folder, sizeof folder, "%s/../cli", ensure_tests_dir());
    int files = 0;
    int bad = check_folder(folder, "cli", check_cli_file, NULL, &files);
    fprintf(stderr, "        %d files in cli/\n", files);
    ENSURE(files > 0);
    ENSURE(bad == 0);
    // The check finds what it is meant to find.
    ENSURE(check_cli_includes("cli/x.c", "#include \"sim/emitter.h\"\n") == 1);
    ENSURE(check_cli_includes("cli/x.c", "#include \"io/exr.h\"\n") == 1);
    ENSURE(check_cli_includes("cli/x.c", "#include \"io/scene_xml.h\"\n#include \"cli.h\"\n") == 0);
}
// ---------------------------------------------------------------------------

// The rules of one layer's file (`ctx` the layer).
static int check_layer_file(const char *rel, const char *name, const char *text, const void *ctx)
{
    (void)name;
    const layer *own = ctx;
    int bad = check_includes(rel, text, own);
    if (is_compute(own)) {
        bad += check_no_file_io(rel, text);
    }
    bad += check_library(rel, text, "<libxml/", libxml_owners);
    bad += check_library(rel, text, "<assimp/", "io/mesh_import.c io/mesh_postprocess.c");
    bad += check_library(rel, text, "<openexr.h>", "io/exr.c io/exr_write.c io/exr_internal.h");
    bad += check_library(rel, text, "<GL/", "raster/baker_internal.h");
    bad += check_library(rel, text, "<png.h>", "io/png_preview.c");
    bad += check_library(rel, text, "<mpi.h>", mpi_owner);
    return bad;
}

TEST(every_layer_includes_only_the_layers_below_it)
{
    int files = 0, bad = 0;
    for (int l = 0; l < LAYER_COUNT; ++l) {
        char folder[4200];
        snprintf(folder, sizeof folder, "%s/../src/%s", ensure_tests_dir(), layers[l].name);
        bad += check_folder(folder, layers[l].name, check_layer_file, &layers[l], &files);
    }
    fprintf(stderr, "        %d files in %d layers\n", files, LAYER_COUNT);
    ENSURE(files > 40);
    ENSURE(bad == 0);
}

// The check finds what it is meant to find (a model file including the sim).
TEST(a_wrong_include_is_caught)
{
    const char *text = "#include \"core/error.h\"\n#include \"sim/particles.h\"\n";
    ENSURE(check_includes("model/x.c", text, &layers[1]) == 1);
    ENSURE(check_includes("pipeline/x.c", text, &layers[6]) == 0);
    ENSURE(check_no_file_io("sim/x.c", "f = fopen(path, \"rb\");") == 1);
    ENSURE(check_no_file_io("sim/x.c", "wx_pool_open(x);") == 0);
    // A library's owners are whole file names of a list, nothing else.
    const char *gl = "#include <GL/gl.h>\n";
    ENSURE(check_library("raster/bake_gl.h", gl, "<GL/", "raster/bake.c raster/bake_gl.c") == 1);
    ENSURE(check_library("raster/bake_gl.c", gl, "<GL/", "raster/bake.c raster/bake_gl.c") == 0);
    ENSURE(check_library("raster/bake.c", gl, "<GL/", "raster/bake.c raster/bake_gl.c") == 0);
    ENSURE(check_library("raster/bake.cc", gl, "<GL/", "raster/bake.c raster/bake_gl.c") == 1);
    ENSURE(check_library("sim/bake.c", gl, "<GL/", "raster/bake.c") == 1);
    const char *mpi = "#include <mpi.h>\n";
    ENSURE(check_library("sim/exchange.c", mpi, "<mpi.h>", mpi_owner) == 1);
    ENSURE(check_library("core/dist.c", mpi, "<mpi.h>", mpi_owner) == 0);
}

// --- private headers ------------------------------------------------------------
// A folder's NAME_internal.h is shared by the files of that folder only, and is
// included by its folder-qualified name ("sim/solver_internal.h"); the
// programs' folders, cli/ and viewer/ (`folder` "cli" or "viewer"), name their
// own by the bare name ("world_internal.h"). A file of another layer or folder,
// or of tests/ (`folder` NULL), that includes one is a violation. Returns the
// number of violations (printed).
static int check_private_headers(const char *rel, const char *folder, const char *text)
{
    static const char suffix[] = "_internal.h";
    const size_t suffix_len = sizeof suffix - 1;
    int bad = 0;
    for (const char *p = text; (p = strstr(p, "#include \"")) != NULL; p += 10) {
        const char *name = p + 10;
        const char *quote = strchr(name, '"');
        const char *newline = strchr(name, '\n');
        if (quote == NULL || (newline != NULL && newline < quote)) {
            continue;
        }
        size_t len = (size_t)(quote - name);
        if (len < suffix_len || strncmp(quote - suffix_len, suffix, suffix_len) != 0) {
            continue;
        }
        const char *slash = memchr(name, '/', len);
        size_t folder_len = slash != NULL ? (size_t)(slash - name) : 0;
        bool program = folder != NULL && (strcmp(folder, "cli") == 0 || strcmp(folder, "viewer") == 0);
        bool own = folder != NULL &&
                   (program ? slash == NULL
                            : slash != NULL && folder_len == strlen(folder) &&
                                  strncmp(name, folder, folder_len) == 0 &&
                                  memchr(slash + 1, '/', (size_t)(quote - slash - 1)) == NULL);
        if (!own) {
            fprintf(stderr, "        %s includes \"%.*s\": a private header of %s\n", rel, (int)len,
                    name, slash != NULL ? "another folder" : "no named folder");
            bad++;
        }
    }
    return bad;
}

// The private-header rule for a file whose own folder is `ctx` (a string; NULL:
// outside src/, cli/ and viewer/).
static int check_private_file(const char *rel, const char *name, const char *text, const void *ctx)
{
    (void)name;
    return check_private_headers(rel, ctx, text);
}

TEST(private_headers_stay_in_their_folder)
{
    int files = 0, bad = 0;
    char dir[4200];
    for (int l = 0; l < LAYER_COUNT; ++l) {
        snprintf(dir, sizeof dir, "%s/../src/%s", ensure_tests_dir(), layers[l].name);
        bad += check_folder(dir, layers[l].name, check_private_file, layers[l].name, &files);
    }
    static const char *const outside[] = { "../cli", "../viewer", ".", "bench", "tools" };
    static const char *const owner[] = { "cli", "viewer", NULL, NULL, NULL };
    for (size_t k = 0; k < sizeof outside / sizeof outside[0]; ++k) {
        snprintf(dir, sizeof dir, "%s/%s", ensure_tests_dir(), outside[k]);
        bad += check_folder(dir, outside[k], check_private_file, owner[k], &files);
    }
    fprintf(stderr, "        %d files checked for private headers\n", files);
    ENSURE(files > 80);
    ENSURE(bad == 0);
    // The check finds what it is meant to find.
    const char *text = "#include \"sim/solver_internal.h\"\n";
    ENSURE(check_private_headers("sim/step.c", "sim", text) == 0);
    ENSURE(check_private_headers("gather/x.c", "gather", text) == 1);
    ENSURE(check_private_headers("cli/main.c", NULL, text) == 1);
    ENSURE(check_private_headers("sim/x.c", "sim", "#include \"solver_internal.h\"\n") == 1);
    ENSURE(check_private_headers("sim/x.c", "sim", "#include \"sim/simulate.h\"\n") == 0);
    const char *world = "#include \"world_internal.h\"\n";
    ENSURE(check_private_headers("viewer/world_load.c", "viewer", world) == 0);
    ENSURE(check_private_headers("tests/test_viewer.c", NULL, "#include \"../viewer/world_internal.h\"\n") == 1);
    ENSURE(check_private_headers("viewer/keys.c", "viewer", text) == 1);
}
// --- end of private headers ----------------------------------------------------------

// --- viewer/ --------------------------------------------------------------------------
// The viewer sits on the library: its files may include core, model, io, sim
// and pipeline headers (no raster: it bakes through a child `weathering bake`;
// no gather: it gathers through the pipeline). Only viewer/gl.h includes
// OpenGL's headers and only viewer/app.h GLFW's; none includes another
// third-party library. Its world (world*), view, point filter and bake child
// are GL-free: they include no GL or window header of the viewer, so that
// test_viewer links them without a window.

static const layer viewer_layer = { "viewer", "core model io sim pipeline" };

// Viewer files (by name prefix) that stay GL-free, and the viewer's headers
// that bring GL or the window in.
static const char *const viewer_gl_free[] = { "world", "view.", "points.", "bake_child." };
static const char *const viewer_gl_headers[] = { "#include \"gl.h\"", "#include \"app.h\"",
                                                 "#include \"draw.h\"", "#include \"overlay.h\"",
                                                 "#include \"screenshot.h\"" };

// The violations of the viewer's rules in one of its files (`name` in viewer/).
static int check_viewer_file(const char *name, const char *text)
{
    char rel[300];
    snprintf(rel, sizeof rel, "viewer/%s", name);
    int bad = check_includes(rel, text, &viewer_layer);
    bad += check_library(rel, text, "<GL/", "viewer/gl.h");
    bad += check_library(rel, text, "<GLFW/", "viewer/app.h");
    bad += check_library(rel, text, "<libxml/", "io/scene_xml.c");
    bad += check_library(rel, text, "<assimp/", "io/mesh_import.c");
    bad += check_library(rel, text, "<openexr.h>", "io/exr.c");
    bad += check_library(rel, text, "<png.h>", "io/png_preview.c");
    bad += check_library(rel, text, "<mpi.h>", mpi_owner);
    for (size_t k = 0; k < sizeof viewer_gl_free / sizeof viewer_gl_free[0]; ++k) {
        if (strncmp(name, viewer_gl_free[k], strlen(viewer_gl_free[k])) != 0) {
            continue;
        }
        for (size_t h = 0; h < sizeof viewer_gl_headers / sizeof viewer_gl_headers[0]; ++h) {
            if (strstr(text, viewer_gl_headers[h]) != NULL) {
                fprintf(stderr, "        %s (GL-free) has %s\n", rel, viewer_gl_headers[h]);
                bad++;
            }
        }
    }
    return bad;
}

static int check_viewer_entry(const char *rel, const char *name, const char *text, const void *ctx)
{
    (void)rel;
    (void)ctx;
    return check_viewer_file(name, text);
}

TEST(the_viewer_includes_only_the_library_and_its_world_no_gl)
{
    char folder[4200];
    snprintf(folder, sizeof folder, "%s/../viewer", ensure_tests_dir());
    int files = 0;
    int bad = check_folder(folder, "viewer", check_viewer_entry, NULL, &files);
    fprintf(stderr, "        %d files in viewer/\n", files);
    ENSURE(files > 20);
    ENSURE(bad == 0);
}

// The viewer's check finds what it is meant to find.
TEST(a_wrong_viewer_include_is_caught)
{
    ENSURE(check_viewer_file("world_x.c", "#include \"gl.h\"\n") == 1);
    ENSURE(check_viewer_file("keys.c", "#include \"gl.h\"\n#include \"app.h\"\n") == 0);
    ENSURE(check_viewer_file("keys.c", "#include \"raster/bake.h\"\n") == 1);
    ENSURE(check_viewer_file("keys.c", "#include <GLFW/glfw3.h>\n") == 1);
    ENSURE(check_viewer_file("app.h", "#include <GLFW/glfw3.h>\n") == 0);
    ENSURE(check_viewer_file("draw.c", "#include <GL/osmesa.h>\n") == 1);
}

int main(void)
{
    RUN(every_layer_includes_only_the_layers_below_it);
    RUN(a_wrong_include_is_caught);
    RUN(private_headers_stay_in_their_folder);
    RUN(the_viewer_includes_only_the_library_and_its_world_no_gl);
    RUN(a_wrong_viewer_include_is_caught);
    RUN(the_command_line_stands_on_the_pipeline);
    return ensure_summary();
}
