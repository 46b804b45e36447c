// test_pipeline.c: output folder rules, atomic files and the --stats JSON.
#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "core/atomic_file.h"
#include "ensure.h"
#include "pipeline/pipeline.h"
#include "core/limits.h"
#include "io/stats_json.h"
#include "pipeline/outputs.h"
#include "sim/simulate.h"

// Number of entries of `dir` whose name starts with '.' (temporaries); -1 when
// the folder cannot be read (never an empty folder's 0).
static int count_hidden_files(const char *dir)
{
    DIR *d = opendir(dir);
    if (d == NULL) {
        fprintf(stderr, "        %s: cannot be read\n", dir);
        return -1;
    }
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        n += e->d_name[0] == '.' && strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
    }
    closedir(d);
    return n;
}

TEST(output_folder_is_created_with_parents)
{
    wx_scene scene = { .output_index = -1 };
    wx_run_def opts = { 0 };
    snprintf(opts.out_dir, sizeof opts.out_dir, "%s/a/b/c", ensure_tmpdir());
    ENSURE(wx_output_prepare(&scene, &opts, NULL, NULL) == WX_OK);
    struct stat st;
    ENSURE(stat(opts.out_dir, &st) == 0 && S_ISDIR(st.st_mode));
    // Again: an existing folder is fine.
    ENSURE(wx_output_prepare(&scene, &opts, NULL, NULL) == WX_OK);
    // A file in the way is bad input.
    const char *file = ensure_write_file(ensure_tmpdir(), "plain", "x");
    snprintf(opts.out_dir, sizeof opts.out_dir, "%s", file);
    wx_error err;
    ENSURE(wx_output_prepare(&scene, &opts, NULL, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, OUTPUT_CONFLICT);
    ENSURE(ensure_contains(err.message, "not a folder"));
}

TEST(default_options_follow_the_scene)
{
    wx_scene scene = { 0 };
    snprintf(scene.name, sizeof scene.name, "house");
    scene.seed = 42;
    wx_run_def opts;
    opts = wx_default_run_def(&scene);
    ENSURE(strcmp(opts.out_dir, "out/house") == 0);
    ENSURE(opts.seed == 42);
    ENSURE(opts.threads >= 1);
    ENSURE(!opts.quiet);
}

TEST(an_input_file_is_never_an_output)
{
    const char *dir = ensure_tmpdir();
    wx_scene scene = { 0 };
    wx_scene_camera cam = { 0 };
    scene.cameras = &cam;
    scene.camera_count = 1;
    char scene_path[WX_PATH_MAX], depth_path[WX_PATH_MAX]; // the structs only point at them
    snprintf(scene_path, sizeof scene_path, "%s", ensure_write_file(dir, "s.xml", "<x/>"));
    snprintf(depth_path, sizeof depth_path, "%s",
             ensure_write_file(dir, "front_depth.exr", "not really"));
    scene.path = scene_path;
    cam.depth_path = depth_path;
    wx_run_def opts = { 0 };
    snprintf(opts.out_dir, sizeof opts.out_dir, "%s", dir);
    char path[WX_PATH_MAX];
    wx_error err;
    ENSURE(wx_output_path(&scene, &opts, "front_depth.exr", path, &err) == WX_BAD_INPUT);
    ENSURE_CAUSE(err, OUTPUT_CONFLICT);
    ENSURE(ensure_contains(err.message, "would be overwritten"));
    ENSURE(wx_output_path(&scene, &opts, "s.xml", path, &err) == WX_BAD_INPUT);
    ENSURE(wx_output_path(&scene, &opts, "mask.exr", path, &err) == WX_OK);
    ENSURE(ensure_contains(path, "/mask.exr"));
    ENSURE(wx_output_path(&scene, &opts, "../mask.exr", path, &err) == WX_BAD_INPUT);
    ENSURE(wx_output_path(&scene, &opts, "..", path, &err) == WX_BAD_INPUT);
}

TEST(atomic_write_replaces_whole_and_leaves_no_temporary)
{
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/atomic", ensure_tmpdir());
    ENSURE(mkdir(dir, 0777) == 0);
    char path[4300];
    snprintf(path, sizeof path, "%s/data.bin", dir);
    ENSURE(wx_write_file_atomic(path, "first version", 13, NULL) == WX_OK);
    ENSURE(wx_write_file_atomic(path, "second", 6, NULL) == WX_OK);
    char *text = ensure_read_file(path);
    ENSURE(text != NULL && strcmp(text, "second") == 0);
    free(text);
    ENSURE(count_hidden_files(dir) == 0);
    char tmp[WX_PATH_MAX];
    wx_temp_path(path, tmp);
    ENSURE(ensure_contains(tmp, "/.data.bin.tmp"));
    // A folder that does not exist: failure, nothing left behind.
    char missing[4400];
    snprintf(missing, sizeof missing, "%s/none/data.bin", dir);
    wx_error err;
    ENSURE(wx_write_file_atomic(missing, "x", 1, &err) == WX_FAIL);
    ENSURE_CAUSE(err, IO);
    ENSURE(ensure_contains(err.message, missing));
}

TEST(stats_json_has_the_pinned_keys_and_values)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/stats.json", ensure_tmpdir());
    wx_sim_stats stats = { .particles_emitted = 100, .particle_steps = 5000, .collisions = 40,
                           .absorbed = 10, .settled = 20, .escaped = 30, .alive = 40,
                           .dirt_initial_surface = 1.5, .dirt_emitted = 100,
                           .dirt_final_surface = 60, .dirt_in_flight = 11.5,
                           .dirt_escaped = 30 };
    wx_phase_times times = { .load = 0.25, .simulate = 1.5, .total = 2 };
    ENSURE(wx_write_stats(path, &stats, &times, NULL, 2, 9, NULL) == WX_OK);
    char *json = ensure_read_file(path);
    ENSURE(json != NULL);
    ENSURE(ensure_contains(json, "\"particles_emitted\": 100,"));
    ENSURE(ensure_contains(json, "\"particle_steps\": 5000,"));
    ENSURE(ensure_contains(json, "\"collisions\": 40,"));
    ENSURE(ensure_contains(json, "\"absorbed\": 10,"));
    ENSURE(ensure_contains(json, "\"settled\": 20,"));
    ENSURE(ensure_contains(json, "\"escaped\": 30,"));
    ENSURE(ensure_contains(json, "\"alive\": 40,"));
    ENSURE(ensure_contains(json, "\"initial_surface\": 1.5,"));
    ENSURE(ensure_contains(json, "\"in_flight\": 11.5,"));
    ENSURE(ensure_contains(json, "\"simulate\": 1.500000,"));
    ENSURE(ensure_contains(json, "\"threads\": 2,"));
    ENSURE(ensure_contains(json, "\"seed\": 9\n"));
    free(json);
    // Valid JSON according to an independent parser (python3: make deps
    // installs it).
    char out[512];
    int status = ensure_shell(out, sizeof out,
                              "python3 -c "
                              "\"import json,sys; d=json.load(open(sys.argv[1])); "
                              "assert d['dirt']['emitted']==100\" %s",
                              path);
    ENSURE(status == 0);
}

// Issue 24: the names of a sequence of 100 000 frames (<OutputMap every="1">
// over 100 000 iterations) were checked against each other pair by pair, 63 s
// before any work. They are listed in linear time now, each once.
TEST(a_sequence_of_100000_frames_is_listed_at_once)
{
    wx_scene_camera cams[2] = { { .name = "front", .has_view = true },
                                { .name = "out", .has_view = true, .is_output = true,
                                  .output_file = "mask.exr", .every = 1 } };
    wx_scene scene = { .cameras = cams, .camera_count = 2, .output_index = 1,
                       .iterations = 100000 };
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    wx_output_names names;
    wx_error err;
    ENSURE(wx_output_names_list(&scene, WX_PHASE_ALL, &names, &err) == WX_OK);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    double seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    printf("        %d names in %.3f s\n", names.count, seconds);
    // front: depth, normal, impact, dirt (bake; simulate's dirt is the same
    // name); out: depth, normal; mask.exr, mask.png; the frames.
    bool right = names.count == 4 + 2 + 2 + 100000 &&
                 strcmp(names.names[3], "front_dirt.exr") == 0 &&
                 strcmp(names.names[8], "mask.0001.exr") == 0 &&
                 strcmp(names.names[names.count - 1], "mask.100000.exr") == 0 &&
                 wx_output_names_has(&names, "mask.54321.exr") &&
                 wx_output_names_has(&names, "front_dirt.exr") &&
                 !wx_output_names_has(&names, "mask.100001.exr") &&
                 !wx_output_names_has(&names, "mask.0000.exr");
    wx_output_names_free(&names);
    ENSURE(right);
    ENSURE(seconds < 2.0); // about 0.03 s; 20 to 60 s when quadratic
}

// The run's list of outputs names exactly the previews the writers write
// (wx_preview_names): BASE.png for a mask of one channel (no <Substances>, or
// one declared substance, and no <Masks>), else BASE_NAME.png per channel, for
// the mask and for each TextureMap alike. The list used to name BASE.png for
// the mask always and no preview of a derived mask, so a stale temporary of
// those was never cleaned and a folder at their names was not refused first.
static bool lists(const wx_scene *scene, const char *const *yes, const char *const *no)
{
    wx_output_names names;
    wx_error err;
    if (wx_output_names_list(scene, WX_PHASE_ALL, &names, &err) != WX_OK) {
        return false;
    }
    bool right = true;
    for (int k = 0; yes[k] != NULL; ++k) {
        if (!wx_output_names_has(&names, yes[k])) {
            fprintf(stderr, "        %s is not listed\n", yes[k]);
            right = false;
        }
    }
    for (int k = 0; no[k] != NULL; ++k) {
        if (wx_output_names_has(&names, no[k])) {
            fprintf(stderr, "        %s is listed\n", no[k]);
            right = false;
        }
    }
    wx_output_names_free(&names);
    return right;
}

TEST(the_output_list_names_the_previews_the_writers_write)
{
    wx_scene_camera cams[2] = {
        { .name = "front", .has_view = true },
        { .name = "out", .has_view = true, .is_output = true, .output_file = "mask.exr" }
    };
    wx_texture_map tex = { .file = "tex.exr" };
    wx_scene scene = { .cameras = cams,
                       .camera_count = 2,
                       .output_index = 1,
                       .textures = &tex,
                       .texture_count = 1,
                       .iterations = 1,
                       .substance_count = 1,
                       .substances = { "dirt" } };
    // No <Substances>, no <Masks>: one channel Y.
    ENSURE(lists(&scene, (const char *[]){ "mask.png", "tex.png", NULL },
                 (const char *[]){ "mask_dirt.png", "tex_dirt.png", NULL }));
    // One declared substance: still one channel, so BASE.png.
    scene.substances_declared = true;
    snprintf(scene.substances[0], sizeof scene.substances[0], "water");
    ENSURE(lists(&scene, (const char *[]){ "mask.png", "tex.png", NULL },
                 (const char *[]){ "mask_water.png", "tex_water.png", NULL }));
    // <Masks> without <Substances>: the dirt's channel and the mask's.
    scene.substances_declared = false;
    snprintf(scene.substances[0], sizeof scene.substances[0], "dirt");
    scene.mask_count = 1;
    snprintf(scene.masks[0].name, sizeof scene.masks[0].name, "ao");
    ENSURE(lists(
        &scene,
        (const char *[]){ "mask_dirt.png", "mask_ao.png", "tex_dirt.png", "tex_ao.png", NULL },
        (const char *[]){ "mask.png", "tex.png", NULL }));
    // An upper-case extension (the scene reader accepts .EXR): the same BASE
    // for the frames and every preview.
    snprintf(cams[1].output_file, sizeof cams[1].output_file, "shot.EXR");
    cams[1].every = 1;
    ENSURE(
        lists(&scene,
              (const char *[]){ "shot.EXR", "shot_dirt.png", "shot_ao.png", "shot.0001.exr", NULL },
              (const char *[]){ "shot.EXR_dirt.png", "shot.EXR.0001.exr", NULL }));
    snprintf(cams[1].output_file, sizeof cams[1].output_file, "mask.exr");
    cams[1].every = 0;
    // Two substances and a mask.
    scene.substances_declared = true;
    scene.substance_count = 2;
    snprintf(scene.substances[0], sizeof scene.substances[0], "water");
    snprintf(scene.substances[1], sizeof scene.substances[1], "rust");
    ENSURE(lists(&scene,
                 (const char *[]){ "mask_water.png", "mask_rust.png", "mask_ao.png",
                                   "tex_water.png", "tex_rust.png", "tex_ao.png", NULL },
                 (const char *[]){ "mask.png", "tex.png", "mask_dirt.png", NULL }));
}

int main(void)
{
    RUN(output_folder_is_created_with_parents);
    RUN(default_options_follow_the_scene);
    RUN(an_input_file_is_never_an_output);
    RUN(atomic_write_replaces_whole_and_leaves_no_temporary);
    RUN(stats_json_has_the_pinned_keys_and_values);
    RUN(a_sequence_of_100000_frames_is_listed_at_once);
    RUN(the_output_list_names_the_previews_the_writers_write);
    return ensure_summary();
}
