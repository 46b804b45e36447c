// test_split.c: `weathering split` (src/pipeline/split.c) on hostile and
// careless files (issue 24): channel names become file names only through the
// scene-name rule, nothing is written outside the output folder or onto the
// input, and every conflict is refused before the first file is written.
#define _XOPEN_SOURCE 700 // realpath
#include <dirent.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <openexr.h>

#include "ensure.h"
#include "run_fixture.h"
#include "io/exr.h"
#include "model/image.h"
#include "pipeline/split.h"

// Writes a 2 x 2 EXR `dir`/`name` whose channels are `names`, channel c
// holding c + 1 everywhere.
static bool write_exr(const char *dir, const char *name, const char *const *names, int count)
{
    char path[PATH_MAX + 256];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    wx_image image;
    wx_error err;
    memset(&image, 0, sizeof image);
    if (wx_image_alloc(&image, 2, 2, count, names, &err) != WX_OK) {
        return false;
    }
    for (int c = 0; c < count; ++c) {
        for (int t = 0; t < 4; ++t) {
            image.channels[c][t] = (float)(c + 1);
        }
    }
    bool ok = wx_exr_write(path, &image, &err) == WX_OK;
    if (!ok) {
        fprintf(stderr, "        %s\n", err.message);
    }
    wx_image_free(&image);
    return ok;
}

// How many entries `dir` holds (without . and ..); -1 when it does not exist.
static int entries(const char *dir)
{
    DIR *d = opendir(dir);
    if (d == NULL) {
        return -1;
    }
    int n = 0;
    for (struct dirent *e = readdir(d); e != NULL; e = readdir(d)) {
        n += strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
    }
    closedir(d);
    return n;
}

// A new empty folder NAME in the tests' temporary folder.
static const char *fresh_dir(const char *name)
{
    static char dir[PATH_MAX];
    snprintf(dir, sizeof dir, "%s/%s", ensure_tmpdir(), name);
    mkdir(dir, 0777);
    return dir;
}

static bool exists(const char *dir, const char *name)
{
    char path[PATH_MAX + 512];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    struct stat st;
    return lstat(path, &st) == 0;
}

// The rule, name by name: ".Y" dropped, '/', control characters and leading
// dots replaced.
TEST(channel_names_become_plain_file_names)
{
    char f[WX_OUTPUT_NAME_MAX];
    wx_split_file_name("mask", "rust.Y", f);
    ENSURE(strcmp(f, "mask_rust.exr") == 0);
    wx_split_file_name("mask", "Y", f);
    ENSURE(strcmp(f, "mask_Y.exr") == 0);
    wx_split_file_name("mask", "old/../../../../outside/v/k", f);
    ENSURE(strcmp(f, "mask_old_.._.._.._.._outside_v_k.exr") == 0);
    wx_split_file_name("mask", "a\x01\nb", f);
    ENSURE(strcmp(f, "mask_a__b.exr") == 0);
    wx_split_file_name("..", "x", f);
    ENSURE(strchr(f, '/') == NULL && f[0] != '.');
}

// A channel named to climb out through an existing folder BASE_old stays a
// file inside the folder; one named to land on the input does not replace it.
TEST(slashes_and_dots_never_leave_the_folder)
{
    const char *dir = fresh_dir("climb");
    char work[PATH_MAX + 16], outside[PATH_MAX + 16];
    snprintf(work, sizeof work, "%s/a/b/c", dir);
    ENSURE(ensure_shell(NULL, 0, "mkdir -p '%s/m_old' '%s/outside/v'", work, dir) == 0);
    snprintf(outside, sizeof outside, "%s/outside/v", dir);
    static const char *const names[] = { "old/../../../../outside/v/k", "old/../m", "Y" };
    ENSURE(write_exr(work, "m.exr", names, 3));
    char input[PATH_MAX + 32];
    snprintf(input, sizeof input, "%s/m.exr", work);
    char *before = ensure_read_file(input);
    ENSURE(weathering_in(work, "split m.exr", true) == 0);
    ENSURE(entries(outside) == 0);
    ENSURE(exists(work, "m_old_.._.._.._.._outside_v_k.exr"));
    ENSURE(exists(work, "m_old_.._m.exr"));
    ENSURE(exists(work, "m_Y.exr"));
    ENSURE(entries(work) == 5); // the input, the folder m_old and three files
    char *after = ensure_read_file(input);
    ENSURE(before != NULL && after != NULL && strcmp(before, after) == 0);
    free(before);
    free(after);
    // Control characters never reach a file name or stdout.
    static const char *const control[] = { "a\x1b[31mred", "b\rc" };
    ENSURE(write_exr(work, "k.exr", control, 2));
    ENSURE(weathering_in(work, "split k.exr --out plain", true) == 0);
    ENSURE(exists(work, "plain/k_a__31mred.exr") && exists(work, "plain/k_b_c.exr"));
    for (const char *c = out; *c != '\0'; ++c) {
        ENSURE(*c == '\n' || (unsigned char)*c >= 0x20);
    }
}

// Conflicts are refused with exit 2 before the first file is written.
TEST(conflicts_are_refused_before_any_file)
{
    const char *dir = fresh_dir("conflicts");
    // Two channels, one file.
    static const char *const twins[] = { "a", "dirt", "dirt.Y" };
    ENSURE(write_exr(dir, "t.exr", twins, 3));
    ENSURE(weathering_in(dir, "split t.exr --out twins", false) == 2);
    ENSURE(strstr(out, "'dirt' and 'dirt.Y' would both be written to t_dirt.exr") != NULL);
    ENSURE(entries(dir) == 1 && !exists(dir, "twins"));
    // The input itself: s.exr's channel "x" of a file named s_x.exr.
    static const char *const self[] = { "a", "x" };
    ENSURE(write_exr(dir, "s_x.exr", self, 2));
    ENSURE(ensure_shell(NULL, 0, "cd '%s' && ln s_x.exr s.exr", dir) == 0);
    ENSURE(weathering_in(dir, "split s.exr", false) == 2);
    ENSURE(strstr(out, "is the input") != NULL && !exists(dir, "s_a.exr"));
    // A symbolic link, a folder where a file would go.
    static const char *const two[] = { "a", "b" };
    ENSURE(write_exr(dir, "l.exr", two, 2));
    ENSURE(ensure_shell(NULL, 0, "cd '%s' && ln -s /tmp/elsewhere.exr l_b.exr && mkdir f_b",
                        dir) == 0);
    ENSURE(weathering_in(dir, "split l.exr", false) == 2);
    ENSURE(strstr(out, "l_b.exr: exists and is a symbolic link") != NULL);
    ENSURE(!exists(dir, "l_a.exr"));
    ENSURE(ensure_shell(NULL, 0, "cd '%s' && cp l.exr f.exr && mkdir f_b.exr", dir) == 0);
    ENSURE(weathering_in(dir, "split f.exr", false) == 2);
    ENSURE(strstr(out, "f_b.exr: exists and is a folder") != NULL && !exists(dir, "f_a.exr"));
    // A name too long for the file system, with its temporary.
    char base[300];
    memset(base, 'n', 240); // BASE_a.exr: 246 characters, its temporary 258
    strcpy(base + 240, ".exr");
    ENSURE(write_exr(dir, base, two, 2));
    char args[400];
    snprintf(args, sizeof args, "split %s", base);
    ENSURE(weathering_in(dir, args, false) == 2);
    ENSURE(strstr(out, "too long for the file system") != NULL);
}

// `--out` to a missing folder makes it, as every command does; a file that
// is not an EXR is bad input.
TEST(out_folder_is_made_and_bad_files_are_exit_2)
{
    const char *dir = fresh_dir("out");
    static const char *const two[] = { "a.Y", "b.Y" };
    ENSURE(write_exr(dir, "m.exr", two, 2));
    ENSURE(weathering_in(dir, "split m.exr --out new/deeper", true) == 0);
    ENSURE(exists(dir, "new/deeper/m_a.exr") && exists(dir, "new/deeper/m_b.exr"));
    ensure_write_file(dir, "not.exr", "hello");
    ENSURE(weathering_in(dir, "split not.exr --out made", false) == 2);
    ENSURE(strstr(out, "not.exr") != NULL && !exists(dir, "made"));
    ENSURE(weathering_in(dir, "split missing.exr", false) == 2);
}

// A channel name longer than the program keeps (63 characters) is refused
// with its length, not taken for a missing or a twice-asked channel. Written
// here with OpenEXR's long names, as other programs may.
TEST(long_channel_names_are_refused_clearly)
{
    const char *dir = fresh_dir("long");
    char path[PATH_MAX + 16];
    snprintf(path, sizeof path, "%s/long.exr", dir);
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_context_t ctx = NULL;
    ENSURE(exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init) == EXR_ERR_SUCCESS);
    int part = 0;
    exr_add_part(ctx, "", EXR_STORAGE_SCANLINE, &part);
    exr_initialize_required_attr_simple(ctx, part, 1, 1, EXR_COMPRESSION_NONE);
    exr_set_longname_support(ctx, 1);
    char name[80];
    memset(name, 'c', 70);
    name[70] = '\0';
    ENSURE(exr_add_channel(ctx, part, name, EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1) ==
           EXR_ERR_SUCCESS);
    ENSURE(exr_write_header(ctx) == EXR_ERR_SUCCESS);
    exr_chunk_info_t cinfo;
    exr_encode_pipeline_t encoder;
    float value = 1.0f;
    ENSURE(exr_write_scanline_chunk_info(ctx, part, 0, &cinfo) == EXR_ERR_SUCCESS);
    ENSURE(exr_encoding_initialize(ctx, part, &cinfo, &encoder) == EXR_ERR_SUCCESS);
    encoder.channels[0].encode_from_ptr = (const uint8_t *)&value;
    encoder.channels[0].user_pixel_stride = 4;
    encoder.channels[0].user_line_stride = 4;
    ENSURE(exr_encoding_choose_default_routines(ctx, part, &encoder) == EXR_ERR_SUCCESS);
    ENSURE(exr_encoding_run(ctx, part, &encoder) == EXR_ERR_SUCCESS);
    exr_encoding_destroy(ctx, &encoder);
    ENSURE(exr_finish(&ctx) == EXR_ERR_SUCCESS);
    ENSURE(weathering_in(dir, "split long.exr", false) == 2);
    ENSURE(strstr(out, "long.exr: channel 1's name has 70 characters, more than the 63") != NULL);
    ENSURE(entries(dir) == 1);
}

int main(void)
{
    RUN(channel_names_become_plain_file_names);
    RUN(slashes_and_dots_never_leave_the_folder);
    RUN(conflicts_are_refused_before_any_file);
    RUN(out_folder_is_made_and_bad_files_are_exit_2);
    RUN(long_channel_names_are_refused_clearly);
    return ensure_summary();
}
