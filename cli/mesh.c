// mesh.c: the mesh commands (docs/presets.md): `init MESH` writes a commented
// scene for a mesh from a preset; `run MESH` generates it in memory and runs it.
#define _XOPEN_SOURCE 700 // realpath
#include "cli.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "core/atomic_file.h"
#include "core/limits.h"
#include "io/scene_xml.h"
#include "model/scene.h"
#include "pipeline/outputs.h"
#include "pipeline/preset.h"

// --- init, run MESH (docs/presets.md) ------------------------------------------

// An Ogre mesh (.mesh.xml) is XML too, but not a scene.
static bool is_ogre_mesh(const char *path)
{
    size_t n = strlen(path);
    return n >= 9 && strcasecmp(path + n - 9, ".mesh.xml") == 0;
}

// A scene file is an .xml; anything else given to `run` is a mesh.
bool cli_is_scene_file(const char *path)
{
    size_t n = strlen(path);
    return n >= 4 && strcasecmp(path + n - 4, ".xml") == 0 && !is_ogre_mesh(path);
}

// The scene text for the mesh of `args`: its path written as given when
// `as_given`, else absolute; `scene_name` (may be NULL) becomes <Weathering
// name>; checked as the file `scene_path` (NULL: in the current folder)
// before it is handed back.
static int generate(const cli_args *args, bool as_given, const char *scene_name,
                    const char *scene_path, char **text)
{
    char mesh_ref[WX_PATH_MAX];
    if (as_given) {
        snprintf(mesh_ref, sizeof mesh_ref, "%s", args->scene_path);
    } else if (realpath(args->scene_path, mesh_ref) == NULL) {
        fprintf(stderr, "weathering: %s: mesh file not found\n", args->scene_path);
        return WX_BAD_INPUT;
    }
    wx_init_def def = { .mesh_path = args->scene_path,
                        .mesh_ref = mesh_ref,
                        .preset = args->preset,
                        .resolution = args->resolution,
                        .unit_m = args->units != NULL ? wx_unit_metres(args->units) : 1.0,
                        .scene_name = scene_name,
                        .scene_path = scene_path,
                        .quiet = args->quiet };
    wx_error err;
    wx_result r = wx_scene_generate(&def, text, &err);
    if (r != WX_OK) {
        fprintf(stderr, "weathering: %s\n", err.message);
    }
    return r;
}

// Where `init` may write its scene: a new or regular file (with --force) in a
// folder that exists, never the mesh. Exit 2 with the reason otherwise.
static int check_init_target(const cli_args *args, const char *scene_path)
{
    struct stat st, target, mesh;
    if (lstat(scene_path, &st) == 0) {
        bool same = stat(scene_path, &target) == 0 && stat(args->scene_path, &mesh) == 0 &&
                    target.st_dev == mesh.st_dev && target.st_ino == mesh.st_ino;
        if (same) {
            fprintf(stderr,
                    "weathering: %s: is the mesh itself; the scene never replaces it (give -o "
                    "SCENE.xml)\n",
                    scene_path);
            return WX_BAD_INPUT;
        }
        if (!S_ISREG(st.st_mode)) {
            fprintf(stderr, "weathering: %s: exists and is %s; choose another -o\n", scene_path,
                    wx_file_kind(st.st_mode));
            return WX_BAD_INPUT;
        }
        if (!args->force) {
            fprintf(stderr, "weathering: %s exists; give --force to replace it\n", scene_path);
            return WX_BAD_INPUT;
        }
    }
    char folder[WX_PATH_MAX] = ".";
    const char *slash = strrchr(scene_path, '/');
    if (slash != NULL) { // "/x.xml": "/"
        int len = slash == scene_path ? 1 : (int)(slash - scene_path);
        snprintf(folder, sizeof folder, "%.*s", len, scene_path);
    }
    struct stat dir;
    if (stat(folder, &dir) != 0 || !S_ISDIR(dir.st_mode)) {
        fprintf(stderr, "weathering: -o %s: folder %s does not exist\n", scene_path, folder);
        return WX_BAD_INPUT;
    }
    return WX_OK;
}

int command_init(const cli_args *args)
{
    char scene_path[WX_PATH_MAX], base[256];
    wx_mesh_name(args->scene_path, base, sizeof base);
    if (args->init_out != NULL) {
        snprintf(scene_path, sizeof scene_path, "%s", args->init_out);
    } else {
        snprintf(scene_path, sizeof scene_path, "%s.xml", base);
    }
    if (!cli_is_scene_file(scene_path)) {
        return usage_error("-o %s: the scene's name must end in .xml (and not .mesh.xml)",
                           scene_path);
    }
    int status = check_init_target(args, scene_path);
    if (status != WX_OK) {
        return status;
    }
    // The mesh as the scene names it: as given when the scene is written in the
    // current folder and the path is relative, else absolute.
    bool as_given = strchr(scene_path, '/') == NULL && args->scene_path[0] != '/';
    char *text = NULL;
    status = generate(args, as_given, NULL, scene_path, &text);
    if (status != WX_OK) {
        return status;
    }
    // What the scene says, read as a run will read it, before it is written
    // (generate checked it already: nothing that does not load is written).
    wx_scene scene;
    wx_error err;
    wx_result r = wx_scene_load_text(scene_path, text, strlen(text), &scene, &err);
    if (r == WX_OK) {
        r = wx_write_file_atomic(scene_path, text, strlen(text), &err);
        if (r != WX_OK) {
            wx_scene_free(&scene);
        }
    }
    free(text);
    if (r != WX_OK) {
        fprintf(stderr, "weathering: %s\n", err.message);
        return r;
    }
    if (!args->quiet) {
        printf("wrote %s (preset %s: %d cameras, %d emitter%s%s); run it with "
               "`weathering run %s`\n",
               scene_path, args->preset != NULL ? args->preset : "rain", scene.camera_count,
               scene.emitter_count, scene.emitter_count == 1 ? "" : "s",
               scene.texture_count > 0 ? ", a TextureMap" : "", scene_path);
    }
    wx_scene_free(&scene);
    return WX_OK;
}

int command_run(const cli_args *args)
{
    const unsigned all = WX_PHASE_BAKE | WX_PHASE_SIMULATE | WX_PHASE_GATHER;
    if (cli_is_scene_file(args->scene_path)) {
        return cli_run_phases(args, all);
    }
    // A mesh: its scene generated in memory, named after the mesh, run as
    // OUT/scene.xml and written there once the run's checks pass.
    char out_dir[WX_PATH_MAX], base[256], scene_path[WX_PATH_MAX + 16];
    wx_mesh_name(args->scene_path, base, sizeof base);
    if (args->out_dir != NULL) {
        snprintf(out_dir, sizeof out_dir, "%s", args->out_dir);
    } else {
        snprintf(out_dir, sizeof out_dir, "out/%s", base);
    }
    snprintf(scene_path, sizeof scene_path, "%s/scene.xml", out_dir);
    char *text = NULL;
    int status = generate(args, false, base, scene_path, &text);
    if (status != WX_OK) {
        return status;
    }
    cli_args scene_args = *args;
    scene_args.scene_path = scene_path;
    scene_args.out_dir = out_dir;
    scene_args.scene_text = text;
    status = cli_run_phases(&scene_args, all);
    free(text);
    return status;
}
