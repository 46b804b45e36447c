// outputs.c: the output folder and what goes into it (outputs.h, docs/design.md
// section 6): the names a run writes, the checks made before any work, the
// folder's preparation and its removal after a failure.
#define _XOPEN_SOURCE 700 // realpath
#include "pipeline/outputs.h"

#include <errno.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/array.h"
#include "core/atomic_file.h"
#include "io/exr.h"
#include "model/naming.h"
#include "pipeline/preset.h"

// A <View> camera whose maps `bake` writes into the output folder.
static bool baked_camera(const wx_scene_camera *cam)
{
    return cam->has_view && (!wx_has_path(cam->depth_path) || cam->maps_in_output);
}

// FNV-1a: the slot a name starts its search at.
static uint64_t name_hash(const char *name)
{
    uint64_t h = 14695981039346656037u;
    for (const unsigned char *c = (const unsigned char *)name; *c != '\0'; ++c) {
        h = (h ^ *c) * 1099511628211u;
    }
    return h;
}

// The slot of `name` in the set: the one holding it, or the empty one where it
// would go.
static int64_t name_slot(const wx_output_names *list, const char *name)
{
    uint64_t mask = (uint64_t)list->slot_count - 1;
    for (uint64_t s = name_hash(name) & mask;; s = (s + 1) & mask) {
        int k = list->slots[s];
        if (k == 0 || strcmp(list->names[k - 1], name) == 0) {
            return (int64_t)s;
        }
    }
}

bool wx_output_names_has(const wx_output_names *list, const char *name)
{
    return list->slot_count > 0 && list->slots[name_slot(list, name)] != 0;
}

// Keeps the set at most half full: doubles it and puts every name back.
static bool grow_slots(wx_output_names *list)
{
    if (2 * ((int64_t)list->count + 1) <= list->slot_count) {
        return true;
    }
    int64_t grown = list->slot_count > 0 ? 2 * list->slot_count : 64;
    int *slots = calloc((size_t)grown, sizeof *slots);
    if (slots == NULL) {
        return false;
    }
    free(list->slots);
    list->slots = slots;
    list->slot_count = grown;
    for (int k = 0; k < list->count; ++k) {
        list->slots[name_slot(list, list->names[k])] = k + 1;
    }
    return true;
}

static wx_result add_name(wx_output_names *list, char *clash, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

// Adds a name unless the list has it already (bake and simulate both write
// <camera>_dirt.exr); then `clash` (WX_OUTPUT_NAME_MAX chars, may be NULL)
// gets it if it holds none yet. A hash set finds it: comparing with every
// name before made a sequence of 100 000 frames cost 63 s before any work
// (issue 24).
static wx_result add_name(wx_output_names *list, char *clash, const char *fmt, ...)
{
    if (!wx_array_reserve((void **)&list->names, &list->capacity, list->count + 1,
                          sizeof *list->names, 16) ||
        !grow_slots(list)) {
        return WX_FAIL;
    }
    va_list args;
    va_start(args, fmt);
    vsnprintf(list->names[list->count], WX_OUTPUT_NAME_MAX, fmt, args);
    va_end(args);
    int64_t slot = name_slot(list, list->names[list->count]);
    if (list->slots[slot] == 0) {
        list->slots[slot] = ++list->count;
    } else if (clash != NULL && clash[0] == '\0') {
        snprintf(clash, WX_OUTPUT_NAME_MAX, "%s", list->names[list->count]);
    }
    return WX_OK;
}

// The previews of a mask or texture file BASE.exr (wx_preview_names: BASE.png
// for one channel, BASE_NAME.png per channel), and its frames BASE.NNNN.exr
// for every k-th iteration.
static wx_result add_sequence(const wx_scene *scene, const char *file, int every,
                              wx_output_names *out, char *clash)
{
    char name[WX_OUTPUT_NAME_MAX];
    char previews[WX_MAX_PREVIEWS][WX_OUTPUT_NAME_MAX];
    int preview_count = wx_preview_names(scene, file, previews);
    wx_result r = WX_OK;
    for (int p = 0; p < preview_count && r == WX_OK; ++p) {
        r = add_name(out, clash, "%s", previews[p]);
    }
    for (int k = every; every > 0 && k <= scene->iterations && r == WX_OK; k += every) {
        wx_frame_name(file, k, name, sizeof name);
        r = add_name(out, clash, "%s", name);
    }
    return r;
}

wx_result wx_output_names_list(const wx_scene *scene, unsigned phases, wx_output_names *out,
                               wx_error *err)
{
    memset(out, 0, sizeof *out);
    wx_result r = WX_OK;
    for (int c = 0; c < scene->camera_count && r == WX_OK; ++c) {
        const wx_scene_camera *cam = &scene->cameras[c];
        int baked = (phases & WX_PHASE_BAKE) && baked_camera(cam) ? (cam->is_output ? 2 : 4) : 0;
        char map[WX_OUTPUT_NAME_MAX];
        for (int k = 0; k < baked && r == WX_OK; ++k) {
            wx_map_file_name(cam->name, k, map, sizeof map);
            r = add_name(out, NULL, "%s", map);
        }
        if (r == WX_OK && (phases & WX_PHASE_SIMULATE) && !cam->is_output) {
            wx_map_file_name(cam->name, WX_MAP_DIRT, map, sizeof map);
            r = add_name(out, NULL, "%s", map);
        }
    }
    if (r == WX_OK && (phases & WX_PHASE_GATHER) && scene->output_index >= 0) {
        const wx_scene_camera *cam = &scene->cameras[scene->output_index];
        r = add_name(out, NULL, "%s", cam->output_file);
        if (r == WX_OK) {
            r = add_sequence(scene, cam->output_file, cam->every, out, NULL);
        }
    }
    // A UDIM texture's names are known only with its mesh's tiles, after the
    // parser has checked the others': from the first UDIM texture on, a name a
    // texture repeats is refused.
    char clash[WX_OUTPUT_NAME_MAX] = "";
    bool udim = false;
    for (int t = 0; t < scene->texture_count && r == WX_OK && (phases & WX_PHASE_GATHER); ++t) {
        const wx_texture_map *tm = &scene->textures[t];
        udim = udim || tm->tiles == WX_TILES_UDIM;
        // One file, or with tiles="udim" one per tile (none until the tiles are
        // known: wx_textures_find_tiles), each with its previews and frames.
        for (int f = 0; f < wx_texture_file_count(tm) && r == WX_OK && clash[0] == '\0'; ++f) {
            char own[WX_OUTPUT_NAME_MAX];
            if (tm->tiles == WX_TILES_UDIM) {
                wx_tile_name(tm->file, wx_texture_file_tile(tm, f), own, sizeof own);
            } else {
                snprintf(own, sizeof own, "%s", tm->file);
            }
            r = add_name(out, udim ? clash : NULL, "%s", own);
            if (r == WX_OK) {
                r = add_sequence(scene, own, tm->every, out, udim ? clash : NULL);
            }
        }
        if (r == WX_OK && clash[0] != '\0') {
            wx_output_names_free(out);
            return wx_fail(err, WX_CAUSE_BAD_SCENE,
                           "%s:%d: <TextureMap> file=\"%s\"%s writes '%s', which another "
                           "output of the scene writes too; choose another file",
                           scene->path, tm->line, tm->file,
                           tm->tiles == WX_TILES_UDIM ? " tiles=\"udim\"" : "", clash);
        }
    }
    if (r != WX_OK) {
        wx_output_names_free(out);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (output names)");
    }
    return WX_OK;
}

void wx_output_names_free(wx_output_names *names)
{
    free(names->names);
    free(names->slots);
    memset(names, 0, sizeof *names);
}

wx_result wx_make_folders(const char *path, char created[WX_PATH_MAX], wx_error *err)
{
    char partial[WX_PATH_MAX];
    size_t len = strlen(path);
    created[0] = '\0';
    if (len == 0 || len >= sizeof partial) {
        return wx_fail(err, WX_CAUSE_PATH_TOO_LONG, "output folder name is empty or too long");
    }
    memcpy(partial, path, len + 1);
    for (size_t i = 1; i <= len; ++i) {
        if (partial[i] != '/' && partial[i] != '\0') {
            continue;
        }
        char saved = partial[i];
        partial[i] = '\0';
        if (mkdir(partial, 0777) == 0) {
            if (created[0] == '\0') {
                memcpy(created, partial, i + 1);
            }
        } else if (errno != EEXIST) {
            return wx_fail(err, WX_CAUSE_IO, "%s: cannot create folder (%s)", partial,
                                strerror(errno));
        }
        partial[i] = saved;
    }
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISDIR(st.st_mode)) {
        return wx_fail(err, WX_CAUSE_OUTPUT_CONFLICT, "%s: exists and is not a folder", path);
    }
    return WX_OK;
}

// Whether a file name in the output folder is the temporary of one of ours.
typedef struct temp_owner {
    const wx_output_names *names;
    const char *stats_name; ///< --stats file's name when it lies in the folder, else NULL
} temp_owner;

static bool is_our_output(const char *name, void *context)
{
    const temp_owner *owner = context;
    if (owner->stats_name != NULL && strcmp(name, owner->stats_name) == 0) {
        return true;
    }
    return wx_output_names_has(owner->names, name);
}

static bool canonical_path(const char *path, char out[WX_PATH_MAX]);

wx_result wx_output_prepare(const wx_scene *scene, const wx_run_def *opts,
                            char created[WX_PATH_MAX], wx_error *err)
{
    char made[WX_PATH_MAX];
    wx_result r = wx_make_folders(opts->out_dir, made, err);
    if (created != NULL) {
        memcpy(created, made, sizeof made);
    }
    if (r != WX_OK) {
        wx_output_remove_empty(opts->out_dir, made);
        return r;
    }
    // Temporaries of an earlier run that was killed (SIGKILL, power loss): only
    // those of the files this program writes there.
    wx_output_names names;
    r = wx_output_names_list(scene, WX_PHASE_ALL, &names, err);
    if (r != WX_OK) {
        return r;
    }
    temp_owner owner = { .names = &names };
    char folder[WX_PATH_MAX], stats_folder[WX_PATH_MAX], stats_canonical[WX_PATH_MAX];
    if (opts->stats_path != NULL) {
        const char *slash = strrchr(opts->stats_path, '/');
        if (slash == NULL) {
            snprintf(stats_folder, sizeof stats_folder, ".");
        } else if (slash == opts->stats_path) {
            snprintf(stats_folder, sizeof stats_folder, "/");
        } else {
            snprintf(stats_folder, sizeof stats_folder, "%.*s", (int)(slash - opts->stats_path),
                     opts->stats_path);
        }
        if (canonical_path(opts->out_dir, folder) &&
            canonical_path(stats_folder, stats_canonical) &&
            strcmp(folder, stats_canonical) == 0) {
            owner.stats_name = slash != NULL ? slash + 1 : opts->stats_path;
        }
    }
    wx_temp_remove_stale(opts->out_dir, is_our_output, &owner);
    wx_output_names_free(&names);
    return WX_OK;
}

void wx_output_remove_empty(const char *out_dir, const char *created)
{
    if (created == NULL || created[0] == '\0') {
        return;
    }
    char folder[WX_PATH_MAX];
    snprintf(folder, sizeof folder, "%s", out_dir);
    size_t stop = strlen(created);
    for (;;) {
        size_t len = strlen(folder);
        while (len > 1 && folder[len - 1] == '/') {
            folder[--len] = '\0';
        }
        if (len < stop || rmdir(folder) != 0) {
            return; // not empty (or not ours): keep it and its parents
        }
        char *slash = strrchr(folder, '/');
        if (len == stop || slash == NULL) {
            return;
        }
        *slash = '\0';
    }
}

static bool same_file(const struct stat *a, const char *path)
{
    struct stat b;
    return wx_has_path(path) && stat(path, &b) == 0 && a->st_dev == b.st_dev &&
           a->st_ino == b.st_ino;
}

// True when the file `st` describes is the scene or a map or mesh it names.
// Maps this program baked into the output folder (maps_in_output) are not inputs.
static bool is_scene_input(const wx_scene *scene, const struct stat *st)
{
    if (same_file(st, scene->path)) {
        return true;
    }
    for (int c = 0; c < scene->camera_count; ++c) {
        const wx_scene_camera *cam = &scene->cameras[c];
        if (cam->maps_in_output) {
            continue; // baked by us: a later phase may write the next stage over them
        }
        if (same_file(st, cam->depth_path) || same_file(st, cam->normal_path) ||
            same_file(st, cam->impact_path) || same_file(st, cam->dirt_path)) {
            return true;
        }
    }
    for (int m = 0; m < scene->mesh_count; ++m) {
        if (same_file(st, scene->meshes[m].path)) {
            return true;
        }
    }
    return false;
}

wx_result wx_output_path(const wx_scene *scene, const wx_run_def *opts, const char *name,
                         char path[WX_PATH_MAX], wx_error *err)
{
    if (name[0] == '\0' || strchr(name, '/') != NULL || strcmp(name, ".") == 0 ||
        strcmp(name, "..") == 0) {
        return wx_fail(err, WX_CAUSE_BAD_VALUE, "'%s' is not a plain file name", name);
    }
    // The file is written as ".NAME.tmpPID" first: that name and its path must fit too.
    if (strlen(name) > WX_OUTPUT_FILE_NAME_MAX) {
        return wx_fail(err, WX_CAUSE_PATH_TOO_LONG,
                       "'%.24s...%s': a name of %zu characters, over the %d a run can write "
                       "(its temporary '.NAME.tmpPID' must fit the %d of a file name)",
                       name, name + strlen(name) - 16, strlen(name), WX_OUTPUT_FILE_NAME_MAX,
                       WX_FILE_NAME_MAX);
    }
    int n = snprintf(path, WX_PATH_MAX, "%s/%s", opts->out_dir, name);
    if (n < 0 || n + WX_TEMP_NAME_EXTRA >= WX_PATH_MAX) {
        return wx_fail(err, WX_CAUSE_PATH_TOO_LONG, "%.200s.../%s: path too long",
                       opts->out_dir, name);
    }
    struct stat st;
    if (stat(path, &st) == 0 && is_scene_input(scene, &st)) {
        return wx_fail(err, WX_CAUSE_OUTPUT_CONFLICT,
                       "%s: is an input of scene %s and would be overwritten; choose "
                       "another --out folder",
                       path, scene->path);
    }
    return WX_OK;
}

const char *wx_file_kind(unsigned mode)
{
    return S_ISLNK(mode)    ? "a symbolic link"
           : S_ISDIR(mode)  ? "a folder"
           : S_ISFIFO(mode) ? "a FIFO"
           : S_ISCHR(mode) || S_ISBLK(mode) ? "a device"
                                             : "not a regular file";
}

// Removes "." and resolves ".." in the part of a path that does not exist yet.
static void append_lexical(char out[WX_PATH_MAX], const char *rest)
{
    char copy[WX_PATH_MAX];
    snprintf(copy, sizeof copy, "%s", rest);
    char *save = NULL;
    for (char *part = strtok_r(copy, "/", &save); part != NULL; part = strtok_r(NULL, "/", &save)) {
        if (strcmp(part, ".") == 0) {
            continue;
        }
        size_t len = strlen(out);
        if (strcmp(part, "..") == 0) {
            char *slash = strrchr(out, '/');
            if (slash != NULL) {
                *(slash == out ? slash + 1 : slash) = '\0';
            }
            continue;
        }
        snprintf(out + len, WX_PATH_MAX - len, "%s%s", len > 0 && out[len - 1] == '/' ? "" : "/",
                 part);
    }
}

// The absolute path of `path` with its symbolic links resolved as far as it
// exists (realpath of its longest existing prefix, then the rest as written).
static bool canonical_path(const char *path, char out[WX_PATH_MAX])
{
    char prefix[WX_PATH_MAX];
    if (snprintf(prefix, sizeof prefix, "%s", path) >= (int)sizeof prefix) {
        return false;
    }
    char resolved[PATH_MAX];
    for (;;) {
        const char *start = prefix[0] != '\0' ? prefix : ".";
        if (realpath(start, resolved) != NULL) {
            break;
        }
        char *slash = strrchr(prefix, '/');
        if (slash == NULL) {
            prefix[0] = '\0';
        } else if (slash == prefix) {
            prefix[1] = '\0'; // "/" exists
        } else {
            *slash = '\0';
        }
    }
    if (snprintf(out, WX_PATH_MAX, "%s", resolved) >= WX_PATH_MAX) {
        return false;
    }
    size_t used = strlen(prefix);
    if (strcmp(prefix, path) != 0) {
        append_lexical(out, path + used);
    }
    return true;
}

// The --stats file (docs/design.md section 6): never an input, an output of the run or an
// existing non-regular file; its folder exists or is the output folder.
static wx_result check_stats_path(const wx_scene *scene, const wx_run_def *opts,
                                  const wx_output_names *outputs, wx_error *err)
{
    const char *path = opts->stats_path;
    const char *slash = strrchr(path, '/');
    const char *base = slash != NULL ? slash + 1 : path;
    if (strlen(base) > WX_OUTPUT_FILE_NAME_MAX || strlen(path) + WX_TEMP_NAME_EXTRA >= WX_PATH_MAX) {
        return wx_fail(err, WX_CAUSE_PATH_TOO_LONG,
                       "--stats %.24s...: a name of %zu characters, over the %d a run can "
                       "write (its temporary '.NAME.tmpPID' must fit the %d of a file name)",
                       base, strlen(base), WX_OUTPUT_FILE_NAME_MAX, WX_FILE_NAME_MAX);
    }
    struct stat st;
    if (lstat(path, &st) == 0) {
        if (!S_ISREG(st.st_mode)) {
            return wx_fail(err, WX_CAUSE_OUTPUT_CONFLICT,
                           "--stats %s: exists and is %s; the statistics are written only "
                           "to a new or a regular file",
                           path, wx_file_kind(st.st_mode));
        }
        if (is_scene_input(scene, &st)) {
            return wx_fail(err, WX_CAUSE_OUTPUT_CONFLICT,
                           "--stats %s: is an input of scene %s and would be overwritten", path,
                           scene->path);
        }
    }
    char stats[WX_PATH_MAX], out_dir[WX_PATH_MAX], output[WX_PATH_MAX];
    if (!canonical_path(path, stats) || !canonical_path(opts->out_dir, out_dir)) {
        return wx_fail(err, WX_CAUSE_PATH_TOO_LONG, "--stats %s: path too long", path);
    }
    for (int k = 0; k < outputs->count; ++k) {
        int n = snprintf(output, sizeof output, "%s/%s", out_dir, outputs->names[k]);
        if (n > 0 && n < (int)sizeof output && strcmp(output, stats) == 0) {
            return wx_fail(err, WX_CAUSE_OUTPUT_CONFLICT,
                           "--stats %s: is the run's output %s; choose another file name", path,
                           outputs->names[k]);
        }
    }
    char folder[WX_PATH_MAX];
    snprintf(folder, sizeof folder, "%s", stats);
    *strrchr(folder, '/') = '\0';
    struct stat dir;
    bool exists = stat(folder[0] != '\0' ? folder : "/", &dir) == 0 && S_ISDIR(dir.st_mode);
    if (!exists && strcmp(folder, out_dir) != 0) {
        return wx_fail(err, WX_CAUSE_FILE_MISSING,
                       "--stats %s: folder %s does not exist (only the output folder is "
                       "made by the run)",
                       path, folder);
    }
    return WX_OK;
}

// The scene `run MESH` generated (opts->scene_text) replaces only a regular
// file that an earlier `run MESH` generated: never a user's own scene.xml, a
// link or a folder.
static wx_result check_scene_copy(const wx_scene *scene, wx_error *err)
{
    struct stat st;
    if (lstat(scene->path, &st) != 0) {
        return WX_OK;
    }
    if (!S_ISREG(st.st_mode)) {
        return wx_fail(err, WX_CAUSE_OUTPUT_CONFLICT,
                       "%s: exists and is %s, where the run writes the scene it generated; "
                       "remove it or choose another --out folder",
                       scene->path, wx_file_kind(st.st_mode));
    }
    char head[512] = "";
    FILE *f = fopen(scene->path, "rb");
    if (f != NULL) {
        size_t n = fread(head, 1, sizeof head - 1, f);
        head[n] = '\0';
        fclose(f);
    }
    if (strstr(head, WX_GENERATED_SCENE_MARK) == NULL) {
        return wx_fail(err, WX_CAUSE_OUTPUT_CONFLICT,
                       "%s: exists and is not a scene that `weathering run MESH` generated; "
                       "it is kept: choose another --out folder or remove it",
                       scene->path);
    }
    return WX_OK;
}

wx_result wx_output_write_scene(const wx_scene *scene, const wx_run_def *opts, wx_error *err)
{
    if (opts->scene_text == NULL) {
        return WX_OK;
    }
    return wx_write_file_atomic(scene->path, opts->scene_text, strlen(opts->scene_text), err);
}

void wx_output_remove_scene(const wx_scene *scene, const wx_run_def *opts, const char *created)
{
    if (opts->scene_text == NULL || created == NULL || created[0] == '\0') {
        return;
    }
    // Only from a folder this run made, and only when the scene is all it holds.
    DIR *dir = opendir(opts->out_dir);
    if (dir == NULL) {
        return;
    }
    const char *slash = strrchr(scene->path, '/');
    const char *base = slash != NULL ? slash + 1 : scene->path;
    int others = 0;
    for (struct dirent *e = readdir(dir); e != NULL; e = readdir(dir)) {
        others += strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0 &&
                  strcmp(e->d_name, base) != 0;
    }
    closedir(dir);
    if (others == 0) {
        unlink(scene->path);
    }
}

wx_result wx_check_outputs(const wx_scene *scene, const wx_run_def *opts, unsigned phases,
                           wx_error *err)
{
    wx_output_names names;
    wx_result r = opts->scene_text != NULL ? check_scene_copy(scene, err) : WX_OK;
    if (r != WX_OK) {
        return r;
    }
    r = wx_output_names_list(scene, phases, &names, err);
    for (int k = 0; k < names.count && r == WX_OK; ++k) {
        char path[WX_PATH_MAX];
        r = wx_output_path(scene, opts, names.names[k], path, err);
        struct stat st;
        if (r == WX_OK && lstat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
            r = wx_fail(err, WX_CAUSE_OUTPUT_CONFLICT,
                        "%s: exists and is %s, where the run writes its output %s; remove "
                        "it or choose another --out folder",
                        path, wx_file_kind(st.st_mode), names.names[k]);
        }
    }
    if (r == WX_OK && opts->stats_path != NULL) {
        wx_output_names all;
        r = wx_output_names_list(scene, WX_PHASE_ALL, &all, err);
        if (r == WX_OK) {
            r = check_stats_path(scene, opts, &all, err);
        }
        wx_output_names_free(&all);
    }
    wx_output_names_free(&names);
    return r;
}

bool wx_scene_needs_bake(const wx_scene *scene)
{
    for (int c = 0; c < scene->camera_count; ++c) {
        if (scene->cameras[c].has_view && !wx_has_path(scene->cameras[c].depth_path)) {
            return true;
        }
    }
    return false;
}

wx_result wx_use_baked_maps(wx_scene *scene, const wx_run_def *opts, wx_error *err)
{
    for (int c = 0; c < scene->camera_count; ++c) {
        wx_scene_camera *cam = &scene->cameras[c];
        if (!cam->has_view || wx_has_path(cam->depth_path)) {
            continue;
        }
        cam->maps_in_output = true;
        char **paths[4] = { &cam->depth_path, &cam->normal_path, &cam->impact_path,
                            &cam->dirt_path };
        int count = cam->is_output ? 2 : 4;
        for (int k = 0; k < count; ++k) {
            char path[WX_PATH_MAX], name[WX_OUTPUT_NAME_MAX];
            wx_map_file_name(cam->name, k, name, sizeof name);
            int n = snprintf(path, sizeof path, "%s/%s", opts->out_dir, name);
            if (n < 0 || n >= (int)sizeof path) {
                return wx_fail(err, WX_CAUSE_PATH_TOO_LONG, "%s: output path too long",
                               opts->out_dir);
            }
            if (!wx_scene_set_path(paths[k], path)) {
                return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (paths)");
            }
            if (access(path, R_OK) != 0) {
                return wx_fail(err, WX_CAUSE_MISSING_PHASE,
                               "%s: camera '%s' has no baked %s map in %s; run `weathering "
                               "bake %s --out %s` first",
                               scene->path, cam->name, wx_map_kind_name(k), opts->out_dir,
                               scene->path, opts->out_dir);
            }
        }
    }
    return WX_OK;
}

void wx_output_describe(FILE *out, const wx_run_def *opts, const char *name)
{
    char path[WX_PATH_MAX + 512];
    snprintf(path, sizeof path, "%s/%s", opts->out_dir, name);
    struct stat st;
    if (stat(path, &st) != 0) {
        return;
    }
    wx_image *image = calloc(1, sizeof *image);
    wx_error err;
    fprintf(out, "  %-28s %8.1f MB", name, (double)st.st_size / 1e6);
    if (image != NULL && wx_exr_read_header(path, image, &err) == WX_OK) {
        fprintf(out, "  %d x %d, channels", image->width, image->height);
        for (int c = 0; c < image->channel_count; ++c) {
            fprintf(out, "%s %s", c > 0 ? "," : "", image->channel_names[c]);
        }
        wx_image_free(image);
    }
    free(image);
    fprintf(out, "\n");
}
