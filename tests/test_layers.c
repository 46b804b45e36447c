// test_layers.c: the layers of src/ stay layers (docs/architecture.md). Each
// folder may include its own headers and those of the layers below it:
//
//   core <- model <- io, raster, sim, gather <- pipeline <- cli, viewer
//
// and the compute layers (raster, sim, gather) never open a file themselves:
// they take and return memory, the pipeline reads and writes. Only the scene
// loader includes libxml2 (scene_xml.c and its table engine's header, which
// the element groups include), only the mesh importer Assimp, only io/exr.c
// OpenEXR, only io/png_preview.c libpng.
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

// Third-party headers that belong to a few files each: `owners` is a
// space-separated list of them.
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

TEST(the_command_line_stands_on_the_pipeline)
{
    char folder[4200];
    snprintf(folder, sizeof folder, "%s/../cli", ensure_tests_dir());
    DIR *dir = opendir(folder);
    ENSURE(dir != NULL);
    int files = 0, bad = 0;
    struct dirent *e;
    while ((e = readdir(dir)) != NULL) {
        size_t n = strlen(e->d_name);
        if (n < 3 || e->d_name[n - 2] != '.' ||
            (e->d_name[n - 1] != 'c' && e->d_name[n - 1] != 'h')) {
            continue;
        }
        char path[4500], rel[300];
        snprintf(path, sizeof path, "%s/%s", folder, e->d_name);
        snprintf(rel, sizeof rel, "cli/%s", e->d_name);
        char *text = source_text(path);
        if (text == NULL) {
            bad++;
            continue;
        }
        bad += check_cli_includes(rel, text);
        bad += check_library(rel, text, "<libxml/", libxml_owners);
        bad += check_library(rel, text, "<openexr.h>", "io/exr.c");
        free(text);
        files++;
    }
    closedir(dir);
    fprintf(stderr, "        %d files in cli/\n", files);
    ENSURE(files > 0);
    ENSURE(bad == 0);
    // The check finds what it is meant to find.
    ENSURE(check_cli_includes("cli/x.c", "#include \"sim/emitter.h\"\n") == 1);
    ENSURE(check_cli_includes("cli/x.c", "#include \"io/exr.h\"\n") == 1);
    ENSURE(check_cli_includes("cli/x.c", "#include \"io/scene_xml.h\"\n#include \"cli.h\"\n") == 0);
}
// ---------------------------------------------------------------------------

TEST(every_layer_includes_only_the_layers_below_it)
{
    int files = 0, bad = 0;
    for (int l = 0; l < LAYER_COUNT; ++l) {
        char folder[4200];
        snprintf(folder, sizeof folder, "%s/../src/%s", ensure_tests_dir(), layers[l].name);
        DIR *dir = opendir(folder);
        ENSURE(dir != NULL);
        struct dirent *e;
        while ((e = readdir(dir)) != NULL) {
            size_t n = strlen(e->d_name);
            if (n < 3 || e->d_name[n - 2] != '.' ||
                (e->d_name[n - 1] != 'c' && e->d_name[n - 1] != 'h')) {
                continue;
            }
            char path[4500], rel[300];
            snprintf(path, sizeof path, "%s/%s", folder, e->d_name);
            snprintf(rel, sizeof rel, "%s/%s", layers[l].name, e->d_name);
            char *text = source_text(path);
            if (text == NULL) {
                bad++;
                continue;
            }
            bad += check_includes(rel, text, &layers[l]);
            if (is_compute(&layers[l])) {
                bad += check_no_file_io(rel, text);
            }
            bad += check_library(rel, text, "<libxml/", libxml_owners);
            bad += check_library(rel, text, "<assimp/", "io/mesh_import.c");
            bad += check_library(rel, text, "<openexr.h>", "io/exr.c");
            bad += check_library(rel, text, "<GL/osmesa.h>", "raster/bake.c");
            bad += check_library(rel, text, "<png.h>", "io/png_preview.c");
            free(text);
            files++;
        }
        closedir(dir);
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
}

int main(void)
{
    RUN(every_layer_includes_only_the_layers_below_it);
    RUN(a_wrong_include_is_caught);
    RUN(the_command_line_stands_on_the_pipeline);
    return ensure_summary();
}
