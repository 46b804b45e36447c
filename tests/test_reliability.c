// test_reliability.c: bad inputs through the command line, interrupted and killed
// runs, the memory limit, and the temporaries of atomic writes (docs/reliability.md).
#define _XOPEN_SOURCE 700 // realpath
#include <dirent.h>
#include <errno.h>
#include <float.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "core/atomic_file.h"
#include "pipeline/pipeline.h"
#include "model/scene.h"
#include "ensure.h"
#include "io/exr.h"
#include "core/limits.h"
#include "io/scene_xml.h"
#include "model/image.h"
#include "pipeline/outputs.h"
#include "pipeline/run.h"

static char out[65536];

static int compare_names(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

// The names in `folder` ending in `suffix`, sorted; returns the count (<= cap),
// -1 (with a note) when the folder cannot be read: never an empty folder's 0.
static int list_names(const char *folder, const char *suffix, char **names, int cap)
{
    DIR *dir = opendir(folder);
    if (dir == NULL) {
        fprintf(stderr, "        %s: cannot be read\n", folder);
        return -1;
    }
    int count = 0;
    struct dirent *entry;
    size_t suffix_len = strlen(suffix);
    while ((entry = readdir(dir)) != NULL && count < cap) {
        size_t len = strlen(entry->d_name);
        if (strcmp(entry->d_name, ".") == 0 || strcmp(entry->d_name, "..") == 0) {
            continue;
        }
        if (len >= suffix_len && strcmp(entry->d_name + len - suffix_len, suffix) == 0) {
            names[count++] = strdup(entry->d_name);
        }
    }
    closedir(dir);
    qsort(names, (size_t)count, sizeof names[0], compare_names);
    return count;
}

static void free_names(char **names, int count)
{
    for (int i = 0; i < count; ++i) {
        free(names[i]);
    }
}

// Loads and runs `path` in this process: it must fail for the expected cause
// (the command line shows only the message and the exit status).
static bool fails_in_process_for(const char *path, const ensure_expectation *want, int index)
{
    wx_scene scene;
    wx_error err = { 0 };
    wx_result r = wx_scene_load(path, &scene, &err);
    if (r == WX_OK) {
        wx_run_def def = wx_default_run_def(&scene);
        snprintf(def.out_dir, sizeof def.out_dir, "%s/in_process_%d", ensure_tmpdir(), index);
        def.quiet = true;
        wx_run_report report;
        r = wx_run_phases(&scene, &def, WX_PHASE_ALL, &report, &err);
        wx_noise_report_free(&report.noise);
    }
    wx_scene_free(&scene);
    if (r == WX_BAD_INPUT && err.cause == want->cause) {
        return true;
    }
    fprintf(stderr, "%s: expected %s, got %d %s: %s\n", path, wx_cause_name(want->cause), (int)r,
            wx_cause_name(err.cause), err.message);
    return false;
}

// Runs `weathering COMMAND` on every bad input of `folder`: exit status 2, one
// message naming the file (and the line), and no output folder or file made; and
// in this process, the cause.
static int check_bad_folder(const char *folder, const char *command, int *checked)
{
    char *names[256];
    int count = list_names(folder, ".xml", names, 256);
    int failures = count > 0 ? 0 : 1; // a folder of bad inputs holds some
    for (int i = 0; i < count; ++i) {
        char path[4400];
        snprintf(path, sizeof path, "%s/%s", folder, names[i]);
        ensure_expectation want;
        if (!ensure_read_expectation(path, &want)) {
            failures++;
            continue;
        }
        if (!fails_in_process_for(path, &want, *checked + i)) {
            failures++;
        }
        int line = want.line;
        const char *substring = want.substring;
        char out_dir[4400];
        snprintf(out_dir, sizeof out_dir, "%s/bad_%d", ensure_tmpdir(), *checked + i);
        int status = ensure_shell(out, sizeof out, "%s/weathering %s %s --out %s -q",
                                  ensure_build_dir(), command, path, out_dir);
        char prefix[4500];
        if (line > 0) {
            snprintf(prefix, sizeof prefix, "weathering: %s:%d: ", path, line);
        } else {
            snprintf(prefix, sizeof prefix, "weathering: ");
        }
        struct stat st;
        bool ok = status == 2 && strncmp(out, prefix, strlen(prefix)) == 0 &&
                  ensure_contains(out, substring) && stat(out_dir, &st) != 0 &&
                  strchr(out, '\n') == out + strlen(out) - 1; // one line
        if (!ok) {
            fprintf(stderr,
                    "%s: expected `%s` to exit 2 with \"%s...%s\" and no output, got %d: %s\n",
                    path, command, prefix, substring, status, out);
            failures++;
        }
    }
    *checked += count > 0 ? count : 0;
    free_names(names, count);
    return failures;
}

// Every bad scene and map of tests/bad/ and tests/bad/run/ through the command line.
TEST(bad_inputs_exit_2_with_their_message)
{
    SLOW();
    char folder[4096];
    int checked = 0;
    snprintf(folder, sizeof folder, "%s/bad", ensure_tests_dir());
    int failures = check_bad_folder(folder, "simulate", &checked);
    snprintf(folder, sizeof folder, "%s/bad/run", ensure_tests_dir());
    failures += check_bad_folder(folder, "simulate", &checked);
    // Meshes that fail when imported: before any work, by info as by bake and run.
    snprintf(folder, sizeof folder, "%s/bad/mesh", ensure_tests_dir());
    const char *commands[3] = { "info", "bake", "run" };
    for (int c = 0; c < 3; ++c) {
        failures += check_bad_folder(folder, commands[c], &checked);
    }
    // Scenes that only the gather refuses: by info and run before any work.
    snprintf(folder, sizeof folder, "%s/bad/gather", ensure_tests_dir());
    failures += check_bad_folder(folder, "info", &checked);
    failures += check_bad_folder(folder, "run", &checked);
    ENSURE(checked >= 100);
    ENSURE(failures == 0);
}

TEST(memory_estimate_over_the_limit_is_refused_with_the_numbers)
{
    const char *dir = ensure_tmpdir();
    int status = ensure_shell(out, sizeof out,
                              "WX_MEMORY_AVAILABLE_MB=4 %s/weathering simulate "
                              "xml_scenes/thesis_box.xml --out %s/mem -q",
                              ensure_build_dir(), dir);
    ENSURE(status == 2);
    ENSURE(ensure_contains(out, "xml_scenes/thesis_box.xml:"));
    ENSURE(ensure_contains(out, "GiB of memory is available"));
    ENSURE(ensure_contains(out, "0.00391 GiB")); // 4 MiB
    char mem_dir[4200];
    snprintf(mem_dir, sizeof mem_dir, "%s/mem", dir);
    struct stat st;
    ENSURE(stat(mem_dir, &st) != 0); // refused before the output folder was made
    // info says so, and is not refused.
    status = ensure_shell(out, sizeof out,
                          "WX_MEMORY_AVAILABLE_MB=4 %s/weathering info xml_scenes/thesis_box.xml",
                          ensure_build_dir());
    ENSURE(status == 0);
    ENSURE(ensure_contains(out, "a run would be refused"));
    // With enough memory the same scene is accepted.
    status = ensure_shell(
        out, sizeof out, "WX_MEMORY_AVAILABLE_MB=1000 %s/weathering info xml_scenes/thesis_box.xml",
        ensure_build_dir());
    ENSURE(status == 0);
    ENSURE(!ensure_contains(out, "refused"));
}

// --- interrupted and killed runs ----------------------------------------------------

static bool copy_file(const char *from, const char *to)
{
    return ensure_shell(NULL, 0, "cp '%s' '%s'", from, to) == 0;
}

// A copy of the building scene, made slower (more steps), in `dir`/scene/.
static bool make_long_scene(const char *dir, char scene[PATH_MAX])
{
    char folder[PATH_MAX];
    snprintf(folder, sizeof folder, "%s/scene/meshes", dir);
    if (ensure_shell(NULL, 0, "mkdir -p '%s'", folder) != 0) {
        return false;
    }
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/building.obj", folder);
    if (!copy_file("xml_scenes/meshes/building.obj", path)) {
        return false;
    }
    snprintf(path, sizeof path, "%s/building.mtl", folder);
    if (!copy_file("xml_scenes/meshes/building.mtl", path)) {
        return false;
    }
    snprintf(scene, PATH_MAX, "%s/scene/building.xml", dir);
    return ensure_shell(NULL, 0,
                        "sed -e 's/steps=\"600\"/steps=\"6000\"/' -e 's/end=\"4\"/end=\"40\"/' "
                        "xml_scenes/building.xml > '%s'",
                        scene) == 0;
}

// A checksum of every file under `folder` except `skip` (names and contents).
static uint64_t tree_hash(const char *folder, const char *skip)
{
    char command[3 * PATH_MAX];
    snprintf(command, sizeof command,
             "cd '%s' && find . -path './%s' -prune -o -type f -print | sort | "
             "xargs -r cksum; find . -path './%s' -prune -o -print | sort",
             folder, skip, skip);
    FILE *pipe = popen(command, "r");
    if (pipe == NULL) {
        return 0;
    }
    uint64_t hash = 1469598103934665603ull;
    int c;
    while ((c = fgetc(pipe)) != EOF) {
        hash = (hash ^ (uint64_t)(unsigned char)c) * 1099511628211ull;
    }
    pclose(pipe);
    return hash;
}

static void sleep_s(double seconds)
{
    struct timespec ts = { (time_t)seconds, (long)((seconds - (double)(time_t)seconds) * 1e9) };
    while (nanosleep(&ts, &ts) != 0 && errno == EINTR) {
    }
}

// Starts `weathering run SCENE --out OUT` in the folder `cwd`, sends `sig` after
// `seconds` (counted from when OUT/`wait_for` exists, when it is not NULL: at
// most 120 s are waited for it) and returns the wait status (or -1).
static int run_and_signal(const char *cwd, const char *scene, const char *out_dir, int sig,
                          double seconds, const char *wait_for)
{
    char program[PATH_MAX];
    if (realpath(ensure_build_dir(), program) == NULL) {
        return -1;
    }
    strncat(program, "/weathering", sizeof program - strlen(program) - 1);
    pid_t pid = fork();
    if (pid < 0) {
        return -1;
    }
    if (pid == 0) {
        int null = open("/dev/null", O_WRONLY);
        if (null >= 0) {
            dup2(null, STDOUT_FILENO);
            dup2(null, STDERR_FILENO);
        }
        signal(SIGINT, SIG_DFL);
        if (chdir(cwd) != 0) {
            _exit(99);
        }
        execl(program, program, "run", scene, "--out", out_dir, "--threads", "2", "-q",
              (char *)NULL);
        _exit(98);
    }
    if (wait_for != NULL) {
        char path[PATH_MAX + 256];
        snprintf(path, sizeof path, "%s/%s", out_dir, wait_for);
        for (int i = 0; i < 1200 && access(path, F_OK) != 0; ++i) {
            sleep_s(0.1);
        }
    }
    sleep_s(seconds);
    kill(pid, sig);
    int status = 0;
    if (waitpid(pid, &status, 0) != pid) {
        return -1;
    }
    return status;
}

static bool ends_with(const char *name, const char *suffix)
{
    size_t n = strlen(name), k = strlen(suffix);
    return n >= k && strcmp(name + n - k, suffix) == 0;
}

// Every file under a final name reads back: EXRs in full, PNGs up to IEND, JSON.
// Counts the temporaries (".name.tmpPID") left in `temps`.
static bool outputs_read_back(const char *folder, int *files, int *temps)
{
    char *names[256];
    int count = list_names(folder, "", names, 256);
    bool ok = count >= 0;
    *files = 0;
    *temps = 0;
    for (int i = 0; i < count; ++i) {
        char path[PATH_MAX + 300];
        snprintf(path, sizeof path, "%s/%s", folder, names[i]);
        if (names[i][0] == '.') {
            *temps += 1;
            continue;
        }
        *files += 1;
        if (ends_with(names[i], ".exr")) {
            wx_image header;
            wx_error err;
            if (wx_exr_read_header(path, &header, &err) != WX_OK) {
                fprintf(stderr, "%s\n", err.message);
                ok = false;
                continue;
            }
            char wanted_names[WX_IMAGE_MAX_CHANNELS][WX_NAME_MAX];
            const char *wanted[WX_IMAGE_MAX_CHANNELS];
            int channels = header.channel_count;
            for (int c = 0; c < channels; ++c) {
                memcpy(wanted_names[c], header.channel_names[c], WX_NAME_MAX);
                wanted[c] = wanted_names[c];
            }
            wx_image_free(&header);
            wx_image image;
            if (wx_exr_read(path, wanted, channels, &image, &err) != WX_OK) {
                fprintf(stderr, "%s\n", err.message);
                ok = false;
            }
            wx_image_free(&image);
        } else if (ends_with(names[i], ".png")) {
            char *data = NULL;
            FILE *f = fopen(path, "rb");
            long size = 0;
            if (f != NULL && fseek(f, 0, SEEK_END) == 0) {
                size = ftell(f);
                data = size >= 20 ? malloc((size_t)size) : NULL;
                if (data != NULL && (fseek(f, 0, SEEK_SET) != 0 ||
                                     fread(data, 1, (size_t)size, f) != (size_t)size)) {
                    free(data);
                    data = NULL;
                }
            }
            if (f != NULL) {
                fclose(f);
            }
            if (data == NULL || memcmp(data, "\x89PNG", 4) != 0 ||
                memcmp(data + size - 8, "IEND", 4) != 0) {
                fprintf(stderr, "%s: not a complete PNG\n", path);
                ok = false;
            }
            free(data);
        } else {
            fprintf(stderr, "%s: unexpected file\n", path);
            ok = false;
        }
    }
    free_names(names, count);
    return ok;
}

// SIGINT at several moments of a run (bake, simulate): exit status 130, no
// temporary left, every output there reads back, the scene's folder unchanged
// and nothing written in the current folder.
TEST(sigint_stops_a_run_cleanly)
{
    SLOW();
    char dir[PATH_MAX];
    ENSURE(realpath(ensure_tmpdir(), dir) != NULL);
    char scene[PATH_MAX];
    ENSURE(make_long_scene(dir, scene));
    char cwd[PATH_MAX + 16];
    snprintf(cwd, sizeof cwd, "%s/cwd", dir);
    ENSURE(mkdir(cwd, 0777) == 0);
    char scene_dir[PATH_MAX + 16];
    snprintf(scene_dir, sizeof scene_dir, "%s/scene", dir);
    uint64_t before = tree_hash(scene_dir, "out");
    // Counted from when the output folder exists (the handlers are in place by
    // then, however loaded the machine): early in the bake; in the bake; and once
    // the bake wrote its last map (simulating).
    const double moments[] = { 0.1, 1.0, 1.0 };
    for (int k = 0; k < 3; ++k) {
        char out_dir[sizeof scene_dir + 32];
        snprintf(out_dir, sizeof out_dir, "%s/out/int%d", scene_dir, k);
        int status = run_and_signal(cwd, scene, out_dir, SIGINT, moments[k],
                                    k == 2 ? "out_normal.exr" : ".");
        ENSURE(WIFEXITED(status));
        ENSURE(WEXITSTATUS(status) == 130);
        int files = 0, temps = 0;
        ENSURE(outputs_read_back(out_dir, &files, &temps));
        ENSURE(temps == 0);
        if (k == 2) {
            ENSURE(files >= 2); // interrupted after the bake wrote its maps
        }
    }
    ENSURE(tree_hash(scene_dir, "out") == before);
    char *names[4];
    int in_cwd = list_names(cwd, "", names, 4);
    free_names(names, in_cwd);
    ENSURE(in_cwd == 0);
    // SIGTERM too: 128 + 15.
    char out_dir[PATH_MAX + 32];
    snprintf(out_dir, sizeof out_dir, "%s/out/term", scene_dir);
    int status = run_and_signal(cwd, scene, out_dir, SIGTERM, 0.5, ".");
    ENSURE(WIFEXITED(status) && WEXITSTATUS(status) == 143);
}

// SIGKILL at several moments: whatever has a final name reads back; the next
// run in that folder removes the temporaries the killed one left.
TEST(sigkill_never_leaves_a_torn_file)
{
    SLOW();
    char dir[PATH_MAX];
    ENSURE(realpath(ensure_tmpdir(), dir) != NULL);
    char scene[PATH_MAX];
    ENSURE(make_long_scene(dir, scene));
    char scene_dir[PATH_MAX + 16];
    snprintf(scene_dir, sizeof scene_dir, "%s/scene", dir);
    uint64_t before = tree_hash(scene_dir, "out");
    char out_dir[PATH_MAX + 32];
    snprintf(out_dir, sizeof out_dir, "%s/out/kill", scene_dir);
    const double moments[] = { 0.5, 1.0, 1.7, 2.5, 3.5 };
    for (int k = 0; k < 5; ++k) {
        // The same folder each time: later runs replace what earlier ones wrote.
        int status = run_and_signal(scene_dir, scene, out_dir, SIGKILL, moments[k], NULL);
        ENSURE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
        int files = 0, temps = 0;
        ENSURE(outputs_read_back(out_dir, &files, &temps));
    }
    ENSURE(tree_hash(scene_dir, "out") == before);
    // Whatever temporaries the killed runs left, their processes are gone: the
    // next run's preparation of the folder removes them.
    wx_scene loaded;
    wx_error err;
    ENSURE(wx_scene_load(scene, &loaded, &err) == WX_OK);
    wx_run_def opts;
    opts = wx_default_run_def(&loaded);
    snprintf(opts.out_dir, sizeof opts.out_dir, "%.4000s", out_dir);
    wx_result prepared = wx_output_prepare(&loaded, &opts, NULL, &err);
    wx_scene_free(&loaded);
    ENSURE(prepared == WX_OK);
    char *names[256];
    int count = list_names(out_dir, "", names, 256);
    int temps = 0;
    for (int i = 0; i < count; ++i) {
        temps += names[i][0] == '.';
    }
    free_names(names, count);
    ENSURE(count >= 0);
    ENSURE(temps == 0);
}

static bool only_mask_exr(const char *name, void *context)
{
    (void)context;
    return strcmp(name, "mask.exr") == 0;
}

TEST(stale_temporaries_of_dead_processes_are_removed)
{
    char dir[PATH_MAX];
    snprintf(dir, sizeof dir, "%s/stale", ensure_tmpdir());
    ENSURE(mkdir(dir, 0777) == 0);
    char mine[64];
    snprintf(mine, sizeof mine, ".mask.exr.tmp%ld", (long)getpid());
    ensure_write_file(dir, ".mask.exr.tmp999999999", "dead"); // above any pid_max
    ensure_write_file(dir, mine, "alive");
    ensure_write_file(dir, "mask.exr", "final");
    ensure_write_file(dir, ".hidden", "not a temporary");
    ensure_write_file(dir, ".x.tmpabc", "not a temporary");
    ensure_write_file(dir, ".draft.txt.tmp999999998", "a user's, not ours"); // dead pid too
    ENSURE(wx_temp_remove_stale(dir, only_mask_exr, NULL) == 1);
    char *names[8];
    int count = list_names(dir, "", names, 8);
    ENSURE(count == 5);
    bool dead_gone = true;
    for (int i = 0; i < count; ++i) {
        dead_gone = dead_gone && strcmp(names[i], ".mask.exr.tmp999999999") != 0;
    }
    free_names(names, count);
    ENSURE(dead_gone);
}

// The registry behind the interrupt handler: a temporary being written is
// removed by wx_temp_remove_all, a committed one is forgotten.
TEST(interrupt_removes_only_unfinished_temporaries)
{
    const char *dir = ensure_tmpdir();
    char final_a[PATH_MAX], final_b[PATH_MAX];
    snprintf(final_a, sizeof final_a, "%s/a.exr", dir);
    snprintf(final_b, sizeof final_b, "%s/b.exr", dir);
    char tmp_a[WX_PATH_MAX], tmp_b[WX_PATH_MAX];
    wx_temp_path(final_a, tmp_a);
    wx_temp_path(final_b, tmp_b);
    ENSURE(tmp_a[strlen(dir) + 1] == '.');
    FILE *f = fopen(tmp_a, "wb");
    ENSURE(f != NULL);
    fputs("a", f);
    fclose(f);
    f = fopen(tmp_b, "wb");
    ENSURE(f != NULL);
    fputs("b", f);
    fclose(f);
    wx_error err;
    ENSURE(wx_atomic_commit(tmp_b, final_b, &err) == WX_OK);
    wx_temp_remove_all();
    ENSURE(access(tmp_a, F_OK) != 0);  // unfinished: removed
    ENSURE(access(final_b, F_OK) == 0); // committed: kept
    ENSURE(access(final_a, F_OK) != 0);
    // Many temporaries, more than the registry's slots, some abandoned.
    for (int i = 0; i < 200; ++i) {
        char name[PATH_MAX + 32], tmp[WX_PATH_MAX];
        snprintf(name, sizeof name, "%s/many%d.exr", dir, i);
        wx_temp_path(name, tmp);
        if (i % 2 == 0) {
            wx_temp_forget(tmp);
        }
    }
    char last[PATH_MAX + 32], tmp_last[WX_PATH_MAX];
    snprintf(last, sizeof last, "%s/last.exr", dir);
    wx_temp_path(last, tmp_last);
    f = fopen(tmp_last, "wb");
    ENSURE(f != NULL);
    fclose(f);
    wx_temp_remove_all();
    ENSURE(access(tmp_last, F_OK) != 0);
}

// A run whose output folder holds the scene's own maps under the names it would
// write: refused with status 2, every input byte for byte unchanged.
TEST(an_input_is_never_overwritten)
{
    const char *dir = ensure_tmpdir();
    int status = ensure_shell(
        out, sizeof out,
        "set -e; mkdir -p %s/inputs; cd %s/inputs; m=$OLDPWD/maps/thesis_box_; "
        "for c in front top; do for k in depth normal impact dirt; do "
        "cp $m${c}_$k.exr ${c}_$k.exr; done; done; "
        "cp ${m}out_depth.exr out_depth.exr; cp ${m}out_normal.exr out_normal.exr; "
        "sed -e 's|../maps/thesis_box_||g' $OLDPWD/xml_scenes/thesis_box.xml > scene.xml; "
        "cksum * > ../inputs.sum",
        dir, dir);
    ENSURE(status == 0);
    status =
        ensure_shell(out, sizeof out, "%s/weathering run %s/inputs/scene.xml --out %s/inputs -q",
                     ensure_build_dir(), dir, dir);
    ENSURE(status == 2);
    ENSURE(ensure_contains(out, "front_dirt.exr: is an input of scene"));
    ENSURE(ensure_shell(out, sizeof out, "cd %s/inputs && cksum * | cmp - ../inputs.sum", dir) ==
           0);
    char inputs[PATH_MAX];
    snprintf(inputs, sizeof inputs, "%s/inputs", dir);
    char *names[32];
    int count = list_names(inputs, "", names, 32);
    free_names(names, count);
    ENSURE(count == 11); // nothing added: no temporary, no mask
}


// Issue 24: output names of 244 to 255 characters passed and failed after all
// the work with "File name too long" (exit 1), the temporary ".NAME.tmpPID"
// being 12 characters longer. 243 is the longest a run writes: a mask of 243
// characters (its preview too: BASE.png) is written; 244 is refused before any
// folder, and so is a --stats file of 244.
TEST(output_names_fit_the_file_system_with_their_temporaries)
{
    const char *dir = ensure_tmpdir();
    char name243[WX_OUTPUT_FILE_NAME_MAX + 1], name244[WX_OUTPUT_FILE_NAME_MAX + 2];
    memset(name243, 'n', sizeof name243 - 5);
    memcpy(name243 + sizeof name243 - 5, ".exr", 5);
    memset(name244, 'n', sizeof name244 - 5);
    memcpy(name244 + sizeof name244 - 5, ".exr", 5);
    ENSURE(strlen(name243) == 243 && strlen(name244) == 244);
    for (int k = 0; k < 2; ++k) {
        const char *file = k == 0 ? name243 : name244;
        int status = ensure_shell(
            out, sizeof out,
            "set -e; mkdir -p %s/names%d; sed -e \"s|\\.\\./maps/|$PWD/maps/|\" -e "
            "'s|thesis_box_mask.exr|%s|' xml_scenes/thesis_box.xml > %s/names%d/scene.xml",
            dir, k, file, dir, k);
        ENSURE(status == 0);
    }
    // 243: written, with its preview and no temporary left.
    int status = ensure_shell(out, sizeof out, "%s/weathering run %s/names0/scene.xml --out "
                              "%s/names0/out -q",
                              ensure_build_dir(), dir, dir);
    if (status != 0) {
        fprintf(stderr, "        %s", out);
    }
    ENSURE(status == 0);
    char path[PATH_MAX + 512];
    struct stat st;
    snprintf(path, sizeof path, "%s/names0/out/%s", dir, name243);
    ENSURE(stat(path, &st) == 0 && st.st_size > 0);
    snprintf(path, sizeof path, "%s/names0/out/%.239s.png", dir, name243);
    ENSURE(stat(path, &st) == 0 && st.st_size > 0);
    // 244: refused at the <OutputMap>'s line, nothing made.
    status = ensure_shell(out, sizeof out, "%s/weathering run %s/names1/scene.xml --out "
                          "%s/names1/out -q",
                          ensure_build_dir(), dir, dir);
    ENSURE(status == 2);
    ENSURE(ensure_contains(out, "names1/scene.xml:41: <OutputMap> file=\""));
    ENSURE(ensure_contains(out, "of 244 characters, over the 243 a run can write"));
    snprintf(path, sizeof path, "%s/names1/out", dir);
    ENSURE(stat(path, &st) != 0);
    // --stats of 244 characters: refused before any work; 243 written.
    char stats[2][WX_OUTPUT_FILE_NAME_MAX + 2];
    for (int k = 0; k < 2; ++k) {
        memset(stats[k], 's', (size_t)(WX_OUTPUT_FILE_NAME_MAX + k - 5));
        memcpy(stats[k] + WX_OUTPUT_FILE_NAME_MAX + k - 5, ".json", 6);
    }
    status = ensure_shell(out, sizeof out, "%s/weathering run %s/names0/scene.xml --out "
                          "%s/names2 -q --stats %s/%s",
                          ensure_build_dir(), dir, dir, dir, stats[1]);
    ENSURE(status == 2);
    ENSURE(ensure_contains(out, "a name of 244 characters, over the 243 a run can write"));
    snprintf(path, sizeof path, "%s/names2", dir);
    ENSURE(stat(path, &st) != 0);
    status = ensure_shell(out, sizeof out, "%s/weathering simulate %s/names0/scene.xml --out "
                          "%s/names2 -q --stats %s/%s",
                          ensure_build_dir(), dir, dir, dir, stats[0]);
    ENSURE(status == 0);
    snprintf(path, sizeof path, "%s/%s", dir, stats[0]);
    ENSURE(stat(path, &st) == 0 && st.st_size > 0);
}


// Issue 24: no output channel is ever written holding NaN or an infinity. The
// scene's amounts are checked when it is read (tests/bad/*_overflows_float.xml);
// what a map file brings is not: a dirt map holding FLT_MAX of two substances
// and a rule moving all of one into the other overflows single precision (b's
// amount and its record of the rules' result, 2 x 16 texels). The dirt map is
// then not written, and the command fails (exit 1) saying why.
TEST(no_output_is_written_non_finite)
{
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/nonfinite", ensure_tmpdir());
    ENSURE(mkdir(dir, 0777) == 0);
    static const char *const names[] = { "a.amount", "a.deposit", "a.erosion",
                                         "b.amount", "b.deposit", "b.erosion" };
    wx_image map;
    ENSURE(wx_image_alloc(&map, 4, 4, 6, names, NULL) == WX_OK);
    for (int t = 0; t < 16; ++t) {
        map.channels[0][t] = FLT_MAX;
        map.channels[3][t] = FLT_MAX;
    }
    char path[4400];
    snprintf(path, sizeof path, "%s/front_dirt_in.exr", dir);
    wx_error err;
    wx_result r = wx_exr_write(path, &map, &err);
    wx_image_free(&map);
    ENSURE(r == WX_OK);
    char maps[PATH_MAX];
    ENSURE(realpath("tests/data/map4.exr", maps) != NULL);
    char scene[16384];
    snprintf(scene, sizeof scene,
             "<Weathering>\n"
             "  <Substances><Substance name=\"a\"/><Substance name=\"b\"/></Substances>\n"
             "  <Ageing><Transfer from=\"a\" to=\"b\" rate=\"1\"/></Ageing>\n"
             "  <Collider><ProjectedMaps><Ortho cameraName=\"front\">\n"
             "    <WTCMatrix matrix=\"1 0 0 0  0 1 0 0  0 0 1 0  0 0 0 1\"/>\n"
             "    <DepthMap file=\"%s\"/><NormalMap file=\"%s\"/><ImpactMap file=\"%s\"/>\n"
             "    <DirtMap file=\"front_dirt_in.exr\"/>\n"
             "  </Ortho></ProjectedMaps></Collider>\n"
             "</Weathering>\n",
             maps, maps, maps);
    ensure_write_file(dir, "scene.xml", scene);
    int status = ensure_shell(out, sizeof out,
                              "%s/weathering simulate %s/scene.xml --out %s/out -q",
                              ensure_build_dir(), dir, dir);
    if (status != 1) {
        fprintf(stderr, "        status %d: %s", status, out);
    }
    ENSURE(status == 1);
    ENSURE(ensure_contains(out, "front_dirt.exr: not written: channel b.amount holds +inf at "
                                "texel (0, 0), and 32 values in all are not finite numbers"));
    snprintf(path, sizeof path, "%s/out/front_dirt.exr", dir);
    struct stat st;
    ENSURE(stat(path, &st) != 0);
    snprintf(path, sizeof path, "%s/out", dir);
    char *left[8];
    // The refused run may not make its folder; when it does, it leaves it empty.
    int count = stat(path, &st) == 0 ? list_names(path, "", left, 8) : 0;
    free_names(left, count);
    ENSURE(count == 0); // no temporary either
}


// Out of memory in the bake (the framebuffer, the images) is exit status 1 with
// "out of memory", never a bad input nor "framebuffer is incomplete" (issue 13).
TEST(out_of_memory_in_the_bake_is_exit_1)
{
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
    SKIP("a sanitizer's shadow memory does not fit under ulimit -v");
#endif
    const char *dir = ensure_tmpdir();
    ENSURE(
        ensure_shell(out, sizeof out,
                     "mkdir -p %s/oom/meshes && cp xml_scenes/meshes/teapot.obj %s/oom/meshes/ && "
                     "sed -e 's/resolution=\"[0-9]*\"/resolution=\"4096\"/' "
                     "-e 's/width=\"1024\" height=\"1024\"/width=\"4096\" height=\"4096\"/' "
                     "xml_scenes/teapot.xml > %s/oom/big.xml",
                     dir, dir, dir) == 0);
    int failed = 0;
    const int limits_mb[] = { 900, 1200, 1500, 1800 };
    for (int k = 0; k < 4; ++k) {
        int status = ensure_shell(out, sizeof out,
                                  "ulimit -v %d; WX_MEMORY_AVAILABLE_MB=100000 %s/weathering bake "
                                  "%s/oom/big.xml --out %s/oom/out%d -q --threads 2",
                                  limits_mb[k] * 1024, ensure_build_dir(), dir, dir, k);
        if (status == 0) {
            continue;
        }
        failed++;
        if (status != 1 || !ensure_contains(out, "out of memory")) {
            fprintf(stderr, "        ulimit %d MiB: status %d: %s", limits_mb[k], status, out);
        }
        ENSURE(status == 1);
        ENSURE(ensure_contains(out, "out of memory"));
        ENSURE(!ensure_contains(out, "incomplete"));
    }
    ENSURE(failed >= 2);
}

// A full disk while a run bakes (a tmpfs too small for the maps): exit status 1
// naming the camera whose file did not fit, whether that file was written while
// the next camera rendered or at the end; nothing torn, no temporary left.
TEST(a_full_disk_in_the_bake_is_exit_1_naming_the_camera)
{
    SLOW();
    char dir[PATH_MAX];
    ENSURE(realpath(ensure_tmpdir(), dir) != NULL);
    // init's scene for the teapot at 256 texels: input cameras front, back, left,
    // right and top (four layers each), then the output camera. The space each
    // camera's files take on the tmpfs (whole pages), in the order they are written.
    static const char *const cameras[] = { "front", "back", "left", "right", "top", "shot" };
    ENSURE(ensure_shell(out, sizeof out,
                        "%s/weathering init xml_scenes/meshes/teapot.obj --resolution 256 "
                        "-o %s/teapot.xml -q && %s/weathering bake %s/teapot.xml --out %s/whole -q",
                        ensure_build_dir(), dir, ensure_build_dir(), dir, dir) == 0);
    long used[6] = { 0 };
    for (int c = 0; c < 6; ++c) {
        ENSURE(ensure_shell(out, sizeof out, "for f in %s/whole/%s_*.exr; do stat -c %%s $f; done",
                            dir, cameras[c]) == 0);
        for (char *line = out; *line != '\0'; line = strchr(line, '\n') + 1) {
            used[c] += (atol(line) + 4095) / 4096 * 4096;
            if (strchr(line, '\n') == NULL) {
                break;
            }
        }
        ENSURE(used[c] > 0);
    }
    // Mounted last: every check from here on unmounts it before it can fail.
    char mnt[PATH_MAX + 16];
    snprintf(mnt, sizeof mnt, "%s/full", dir);
    ENSURE(mkdir(mnt, 0777) == 0);
    if (ensure_shell(out, sizeof out, "mount -t tmpfs -o size=64k tmpfs %s", mnt) != 0) {
        SKIP("no tmpfs can be mounted here (needs root)");
    }
    // A disk that fills in the middle of the files of back (written while left
    // renders, its failure met when left's are handed over) and of top (written
    // while the output camera renders, met when the bake ends).
    const int fill[] = { 1, 4 };
    for (int k = 0; k < 2; ++k) {
        long size = used[fill[k]] / 2;
        for (int c = 0; c < fill[k]; ++c) {
            size += used[c];
        }
        size = (size / 4096 + 1) * 4096;
        if (ensure_shell(out, sizeof out, "mount -o remount,size=%ld %s", size, mnt) != 0) {
            ensure_shell(out, sizeof out, "umount %s", mnt);
            ENSURE(!"the tmpfs could not be resized");
        }
        char out_dir[sizeof mnt + 16];
        snprintf(out_dir, sizeof out_dir, "%s/o%d", mnt, k);
        int status = ensure_shell(out, sizeof out, "%s/weathering run %s/teapot.xml --out %s -q",
                                  ensure_build_dir(), dir, out_dir);
        char want[64];
        snprintf(want, sizeof want, "weathering: bake camera '%s': ", cameras[fill[k]]);
        bool ok = status == 1 && strncmp(out, want, strlen(want)) == 0 &&
                  ensure_contains(out, "No space left on device");
        if (!ok) {
            fprintf(stderr, "        %ld bytes: expected \"%s...\", status 1, got %d: %s", size,
                    want, status, out);
        }
        int files = 0, temps = 0;
        bool read_back = outputs_read_back(out_dir, &files, &temps);
        ensure_shell(out, sizeof out, "rm -rf %s", out_dir);
        if (!ok || !read_back || temps != 0) {
            ensure_shell(out, sizeof out, "umount %s", mnt);
        }
        ENSURE(ok);
        ENSURE(read_back);
        ENSURE(temps == 0);
    }
    ensure_shell(out, sizeof out, "umount %s", mnt);
}

int main(void)
{
    RUN(bad_inputs_exit_2_with_their_message);
    RUN(memory_estimate_over_the_limit_is_refused_with_the_numbers);
    RUN(stale_temporaries_of_dead_processes_are_removed);
    RUN(interrupt_removes_only_unfinished_temporaries);
    RUN(an_input_is_never_overwritten);
    RUN(output_names_fit_the_file_system_with_their_temporaries);
    RUN(no_output_is_written_non_finite);
    RUN(out_of_memory_in_the_bake_is_exit_1);
    RUN(a_full_disk_in_the_bake_is_exit_1_naming_the_camera);
    RUN(sigint_stops_a_run_cleanly);
    RUN(sigkill_never_leaves_a_torn_file);
    return ensure_summary();
}
