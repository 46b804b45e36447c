// naming.c: the names of a run's files and channels (naming.h): map kinds,
// map files, frames, tiles, previews, the mask's and a texture's channels.
#include "model/naming.h"

#include <stdio.h>
#include <string.h>
#include <strings.h>

static const char *const map_kinds[WX_MAP_KINDS] = { "depth", "normal", "impact", "dirt" };

const char *wx_map_kind_name(int kind)
{
    return map_kinds[kind];
}

void wx_map_file_name(const char *camera, int kind, char *out, size_t cap)
{
    snprintf(out, cap, "%s_%s.exr", camera, map_kinds[kind]);
}

size_t wx_output_base_length(const char *file)
{
    size_t n = strlen(file);
    // In any case, as the scene reader accepts it: mask.EXR's frames are
    // mask.0001.exr and its previews mask.png and mask_rust.png alike.
    return n >= 4 && strcasecmp(file + n - 4, ".exr") == 0 ? n - 4 : n;
}

void wx_preview_name(const char *mask_name, char *out, size_t cap)
{
    const char *dot = strrchr(mask_name, '.');
    int stem = dot != NULL && dot != mask_name ? (int)(dot - mask_name) : (int)strlen(mask_name);
    bool is_png = dot != NULL && dot != mask_name && strcmp(dot, ".png") == 0;
    snprintf(out, cap, "%.*s%s", stem, mask_name, is_png ? ".preview.png" : ".png");
}

void wx_frame_name(const char *mask_name, int frame, char *out, size_t cap)
{
    size_t base = wx_output_base_length(mask_name);
    snprintf(out, cap, "%.*s.%04d.exr", (int)base, mask_name, frame);
}

size_t wx_channel_stem_length(const char *channel)
{
    size_t len = strlen(channel);
    if (len >= 2 && strcmp(channel + len - 2, ".Y") == 0) {
        len -= 2; // rust.Y -> rust
    }
    return len;
}

void wx_channel_preview_name(const char *mask_name, const char *channel, char *out, size_t cap)
{
    size_t base = wx_output_base_length(mask_name);
    size_t len = wx_channel_stem_length(channel); // rust.Y -> BASE_rust.png
    snprintf(out, cap, "%.*s_%.*s.png", (int)base, mask_name, (int)len, channel);
}

void wx_tile_name(const char *file, int udim, char *out, size_t cap)
{
    size_t base = wx_output_base_length(file);
    snprintf(out, cap, "%.*s.%04d.exr", (int)base, file, WX_UDIM_FIRST + udim);
}

int wx_mask_channels(const wx_scene *scene, char names[][WX_NAME_MAX])
{
    if (!scene->substances_declared && scene->mask_count == 0) {
        snprintf(names[0], WX_NAME_MAX, "Y");
        return 1;
    }
    int n = 0;
    for (int s = 0; s < scene->substance_count; ++s) {
        snprintf(names[n++], WX_NAME_MAX, "%s.Y", scene->substances[s]);
    }
    for (int m = 0; m < scene->mask_count; ++m) {
        snprintf(names[n++], WX_NAME_MAX, "%s.Y", scene->masks[m].name);
    }
    return n;
}

int wx_texture_channels(const wx_scene *scene, char names[][WX_NAME_MAX])
{
    int n = wx_mask_channels(scene, names);
    snprintf(names[n], WX_NAME_MAX, "seen");
    return n + 1;
}

int wx_preview_names(const wx_scene *scene, const char *file, char names[][WX_OUTPUT_NAME_MAX])
{
    char channels[WX_MAX_PREVIEWS][WX_NAME_MAX];
    int n = wx_mask_channels(scene, channels);
    if (n == 1) {
        wx_preview_name(file, names[0], WX_OUTPUT_NAME_MAX);
        return 1;
    }
    for (int c = 0; c < n; ++c) {
        wx_channel_preview_name(file, channels[c], names[c], WX_OUTPUT_NAME_MAX);
    }
    return n;
}

bool wx_texture_writes_frame(const wx_texture_map *t, int frame)
{
    return frame == 0 || (t->every > 0 && frame % t->every == 0);
}

bool wx_frame_wanted(const wx_scene *scene, int frame)
{
    if (scene->output_index >= 0 && scene->output_index < scene->camera_count) {
        int every = scene->cameras[scene->output_index].every;
        if (frame == 0 || (every > 0 && frame % every == 0)) {
            return true;
        }
    }
    for (int t = 0; t < scene->texture_count; ++t) {
        if (wx_texture_writes_frame(&scene->textures[t], frame)) {
            return true;
        }
    }
    return false;
}
