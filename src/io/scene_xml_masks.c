// scene_xml_masks.c: <Masks> (docs/design.md section 12): the derived masks
// (Accessibility, Exposure, Curvature, Height, Noise) and their
// combinations, in document order.
#include "io/scene_xml_internal.h"

#include <stddef.h>
#include <stdio.h>
#include <string.h>

// ---------------------------------------------------------------------------
// <Masks> (docs/design.md section 12): derived masks, in document order

#define MASK_NAME                                                                            \
    { "name", T_TEXT, offsetof(wx_mask_def, name), .size = sizeof(((wx_mask_def *)0)->name), \
      .required = true }

static const attr_spec accessibility_attrs[] = {
    MASK_NAME,
    { "rays", T_INT, offsetof(wx_mask_def, rays), .lo = 1, .hi = SCENE_MAX_RAYS },
    { "distance", T_FLOAT, offsetof(wx_mask_def, distance), .range = R_POSITIVE },
};

static const attr_spec exposure_attrs[] = {
    MASK_NAME,
    { "elevation", T_FLOAT, offsetof(wx_mask_def, elevation), .range = R_ELEVATION },
    { "azimuth", T_FLOAT, offsetof(wx_mask_def, azimuth), .range = R_FINITE },
    { "sideWeight", T_FLOAT, offsetof(wx_mask_def, side_weight), .range = R_NONNEG },
    { "sideElevation", T_FLOAT, offsetof(wx_mask_def, side_elevation), .range = R_FINITE },
    { "sideSpread", T_FLOAT, offsetof(wx_mask_def, side_spread), .range = R_FINITE },
};

// radius 0 (the default): 4 texels of the target, chosen by the program.
static const attr_spec curvature_attrs[] = {
    MASK_NAME,
    { "radius", T_FLOAT, offsetof(wx_mask_def, radius), .range = R_NONNEG },
};

enum { HT_NAME, HT_MIN, HT_MAX }; // bits of `present`

// min, max absent: the geometry's bounds, known only when the maps are.
static const attr_spec height_attrs[] = {
    [HT_NAME] = MASK_NAME,
    [HT_MIN] = { "min", T_FLOAT, offsetof(wx_mask_def, min), .range = R_FINITE },
    [HT_MAX] = { "max", T_FLOAT, offsetof(wx_mask_def, max), .range = R_FINITE },
};

static const attr_spec noise_attrs[] = {
    MASK_NAME,
    { "frequency", T_FLOAT, offsetof(wx_mask_def, frequency), .range = R_POSITIVE },
    { "octaves", T_INT, offsetof(wx_mask_def, octaves), .lo = 1, .hi = WX_NOISE_MAX_OCTAVES },
    { "gain", T_FLOAT, offsetof(wx_mask_def, gain), .range = R_UNIT },
    { "seed", T_UINT64, offsetof(wx_mask_def, noise_seed), .range = R_FINITE },
};

static const attr_spec combine_attrs[] = {
    MASK_NAME,
    { "scale", T_FLOAT, offsetof(wx_mask_def, scale), .range = R_FINITE },
};

/// The index of the mask called `name` among those defined so far, or -1.
static int find_mask(const wx_scene *s, const char *name)
{
    for (int i = 0; i < s->mask_count; ++i) {
        if (strcmp(s->masks[i].name, name) == 0) {
            return i;
        }
    }
    return -1;
}

/// A mask's name: a substance-like name, not Y or seen, unique among the masks
/// and the substances (one namespace: both are channels NAME.Y).
static wx_result check_mask_name(parser *p, const xmlNode *node, const char *name)
{
    const wx_scene *s = p->scene;
    if (!xml_is_substance_name(name)) {
        return fail(p, node, WX_CAUSE_BAD_VALUE,
                    "<%s> name=\"%s\" must be letters, digits and '_', starting with a letter",
                    name_of(node), name);
    }
    if (strcmp(name, "Y") == 0 || strcmp(name, "seen") == 0) {
        return fail(p, node, WX_CAUSE_BAD_VALUE,
                    "<%s> name=\"%s\" is reserved (Y and seen name mask channels)",
                    name_of(node), name);
    }
    int k = wx_scene_substance(s, name);
    if (k >= 0 && !s->substances_declared) {
        return fail(p, node, WX_CAUSE_DUPLICATE,
                    "mask name '%s' is the name of the default substance (the scene has no "
                    "<Substances>): masks and substances share one namespace",
                    name);
    }
    if (k >= 0) {
        return fail(p, node, WX_CAUSE_DUPLICATE,
                    "mask name '%s' is the name of substance '%s' (declared at line %d): masks "
                    "and substances share one namespace",
                    name, name, p->substance_lines[k]);
    }
    k = find_mask(s, name);
    if (k >= 0) {
        return fail(p, node, WX_CAUSE_DUPLICATE, "mask name '%s' is used twice (first at line %d)",
                    name, s->masks[k].line);
    }
    return WX_OK;
}

/// A <Combine>'s <Term> children.
typedef struct combine_state {
    wx_mask_def *mask;      ///< the Combine, not yet counted in wx_scene.mask_count
    const xmlNode *combine; ///< its element
} combine_state;

typedef struct term_def {
    char mask[SCENE_REF_MAX], substance[SCENE_REF_MAX];
    float constant, weight, offset, steepness, age;
} term_def;

// Bits of `present`.
enum { TM_MASK, TM_SUBSTANCE, TM_CONSTANT, TM_WEIGHT, TM_OFFSET, TM_STEEPNESS, TM_AGE };

static const attr_spec term_attrs[] = {
    [TM_MASK] = { "mask", T_TEXT, offsetof(term_def, mask), .size = SCENE_REF_MAX },
    [TM_SUBSTANCE] = { "substance", T_TEXT, offsetof(term_def, substance),
                       .size = SCENE_REF_MAX },
    [TM_CONSTANT] = { "constant", T_FLOAT, offsetof(term_def, constant), .range = R_FINITE },
    [TM_WEIGHT] = { "weight", T_FLOAT, offsetof(term_def, weight), .range = R_FINITE },
    [TM_OFFSET] = { "offset", T_FLOAT, offsetof(term_def, offset), .range = R_FINITE },
    [TM_STEEPNESS] = { "steepness", T_FLOAT, offsetof(term_def, steepness), .range = R_NONNEG },
    [TM_AGE] = { "age", T_FLOAT, offsetof(term_def, age), .range = R_FINITE },
};

/// The line of the element called `name` at or after `from` among its
/// siblings (a mask defined later in <Masks>), or 0.
static int later_mask_line(const xmlNode *from, const char *name)
{
    for (const xmlNode *n = from; n != NULL; n = n->next) {
        if (n->type != XML_ELEMENT_NODE || n->ns != NULL) {
            continue;
        }
        xmlChar *value = xmlGetNoNsProp(n, (const xmlChar *)"name");
        bool same = value != NULL && strcmp((const char *)value, name) == 0;
        xmlFree(value);
        if (same) {
            return line_of(n);
        }
    }
    return 0;
}

/// The mask a <Term mask=...> names: one defined before its <Combine>.
static wx_result find_term_mask(parser *p, const xmlNode *node, const combine_state *st,
                                const char *name, int *index)
{
    const wx_scene *s = p->scene;
    *index = find_mask(s, name);
    if (*index >= 0) {
        return WX_OK;
    }
    if (strcmp(st->mask->name, name) == 0) {
        return fail(p, node, WX_CAUSE_BAD_SCENE,
                    "<Term> mask=\"%s\" names its own <Combine> (line %d): a term names only "
                    "masks defined before its <Combine>",
                    name, st->mask->line);
    }
    int later = later_mask_line(st->combine->next, name);
    if (later > 0) {
        return fail(p, node, WX_CAUSE_BAD_SCENE,
                    "<Term> mask=\"%s\" names a mask defined after this <Combine>, at line %d: a "
                    "term names only masks defined before its <Combine>",
                    name, later);
    }
    char list[WX_MAX_MASKS * (WX_SUBSTANCE_NAME_MAX + 2) + 1] = "";
    for (int k = 0; k < s->mask_count; ++k) {
        wx_list_append(list, sizeof list, s->masks[k].name);
    }
    char hint[2 * SCENE_REF_MAX + 64] = "";
    if (wx_scene_substance(s, name) >= 0) {
        snprintf(hint, sizeof hint, "; '%s' is a substance: substance=\"%s\"", name, name);
    }
    if (s->mask_count == 0) {
        return fail(p, node, WX_CAUSE_BAD_SCENE,
                    "<Term> mask=\"%s\" names an unknown mask (no mask is defined before this "
                    "<Combine>)%s",
                    name, hint);
    }
    return fail(p, node, WX_CAUSE_BAD_SCENE,
                "<Term> mask=\"%s\" names an unknown mask (defined before this <Combine>: %s)%s",
                name, list, hint);
}

static wx_result parse_term(parser *p, const xmlNode *node, void *user)
{
    combine_state *st = user;
    wx_mask_def *m = st->mask;
    if (m->term_count >= WX_MAX_TERMS) {
        return fail(p, node, WX_CAUSE_TOO_MANY, "too many terms in this <Combine> (at most %d)",
                    WX_MAX_TERMS);
    }
    term_def d = { .weight = 1.0f };
    unsigned given;
    wx_result r = LEAF(term_attrs, &d, &given);
    if (r != WX_OK) {
        return r;
    }
    static const int sources[] = { TM_MASK, TM_SUBSTANCE, TM_CONSTANT, TM_AGE };
    int first = -1;
    for (int i = 0; i < 4; ++i) {
        if (!(given & (1u << sources[i]))) {
            continue;
        }
        if (first >= 0) {
            return fail(p, node, WX_CAUSE_BAD_SCENE,
                        "<Term> gives both %s and %s: a term has one source (mask, substance, "
                        "constant or age)",
                        term_attrs[first].name, term_attrs[sources[i]].name);
        }
        first = sources[i];
    }
    wx_term t = { .index = -1, .weight = d.weight, .offset = d.offset,
                  .steepness = d.steepness, .line = line_of(node) };
    switch (first) {
    case TM_MASK:
        t.kind = WX_TERM_MASK;
        r = find_term_mask(p, node, st, d.mask, &t.index);
        break;
    case TM_SUBSTANCE:
        t.kind = WX_TERM_SUBSTANCE;
        if (find_mask(p->scene, d.substance) >= 0) {
            return fail(p, node, WX_CAUSE_BAD_SCENE,
                        "<Term> substance=\"%s\" names a mask, not a substance: mask=\"%s\"",
                        d.substance, d.substance);
        }
        r = xml_find_substance(p, node, "substance", d.substance, &t.index);
        break;
    case TM_CONSTANT:
        t.kind = WX_TERM_CONSTANT;
        t.constant = d.constant;
        break;
    case TM_AGE:
        t.kind = WX_TERM_AGE; // age="w": w * i / iterations in frame i
        t.constant = d.age;
        break;
    default:
        return fail(p, node, WX_CAUSE_MISSING,
                    "<Term> needs one of mask, substance, constant or age");
    }
    if (r != WX_OK) {
        return r;
    }
    m->terms[m->term_count++] = t;
    return WX_OK;
}

static const child_spec combine_children[] = {
    { "Term", parse_term, true },
};

/// One mask of <Masks>, with the defaults of its kind.
static wx_result parse_mask(parser *p, const xmlNode *node, wx_mask_kind kind)
{
    wx_scene *s = p->scene;
    if (s->mask_count >= WX_MAX_MASKS) {
        return fail(p, node, WX_CAUSE_TOO_MANY, "too many masks (at most %d)", WX_MAX_MASKS);
    }
    // Each substance and each mask is a channel NAME.Y; a TextureMap adds seen.
    if (s->substance_count + s->mask_count + 1 > WX_IMAGE_MAX_CHANNELS - 1) {
        return fail(p, node, WX_CAUSE_TOO_MANY,
                    "too many channels: %d substances and %d masks (at most %d in all, each a "
                    "channel NAME.Y beside a TextureMap's seen)",
                    s->substance_count, s->mask_count + 1, WX_IMAGE_MAX_CHANNELS - 1);
    }
    wx_mask_def *m = &s->masks[s->mask_count];
    *m = (wx_mask_def){ .kind = kind, .line = line_of(node) };
    unsigned given = 0;
    wx_result r = WX_OK;
    switch (kind) {
    case WX_MASK_ACCESSIBILITY:
        m->rays = 64;
        m->distance = 1.0f;
        r = LEAF(accessibility_attrs, m, NULL);
        break;
    case WX_MASK_EXPOSURE:
        m->elevation = 45.0f;
        m->side_elevation = 1.0f;
        r = LEAF(exposure_attrs, m, NULL);
        break;
    case WX_MASK_CURVATURE:
        r = LEAF(curvature_attrs, m, NULL);
        break;
    case WX_MASK_HEIGHT:
        r = LEAF(height_attrs, m, &given);
        break;
    case WX_MASK_COMBINE:
        m->scale = 1.0f;
        r = ATTRS(combine_attrs, m, NULL);
        break;
    case WX_MASK_NOISE:
        m->frequency = 1.0f;
        m->octaves = 4;
        m->gain = 0.5f;
        m->noise_seed = 1;
        r = LEAF(noise_attrs, m, NULL);
        if (r == WX_OK && m->frequency > WX_NOISE_MAX_FREQUENCY) {
            r = fail(p, node, WX_CAUSE_BAD_VALUE,
                     "<Noise> frequency=\"%g\" is above %g per world unit", (double)m->frequency,
                     WX_NOISE_MAX_FREQUENCY);
        }
        break;
    }
    if (r != WX_OK || (r = check_mask_name(p, node, m->name)) != WX_OK) {
        return r;
    }
    if (kind == WX_MASK_HEIGHT) {
        m->has_min = (given & (1u << HT_MIN)) != 0;
        m->has_max = (given & (1u << HT_MAX)) != 0;
        if (m->has_min && m->has_max && !(m->max > m->min)) {
            return fail(p, node, WX_CAUSE_BAD_VALUE, "<Height> max=%g is not above min=%g",
                        (double)m->max, (double)m->min);
        }
    }
    if (kind == WX_MASK_COMBINE) {
        combine_state st = { .mask = m, .combine = node };
        if ((r = CHILDREN(combine_children, &st, NULL)) != WX_OK) {
            return r;
        }
        if (m->term_count == 0) {
            return fail(p, node, WX_CAUSE_MISSING,
                        "<Combine> needs at least one <Term> (at most %d)", WX_MAX_TERMS);
        }
    }
    s->mask_count++;
    return WX_OK;
}

static wx_result parse_accessibility(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    return parse_mask(p, node, WX_MASK_ACCESSIBILITY);
}

static wx_result parse_exposure(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    return parse_mask(p, node, WX_MASK_EXPOSURE);
}

static wx_result parse_curvature(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    return parse_mask(p, node, WX_MASK_CURVATURE);
}

static wx_result parse_height(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    return parse_mask(p, node, WX_MASK_HEIGHT);
}

static wx_result parse_noise(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    return parse_mask(p, node, WX_MASK_NOISE);
}

static wx_result parse_combine(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    return parse_mask(p, node, WX_MASK_COMBINE);
}

static const child_spec masks_children[] = {
    { "Accessibility", parse_accessibility, true },
    { "Exposure", parse_exposure, true },
    { "Curvature", parse_curvature, true },
    { "Height", parse_height, true },
    { "Combine", parse_combine, true },
    { "Noise", parse_noise, true },
};

/// <Masks>: after <Substances> (read first), since names are shared and terms
/// name substances; an empty <Masks> is no mask at all.
wx_result xml_parse_masks(parser *p, const xmlNode *node, void *user)
{
    wx_result r = NO_ATTRS();
    return r != WX_OK ? r : CHILDREN(masks_children, user, NULL);
}
