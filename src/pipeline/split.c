// split.c: every channel of an EXR as a one-channel file (split.h).
#include "pipeline/split.h"

#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "core/atomic_file.h"
#include "io/exr.h"
#include "model/image.h"
#include "model/naming.h"
#include "pipeline/outputs.h"
#include "pipeline/pipeline.h"

void wx_split_file_name(const char *base, const char *channel, char out[WX_OUTPUT_NAME_MAX])
{
    char name[WX_NAME_MAX];
    snprintf(name, sizeof name, "%s", channel);
    if (strlen(name) > 2) { // a channel named ".Y" keeps its name
        name[wx_channel_stem_length(name)] = '\0';
    }
    char joined[WX_OUTPUT_NAME_MAX];
    snprintf(joined, sizeof joined, "%s_%s", base, name);
    char plain[WX_OUTPUT_NAME_MAX - 4]; // room for ".exr"
    wx_default_out_name(joined, plain, sizeof plain);
    snprintf(out, WX_OUTPUT_NAME_MAX, "%s.exr", plain);
}

// The input's name without folder and extension, made plain.
static void input_base(const char *path, char *out, size_t cap)
{
    char raw[WX_OUTPUT_NAME_MAX];
    const char *slash = strrchr(path, '/');
    snprintf(raw, sizeof raw, "%s", slash != NULL ? slash + 1 : path);
    char *dot = strrchr(raw, '.');
    if (dot != NULL && dot != raw) {
        *dot = '\0';
    }
    wx_default_out_name(raw, out, cap);
}

// Every check before the first file: names that fit and differ, no file that
// is the input or is not a regular file.
static wx_result check_files(const char *input, const char *dir, const wx_image *in,
                             char (*files)[WX_OUTPUT_NAME_MAX], wx_error *err)
{
    struct stat input_st;
    if (stat(input, &input_st) != 0) {
        return wx_fail(err, WX_CAUSE_FILE_MISSING, "%s: not found", input);
    }
    for (int c = 0; c < in->channel_count; ++c) {
        if (strlen(files[c]) > WX_OUTPUT_FILE_NAME_MAX) { // with its temporary
            return wx_fail(err, WX_CAUSE_PATH_TOO_LONG,
                           "%s: channel '%s' would be written to a file name of %zu characters, "
                           "too long for the file system; nothing written",
                           input, in->channel_names[c], strlen(files[c]));
        }
        for (int d = 0; d < c; ++d) {
            if (strcmp(files[c], files[d]) == 0) {
                return wx_fail(err, WX_CAUSE_OUTPUT_CONFLICT,
                               "%s: channels '%s' and '%s' would both be written to %s; "
                               "nothing written",
                               input, in->channel_names[d], in->channel_names[c], files[c]);
            }
        }
        char path[WX_PATH_MAX];
        int n = snprintf(path, sizeof path, "%s/%s", dir, files[c]);
        if (n < 0 || n >= (int)sizeof path) {
            return wx_fail(err, WX_CAUSE_PATH_TOO_LONG, "%s/%s: path too long", dir, files[c]);
        }
        struct stat st;
        if (lstat(path, &st) != 0) {
            continue;
        }
        if (!S_ISREG(st.st_mode)) {
            return wx_fail(err, WX_CAUSE_OUTPUT_CONFLICT,
                           "%s: exists and is %s, where split writes channel '%s'; remove it "
                           "or choose another --out folder; nothing written",
                           path, wx_file_kind(st.st_mode), in->channel_names[c]);
        }
        if (st.st_dev == input_st.st_dev && st.st_ino == input_st.st_ino) {
            return wx_fail(err, WX_CAUSE_OUTPUT_CONFLICT,
                           "%s: is the input, where split would write channel '%s'; choose "
                           "another --out folder; nothing written",
                           path, in->channel_names[c]);
        }
    }
    return WX_OK;
}

wx_result wx_split_exr(const wx_split_def *def, wx_error *err)
{
    wx_image *in = calloc(1, sizeof *in);
    wx_image *one = calloc(1, sizeof *one);
    char(*files)[WX_OUTPUT_NAME_MAX] = calloc(WX_IMAGE_MAX_CHANNELS, sizeof *files);
    wx_result r = in != NULL && one != NULL && files != NULL
                      ? wx_exr_read_all(def->input, in, err)
                      : wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory");
    char dir[WX_PATH_MAX] = ".";
    const char *slash = strrchr(def->input, '/');
    if (def->out_dir != NULL) {
        snprintf(dir, sizeof dir, "%s", def->out_dir);
    } else if (slash != NULL) {
        int len = slash == def->input ? 1 : (int)(slash - def->input);
        snprintf(dir, sizeof dir, "%.*s", len, def->input);
    }
    char base[WX_OUTPUT_NAME_MAX];
    input_base(def->input, base, sizeof base);
    for (int c = 0; r == WX_OK && c < in->channel_count; ++c) {
        wx_split_file_name(base, in->channel_names[c], files[c]);
    }
    if (r == WX_OK) {
        r = check_files(def->input, dir, in, files, err);
    }
    char created[WX_PATH_MAX] = "";
    if (r == WX_OK) {
        r = wx_make_folders(dir, created, err);
    }
    static const char *const y[1] = { "Y" };
    for (int c = 0; r == WX_OK && c < in->channel_count; ++c) {
        char path[WX_PATH_MAX];
        snprintf(path, sizeof path, "%s/%s", dir, files[c]);
        r = wx_image_alloc(one, in->width, in->height, 1, y, err);
        if (r == WX_OK) {
            memcpy(one->channels[0], in->channels[c],
                   (size_t)in->width * (size_t)in->height * sizeof(float));
            r = wx_exr_write(path, one, err);
            wx_image_free(one);
        }
        if (r == WX_OK && def->on_written != NULL) {
            def->on_written(path, def->context);
        }
    }
    if (r != WX_OK) {
        wx_output_remove_empty(dir, created);
    }
    if (in != NULL) {
        wx_image_free(in);
    }
    free(in);
    free(one);
    free(files);
    return r;
}
