// scene_xml_checks.c: the checks that need the whole scene once every element
// is read: output names that clash with the maps, the mask, another texture,
// their frames or previews; names too long for a temporary; the amounts'
// worst case in single precision; per-surface rules against pre-rendered maps.
#include "io/scene_xml_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "model/naming.h"

// ---------------------------------------------------------------------------
// <Weathering> and the checks that need the whole scene

static const char *const rule_elements[] = {
    [WX_RULE_TRANSFER] = "Transfer", [WX_RULE_DECAY] = "Decay",   [WX_RULE_GROW] = "Grow",
    [WX_RULE_SEED] = "Seed",         [WX_RULE_SPREAD] = "Spread", [WX_RULE_CRACK] = "Crack",
    [WX_RULE_PEEL] = "Peel"
};

/// A surface's own rules need the bake to record which <Surface> each texel of
/// every input camera shows; maps the scene names were made elsewhere and do
/// not (docs/design.md section 9: pre-rendered maps have global rules only).
static wx_result check_surface_rules(parser *p)
{
    const wx_scene *s = p->scene;
    const wx_scene_camera *given = NULL;
    for (int c = 0; c < s->camera_count && given == NULL; ++c) {
        if (!s->cameras[c].is_output && wx_has_path(s->cameras[c].depth_path)) {
            given = &s->cameras[c];
        }
    }
    for (int m = 0; m < s->mesh_count && given != NULL; ++m) {
        for (int k = 0; k < s->meshes[m].surface_count; ++k) {
            const wx_surface *sf = &s->meshes[m].surfaces[k];
            if (sf->rule_count > 0) {
                const wx_rule *rule = &sf->rules[0];
                return fail_line(
                    p, rule->line, WX_CAUSE_BAD_SCENE,
                    "<%s> in <Surface material=\"%s\"> is a per-surface rule: the bake must "
                    "record which surface each texel shows, but input camera '%s' (line %d) has "
                    "pre-rendered maps; give it a <View> without maps so that bake makes them, "
                    "or move the rule to <Ageing>",
                    rule_elements[rule->kind], sf->material, given->name, given->line);
            }
        }
    }
    return WX_OK;
}

/// Whether `file` is the name of a map bake or simulate writes
/// (<camera>_<kind>.exr); then *camera and *kind say whose.
static bool map_named(const wx_scene *s, const char *file, int *camera, int *kind)
{
    for (int c = 0; c < s->camera_count; ++c) {
        for (int k = 0; k < WX_MAP_KINDS; ++k) {
            char name[128];
            wx_map_file_name(s->cameras[c].name, k, name, sizeof name);
            if (strcmp(name, file) == 0) {
                *camera = c;
                *kind = k;
                return true;
            }
        }
    }
    return false;
}

/// The mask must not take the name of a map that bake or simulate writes.
static wx_result check_output_name(parser *p)
{
    const wx_scene *s = p->scene;
    if (s->output_index < 0) {
        return WX_OK;
    }
    const wx_scene_camera *out = &s->cameras[s->output_index];
    int c, k;
    if (map_named(s, out->output_file, &c, &k)) {
        return fail_line(p, out->line, WX_CAUSE_BAD_SCENE,
                         "<OutputMap> file=\"%s\" is the name of camera '%s''s %s map in "
                         "the output folder; choose another",
                         out->output_file, s->cameras[c].name, wx_map_kind_name(k));
    }
    return WX_OK;
}

/// A file the gather writes with its image sequence and previews: the output
/// camera's mask or a <TextureMap> (docs/design.md sections 10 and 11).
typedef struct output_entry {
    const char *file;
    int every;
    const wx_scene_camera *camera; ///< the output camera for the mask, else NULL
    int line;
} output_entry;

/// The frame number N when `name` is BASE.NNNN.exr of `e`'s image sequence and
/// the run writes that frame (N a multiple of every, at most the iterations); else 0.
static int frame_of(const wx_scene *s, const char *name, const output_entry *e)
{
    size_t base = wx_output_base_length(e->file);
    size_t n = strlen(name);
    if (e->every <= 0 || n < base + 9 || strncmp(name, e->file, base) != 0 ||
        name[base] != '.' || strcmp(name + n - 4, ".exr") != 0) {
        return 0;
    }
    const char *digits = name + base + 1;
    size_t count = n - base - 5;
    long long frame = 0;
    for (size_t i = 0; i < count; ++i) {
        if (digits[i] < '0' || digits[i] > '9' || frame > SCENE_MAX_ITERATIONS) {
            return 0;
        }
        frame = frame * 10 + (digits[i] - '0');
    }
    char written[32];
    snprintf(written, sizeof written, "%04lld", frame);
    if (strlen(written) != count || strncmp(written, digits, count) != 0 || frame < 1 ||
        frame > s->iterations || frame % e->every != 0) {
        return 0;
    }
    return (int)frame;
}

/// "the <OutputMap> of output camera 'out' (line 12)" or "the <TextureMap> at line 30".
static void describe_output(const output_entry *e, char *out, size_t cap)
{
    if (e->camera != NULL) {
        snprintf(out, cap, "the <OutputMap> of output camera '%s' (line %d)", e->camera->name,
                 e->camera->line);
    } else {
        snprintf(out, cap, "the <TextureMap> at line %d", e->line);
    }
}

/// TextureMap `t` against an earlier output `e` (the mask or a TextureMap):
/// neither file, frame nor preview may be written twice.
static wx_result check_texture_against(parser *p, const output_entry *t, const output_entry *e)
{
    const wx_scene *s = p->scene;
    char other[128];
    describe_output(e, other, sizeof other);
    if (strcmp(t->file, e->file) == 0) {
        if (e->camera == NULL) {
            return fail_line(p, t->line, WX_CAUSE_DUPLICATE,
                             "<TextureMap> file=\"%s\" is used twice (first at line %d)",
                             t->file, e->line);
        }
        return fail_line(p, t->line, WX_CAUSE_BAD_SCENE,
                         "<TextureMap> file=\"%s\" is the file of %s; choose another", t->file,
                         other);
    }
    int frame = frame_of(s, t->file, e);
    if (frame > 0) {
        return fail_line(p, t->line, WX_CAUSE_BAD_SCENE,
                         "<TextureMap> file=\"%s\" is frame %d of the image sequence of '%s', "
                         "which %s writes with every=\"%d\"; choose another",
                         t->file, frame, e->file, other, e->every);
    }
    frame = frame_of(s, e->file, t);
    if (frame > 0) {
        return fail_line(p, t->line, WX_CAUSE_BAD_SCENE,
                         "<TextureMap> file=\"%s\" every=\"%d\" writes frame %d as '%s', the "
                         "file of %s; choose another",
                         t->file, t->every, frame, e->file, other);
    }
    char mine[WX_MAX_PREVIEWS][WX_OUTPUT_NAME_MAX];
    char theirs[WX_MAX_PREVIEWS][WX_OUTPUT_NAME_MAX];
    int n_mine = wx_preview_names(s, t->file, mine);
    int n_theirs = wx_preview_names(s, e->file, theirs);
    for (int i = 0; i < n_mine; ++i) {
        for (int k = 0; k < n_theirs; ++k) {
            if (strcmp(mine[i], theirs[k]) == 0) {
                return fail_line(p, t->line, WX_CAUSE_BAD_SCENE,
                                 "<TextureMap> file=\"%s\" writes the preview '%s', as %s "
                                 "(file=\"%s\") does; choose another",
                                 t->file, mine[i], other, e->file);
            }
        }
    }
    return WX_OK;
}

/// Every TextureMap writes files of its own (docs/design.md section 11): not a
/// map that bake or simulate writes, not the mask, not another TextureMap's,
/// nor their frames or previews.
static wx_result check_texture_names(parser *p)
{
    const wx_scene *s = p->scene;
    for (int i = 0; i < s->texture_count; ++i) {
        const wx_texture_map *tex = &s->textures[i];
        int c, k;
        if (map_named(s, tex->file, &c, &k)) {
            return fail_line(p, tex->line, WX_CAUSE_BAD_SCENE,
                             "<TextureMap> file=\"%s\" is the name of camera '%s''s %s "
                             "map in the output folder; choose another",
                             tex->file, s->cameras[c].name, wx_map_kind_name(k));
        }
        output_entry t = { .file = tex->file, .every = tex->every, .line = tex->line };
        if (s->output_index >= 0) {
            const wx_scene_camera *out = &s->cameras[s->output_index];
            output_entry mask = { .file = out->output_file, .every = out->every, .camera = out,
                                  .line = out->line };
            wx_result r = check_texture_against(p, &t, &mask);
            if (r != WX_OK) {
                return r;
            }
        }
        for (int j = 0; j < i; ++j) {
            const wx_texture_map *first = &s->textures[j];
            output_entry e = { .file = first->file, .every = first->every, .line = first->line };
            wx_result r = check_texture_against(p, &t, &e);
            if (r != WX_OK) {
                return r;
            }
        }
    }
    return WX_OK;
}

/// The longest name among the files an output writes, as model/naming.c names
/// them (docs/design.md sections 10 and 11): the file,
/// its previews (BASE.png, or BASE.preview.png for a file ending in .png, when
/// the scene has neither <Substances> nor <Masks>; else BASE_NAME.png per
/// substance and per mask) and its last frame BASE.NNNN.exr.
static size_t longest_output_name(const wx_scene *s, const char *file, int every,
                                  char longest[WX_OUTPUT_NAME_MAX])
{
    char name[WX_OUTPUT_NAME_MAX];
    snprintf(longest, WX_OUTPUT_NAME_MAX, "%s", file);
    if (!s->substances_declared && s->mask_count == 0) {
        wx_preview_name(file, name, sizeof name);
        if (strlen(name) > strlen(longest)) {
            memcpy(longest, name, sizeof name);
        }
    }
    for (int k = 0; k < s->substance_count + s->mask_count && s->substances_declared +
                                                                   s->mask_count > 0; ++k) {
        const char *channel = k < s->substance_count ? s->substances[k]
                                                      : s->masks[k - s->substance_count].name;
        wx_channel_preview_name(file, channel, name, sizeof name);
        if (strlen(name) > strlen(longest)) {
            memcpy(longest, name, sizeof name);
        }
    }
    int last = every > 0 ? s->iterations / every * every : 0;
    if (last > 0) {
        wx_frame_name(file, last, name, sizeof name);
        if (strlen(name) > strlen(longest)) {
            memcpy(longest, name, sizeof name);
        }
    }
    return strlen(longest);
}

/// Every file a run writes has a name its temporary ".NAME.tmpPID" can take
/// (WX_OUTPUT_FILE_NAME_MAX): a longer one failed with "File name too long"
/// after all the work (issue 24). Refused at the <OutputMap>'s or the
/// <TextureMap>'s line. A camera's maps (<camera>_normal.exr) always fit.
static wx_result check_output_name_lengths(parser *p)
{
    _Static_assert(sizeof(((wx_scene_camera *)0)->name) - 1 + sizeof "_normal.exr" - 1 <=
                       WX_OUTPUT_FILE_NAME_MAX,
                   "a camera's map names fit");
    const wx_scene *s = p->scene;
    int count = s->texture_count + (s->output_index >= 0 ? 1 : 0);
    for (int k = 0; k < count; ++k) {
        bool mask = k == s->texture_count;
        const char *file = mask ? s->cameras[s->output_index].output_file : s->textures[k].file;
        int every = mask ? s->cameras[s->output_index].every : s->textures[k].every;
        int line = mask ? (p->output_map_line > 0 ? p->output_map_line
                                                  : s->cameras[s->output_index].line)
                        : s->textures[k].line;
        // A UDIM texture's files are BASE.TTTT.exr, four digits each.
        char own[WX_OUTPUT_NAME_MAX];
        snprintf(own, sizeof own, "%s", file);
        if (!mask && s->textures[k].tiles == WX_TILES_UDIM) {
            wx_tile_name(file, 0, own, sizeof own);
        }
        char longest[WX_OUTPUT_NAME_MAX];
        size_t len = longest_output_name(s, own, every, longest);
        if (len > WX_OUTPUT_FILE_NAME_MAX) {
            return fail_line(p, line, WX_CAUSE_PATH_TOO_LONG,
                             "<%s> file=\"%.24s...\" (%zu characters) gives the output name "
                             "'%.24s...%s' of %zu characters, over the %d a run can write (its "
                             "temporary '.NAME.tmpPID' must fit the %d of a file name); shorten "
                             "file",
                             mask ? "OutputMap" : "TextureMap", file, strlen(file), longest,
                             longest + len - 16, len, WX_OUTPUT_FILE_NAME_MAX, WX_FILE_NAME_MAX);
        }
    }
    return WX_OK;
}

/// One amount's share of the worst case, per square metre and per texel.
typedef struct amount_share {
    double per_m2, per_texel;
    int line;
    char what[160];
} amount_share;

static void keep_largest(amount_share *largest, const amount_share *share)
{
    if (fmax(share->per_m2, share->per_texel) > fmax(largest->per_m2, largest->per_texel) ||
        largest->line == 0) {
        *largest = *share;
    }
}

/// The amounts' worst case fits single precision with room for sums over a map
/// (WX_AMOUNT_MAX, docs/reliability.md "Amounts"): what one texel of an input
/// camera can hold, per square metre and in all, if every particle of every
/// emitter, over every iteration, left its whole load on the smallest texel,
/// on top of every surface's initial amount and every Grow's amount over the
/// iterations (a substance may be transferred into another, so all add up;
/// a texel seen edge-on covers up to 1000 times its area, as the bake clamps
/// |N.view| at 1e-3). A scene over it is refused at the line of the amount that
/// gives the most: <Load amount="3e38"> wrote dirt maps holding +inf, <Grow
/// amount="3e38"> a mask holding +inf, with exit 0 (issue 24).
static wx_result check_amounts(parser *p)
{
    const wx_scene *s = p->scene;
    double a_min = INFINITY, a_max = 0.0;
    for (int c = 0; c < s->camera_count; ++c) {
        const wx_scene_camera *cam = &s->cameras[c];
        float fw = 0.0f, fh = 0.0f;
        if (cam->is_output || cam->camera.width <= 0 || cam->camera.height <= 0) {
            continue;
        }
        wx_camera_frame_size(&cam->camera, &fw, &fh);
        double area = ((double)fw / cam->camera.width) * ((double)fh / cam->camera.height);
        if (area > 0.0 && isfinite(area)) {
            a_min = fmin(a_min, area);
            a_max = fmax(a_max, area);
        }
    }
    if (a_max <= 0.0) {
        return WX_OK; // no input camera: refused elsewhere
    }
    const double edge_on = 1000.0; // 1 / the bake's smallest |N.view|
    double iterations = s->iterations > 1 ? s->iterations : 1;
    double per_m2 = 0.0, per_texel = 0.0;
    amount_share largest = { .line = 0 }, share;
    for (int64_t k = 0; k < p->source_count; ++k) {
        const amount_source *src = &p->sources[k];
        const char *substance = s->substances[src->substance];
        if (src->load) {
            const wx_emitter *e = &s->emitters[src->emitter];
            double particles = fmax(0.0, e->rate * (e->end - e->start)) * iterations;
            share.per_texel = particles * src->amount;
            share.per_m2 = share.per_texel / a_min;
            snprintf(share.what, sizeof share.what,
                     "%s=\"%g\" of substance '%s' (%.3g particles over %g iteration%s)",
                     src->element, src->amount, substance, particles, iterations,
                     iterations == 1.0 ? "" : "s");
        } else {
            share.per_m2 = edge_on * src->amount;
            share.per_texel = share.per_m2 * a_max;
            snprintf(share.what, sizeof share.what, "%s=\"%g\" of substance '%s'",
                     src->element, src->amount, substance);
        }
        share.line = src->line;
        per_m2 += share.per_m2;
        per_texel += share.per_texel;
        keep_largest(&largest, &share);
    }
    for (int m = -1; m < s->mesh_count; ++m) {
        for (int f = m < 0 ? -1 : 0; f < (m < 0 ? 0 : s->meshes[m].surface_count); ++f) {
            const wx_rule *rules = m < 0 ? s->rules : s->meshes[m].surfaces[f].rules;
            int count = m < 0 ? s->rule_count : s->meshes[m].surfaces[f].rule_count;
            for (int r = 0; r < count; ++r) {
                if (rules[r].kind != WX_RULE_GROW || !(rules[r].amount > 0.0f)) {
                    continue;
                }
                share.per_m2 = edge_on * iterations * rules[r].amount;
                share.per_texel = share.per_m2 * a_max;
                share.line = rules[r].line;
                snprintf(share.what, sizeof share.what,
                         "<Grow> amount=\"%g\" of substance '%s' (over %g iteration%s)",
                         (double)rules[r].amount, s->substances[rules[r].substance], iterations,
                         iterations == 1.0 ? "" : "s");
                per_m2 += share.per_m2;
                per_texel += share.per_texel;
                keep_largest(&largest, &share);
            }
        }
    }
    if (!(per_m2 > WX_AMOUNT_MAX || per_texel > WX_AMOUNT_MAX)) {
        return WX_OK;
    }
    return fail_line(p, largest.line, WX_CAUSE_BAD_VALUE,
                     "%s: in the worst case one texel would hold %.3g per square metre (%.3g "
                     "in all), over the %.0e that single-precision maps and masks hold with room "
                     "for their sums (every load on the smallest input texel, %.3g m^2, plus "
                     "every initial and grown amount; see docs/reliability.md); this amount "
                     "gives the most: lower it%s",
                     largest.what, per_m2, per_texel, WX_AMOUNT_MAX, a_min,
                     strstr(largest.what, "particles") != NULL
                         ? ", or the emitter's rate or duration, or the iterations"
                         : "");
}

/// The checks that need the whole scene, once every element is read, in this
/// order: the mask's and the textures' names, their lengths, the amounts, the
/// per-surface rules.
wx_result xml_check_scene(parser *p)
{
    wx_result r;
    if ((r = check_output_name(p)) != WX_OK || (r = check_texture_names(p)) != WX_OK ||
        (r = check_output_name_lengths(p)) != WX_OK || (r = check_amounts(p)) != WX_OK) {
        return r;
    }
    return check_surface_rules(p);
}
