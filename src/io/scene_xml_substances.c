// scene_xml_substances.c: <Substances> (docs/design.md section 9), the
// substances other elements name, and the ageing rules (<Transfer>, <Decay>,
// <Grow>) of <Ageing> and of each <Surface>.
#include "io/scene_xml_internal.h"

#include <stddef.h>
#include <string.h>

// ---------------------------------------------------------------------------
// <Substances> (docs/design.md section 9), and the substances other elements name

typedef struct substance_def {
    char name[WX_SUBSTANCE_NAME_MAX + 1];
} substance_def;

static const attr_spec substance_attrs[] = {
    { "name", T_TEXT, offsetof(substance_def, name), .size = sizeof(((substance_def *)0)->name),
      .required = true },
};

/// What <Substances> declares, before it is stored in the scene.
typedef struct substances_state {
    int count;
    char names[WX_MAX_SUBSTANCES][WX_SUBSTANCE_NAME_MAX + 1];
    int lines[WX_MAX_SUBSTANCES];
} substances_state;

/// Letters, digits and '_', starting with a letter (ASCII, whatever the locale).
bool xml_is_substance_name(const char *name)
{
    bool letter = (name[0] >= 'a' && name[0] <= 'z') || (name[0] >= 'A' && name[0] <= 'Z');
    if (!letter) {
        return false;
    }
    for (const char *c = name; *c != '\0'; ++c) {
        bool ok = (*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') ||
                  (*c >= '0' && *c <= '9') || *c == '_';
        if (!ok) {
            return false;
        }
    }
    return true;
}

static wx_result parse_substance(parser *p, const xmlNode *node, void *user)
{
    substances_state *st = user;
    if (st->count >= WX_MAX_SUBSTANCES) {
        return fail(p, node, WX_CAUSE_TOO_MANY, "too many substances (at most %d)",
                    WX_MAX_SUBSTANCES);
    }
    substance_def d = { .name = "" };
    wx_result r = LEAF(substance_attrs, &d, NULL);
    if (r != WX_OK) {
        return r;
    }
    if (!xml_is_substance_name(d.name)) {
        return fail(p, node, WX_CAUSE_BAD_VALUE,
                    "<Substance> name=\"%s\" must be letters, digits and '_', starting with a "
                    "letter",
                    d.name);
    }
    // The mask's channels are NAME.Y, and a TextureMap's plain "seen".
    if (strcmp(d.name, "Y") == 0 || strcmp(d.name, "seen") == 0) {
        return fail(p, node, WX_CAUSE_BAD_VALUE,
                    "<Substance> name=\"%s\" is reserved (Y and seen name mask channels)",
                    d.name);
    }
    for (int k = 0; k < st->count; ++k) {
        if (strcmp(st->names[k], d.name) == 0) {
            return fail(p, node, WX_CAUSE_DUPLICATE,
                        "substance '%s' is declared twice (first at line %d)", d.name,
                        st->lines[k]);
        }
    }
    memcpy(st->names[st->count], d.name, sizeof d.name);
    st->lines[st->count] = line_of(node);
    st->count++;
    return WX_OK;
}

static const child_spec substances_children[] = {
    { "Substance", parse_substance, true },
};

/// Read before the other children of <Weathering> (parse_root).
wx_result xml_parse_substances(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    substances_state st = { .count = 0 };
    wx_result r = NO_ATTRS();
    if (r != WX_OK || (r = CHILDREN(substances_children, &st, NULL)) != WX_OK) {
        return r;
    }
    if (st.count == 0) {
        return fail(p, node, WX_CAUSE_MISSING,
                    "<Substances> declares no substance (give 1 to %d <Substance name=...>)",
                    WX_MAX_SUBSTANCES);
    }
    wx_scene *s = p->scene;
    s->substances_declared = true;
    s->substance_count = st.count;
    memset(s->substances, 0, sizeof s->substances);
    memcpy(s->substances, st.names, sizeof st.names);
    memcpy(p->substance_lines, st.lines, sizeof st.lines);
    s->dirt_substance = wx_scene_substance(s, "dirt");
    p->substances = node;
    return WX_OK;
}

/// The main pass meets <Substances> again: it was read first.
wx_result xml_skip_substances(parser *p, const xmlNode *node, void *user)
{
    (void)p;
    (void)node;
    (void)user;
    return WX_OK;
}

/// The index of the substance that attribute `attr` of `node` names; an
/// undeclared one is an error at the element's line.
wx_result xml_find_substance(parser *p, const xmlNode *node, const char *attr,
                             const char *name, int *index)
{
    const wx_scene *s = p->scene;
    *index = wx_scene_substance(s, name);
    if (*index >= 0) {
        return WX_OK;
    }
    if (!s->substances_declared) {
        return fail(p, node, WX_CAUSE_BAD_SCENE,
                    "<%s> %s=\"%s\" names an undeclared substance (without <Substances> the "
                    "scene has the one substance 'dirt')",
                    name_of(node), attr, name);
    }
    char list[WX_MAX_SUBSTANCES * (WX_SUBSTANCE_NAME_MAX + 2) + 1] = "";
    for (int k = 0; k < s->substance_count; ++k) {
        wx_list_append(list, sizeof list, s->substances[k]);
    }
    return fail(p, node, WX_CAUSE_BAD_SCENE,
                "<%s> %s=\"%s\" names an undeclared substance (<Substances> at line %d "
                "declares: %s)",
                name_of(node), attr, name, line_of(p->substances), list);
}

// ---------------------------------------------------------------------------
// Ageing rules: <Transfer>, <Decay>, <Grow> in <Ageing> and in <Surface>

typedef struct rule_def {
    char from[SCENE_REF_MAX], to[SCENE_REF_MAX], substance[SCENE_REF_MAX];
    char where[SCENE_REF_MAX];
    float rate, amount, min, density, radius, probability, strength;
} rule_def;

static const attr_spec transfer_attrs[] = {
    { "from", T_TEXT, offsetof(rule_def, from), .size = SCENE_REF_MAX, .required = true },
    { "to", T_TEXT, offsetof(rule_def, to), .size = SCENE_REF_MAX, .required = true },
    { "rate", T_FLOAT, offsetof(rule_def, rate), .range = R_UNIT, .required = true },
};

static const attr_spec decay_attrs[] = {
    { "substance", T_TEXT, offsetof(rule_def, substance), .size = SCENE_REF_MAX,
      .required = true },
    { "rate", T_FLOAT, offsetof(rule_def, rate), .range = R_UNIT, .required = true },
};

static const attr_spec grow_attrs[] = {
    { "substance", T_TEXT, offsetof(rule_def, substance), .size = SCENE_REF_MAX,
      .required = true },
    { "amount", T_FLOAT, offsetof(rule_def, amount), .range = R_NONNEG, .required = true },
};

static const attr_spec seed_attrs[] = {
    { "substance", T_TEXT, offsetof(rule_def, substance), .size = SCENE_REF_MAX, .required = true },
    { "density", T_FLOAT, offsetof(rule_def, density), .range = R_NONNEG, .required = true },
    { "where", T_TEXT, offsetof(rule_def, where), .size = SCENE_REF_MAX },
    { "min", T_FLOAT, offsetof(rule_def, min), .range = R_NONNEG },
};

static const attr_spec spread_attrs[] = {
    { "substance", T_TEXT, offsetof(rule_def, substance), .size = SCENE_REF_MAX, .required = true },
    { "radius", T_FLOAT, offsetof(rule_def, radius), .range = R_POSITIVE, .required = true },
    { "probability", T_FLOAT, offsetof(rule_def, probability), .range = R_UNIT },
    { "where", T_TEXT, offsetof(rule_def, where), .size = SCENE_REF_MAX },
    { "min", T_FLOAT, offsetof(rule_def, min), .range = R_NONNEG },
};

static const attr_spec crack_attrs[] = {
    { "substance", T_TEXT, offsetof(rule_def, substance), .size = SCENE_REF_MAX, .required = true },
    { "radius", T_FLOAT, offsetof(rule_def, radius), .range = R_POSITIVE, .required = true },
    { "strength", T_FLOAT, offsetof(rule_def, strength), .range = R_UNIT },
    { "where", T_TEXT, offsetof(rule_def, where), .size = SCENE_REF_MAX },
    { "min", T_FLOAT, offsetof(rule_def, min), .range = R_NONNEG },
};

static const attr_spec peel_attrs[] = {
    { "substance", T_TEXT, offsetof(rule_def, substance), .size = SCENE_REF_MAX, .required = true },
    { "from", T_TEXT, offsetof(rule_def, from), .size = SCENE_REF_MAX, .required = true },
    { "radius", T_FLOAT, offsetof(rule_def, radius), .range = R_POSITIVE, .required = true },
    { "probability", T_FLOAT, offsetof(rule_def, probability), .range = R_UNIT },
    { "where", T_TEXT, offsetof(rule_def, where), .size = SCENE_REF_MAX },
    { "min", T_FLOAT, offsetof(rule_def, min), .range = R_NONNEG },
};

/// Seed's and Spread's `where` (none: anywhere) and `min` (only with where).
static wx_result find_where(parser *p, const xmlNode *node, const rule_def *d, wx_rule *rule)
{
    rule->where = -1;
    if (d->where[0] == '\0') {
        if (d->min > 0.0f) {
            return fail(p, node, WX_CAUSE_BAD_VALUE,
                        "<%s> min=\"%g\" needs where= (the substance it is the least amount of)",
                        name_of(node), (double)d->min);
        }
        return WX_OK;
    }
    return xml_find_substance(p, node, "where", d->where, &rule->where);
}

/// Appends the rule `node` gives to `user` (a rule_list, or a struct that
/// starts with one).
static wx_result parse_rule(parser *p, const xmlNode *node, wx_rule_kind kind, void *user)
{
    rule_list *list = user;
    rule_def d = { .rate = 0.0f, .probability = 1.0f, .strength = 0.5f };
    wx_result r = WX_OK;
    wx_rule rule = { .kind = kind, .substance = -1, .to = -1, .where = -1, .line = line_of(node) };
    switch (kind) {
    case WX_RULE_TRANSFER:
        if ((r = LEAF(transfer_attrs, &d, NULL)) == WX_OK &&
            (r = xml_find_substance(p, node, "from", d.from, &rule.substance)) == WX_OK) {
            r = xml_find_substance(p, node, "to", d.to, &rule.to);
        }
        if (r == WX_OK && rule.substance == rule.to) {
            return fail(p, node, WX_CAUSE_BAD_VALUE,
                        "<Transfer> from and to are the same substance '%s'", d.from);
        }
        break;
    case WX_RULE_DECAY:
        if ((r = LEAF(decay_attrs, &d, NULL)) == WX_OK) {
            r = xml_find_substance(p, node, "substance", d.substance, &rule.substance);
        }
        break;
    case WX_RULE_GROW:
        if ((r = LEAF(grow_attrs, &d, NULL)) == WX_OK) {
            r = xml_find_substance(p, node, "substance", d.substance, &rule.substance);
        }
        break;
    case WX_RULE_SEED:
    case WX_RULE_SPREAD:
        r = kind == WX_RULE_SEED ? LEAF(seed_attrs, &d, NULL) : LEAF(spread_attrs, &d, NULL);
        if (r == WX_OK &&
            (r = xml_find_substance(p, node, "substance", d.substance, &rule.substance)) == WX_OK) {
            r = find_where(p, node, &d, &rule);
        }
        break;
    case WX_RULE_CRACK:
        if ((r = LEAF(crack_attrs, &d, NULL)) == WX_OK &&
            (r = xml_find_substance(p, node, "substance", d.substance, &rule.substance)) == WX_OK) {
            r = find_where(p, node, &d, &rule);
        }
        break;
    case WX_RULE_PEEL:
        if ((r = LEAF(peel_attrs, &d, NULL)) == WX_OK &&
            (r = xml_find_substance(p, node, "substance", d.substance, &rule.substance)) == WX_OK &&
            (r = xml_find_substance(p, node, "from", d.from, &rule.to)) == WX_OK) {
            r = find_where(p, node, &d, &rule);
        }
        if (r == WX_OK && rule.substance == rule.to) {
            return fail(p, node, WX_CAUSE_BAD_VALUE,
                        "<Peel> from and substance are the same substance '%s'", d.from);
        }
        break;
    }
    if (r != WX_OK) {
        return r;
    }
    rule.min = d.min;
    rule.density = d.density;
    rule.radius = d.radius;
    rule.probability = d.probability;
    rule.strength = d.strength;
    rule.rate = kind == WX_RULE_TRANSFER || kind == WX_RULE_DECAY ? d.rate : 0.0f;
    rule.amount = kind == WX_RULE_GROW ? d.amount : 0.0f;
    r = xml_grow_list(p, node, (void **)list->rules, *list->count, list->capacity, sizeof rule,
                      SCENE_MAX_RULES, "ageing rules");
    if (r != WX_OK) {
        return r;
    }
    (*list->rules)[(*list->count)++] = rule;
    return WX_OK;
}

wx_result xml_parse_transfer(parser *p, const xmlNode *node, void *user)
{
    return parse_rule(p, node, WX_RULE_TRANSFER, user);
}

wx_result xml_parse_decay(parser *p, const xmlNode *node, void *user)
{
    return parse_rule(p, node, WX_RULE_DECAY, user);
}

wx_result xml_parse_grow(parser *p, const xmlNode *node, void *user)
{
    return parse_rule(p, node, WX_RULE_GROW, user);
}

wx_result xml_parse_seed(parser *p, const xmlNode *node, void *user)
{
    return parse_rule(p, node, WX_RULE_SEED, user);
}

wx_result xml_parse_spread(parser *p, const xmlNode *node, void *user)
{
    return parse_rule(p, node, WX_RULE_SPREAD, user);
}

wx_result xml_parse_crack(parser *p, const xmlNode *node, void *user)
{
    return parse_rule(p, node, WX_RULE_CRACK, user);
}

wx_result xml_parse_peel(parser *p, const xmlNode *node, void *user)
{
    return parse_rule(p, node, WX_RULE_PEEL, user);
}

static const child_spec ageing_children[] = {
    { "Transfer", xml_parse_transfer, true }, { "Decay", xml_parse_decay, true },
    { "Grow", xml_parse_grow, true },         { "Seed", xml_parse_seed, true },
    { "Spread", xml_parse_spread, true },     { "Crack", xml_parse_crack, true },
    { "Peel", xml_parse_peel, true },
};

/// <Ageing>: the global rules, run on every surface texel after each iteration.
wx_result xml_parse_ageing(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    wx_scene *s = p->scene;
    rule_list list = { .rules = &s->rules, .count = &s->rule_count, .capacity = &p->rule_cap };
    wx_result r = NO_ATTRS();
    return r != WX_OK ? r : CHILDREN(ageing_children, &list, NULL);
}
