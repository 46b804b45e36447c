// scene_xml_particles.c: the elements of the particles (docs/design.md section
// 3): <Solver> (the simulation's bounds and steps), <ForceFields> and
// <Emitters> with their loads.
#include "io/scene_xml_internal.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

// ---------------------------------------------------------------------------
// <Solver>

static const attr_spec bbox_attrs[] = {
    { "size", T_FLOAT, offsetof(wx_scene, bbox_size), .range = R_POSITIVE },
    { "centerX", T_FLOAT, offsetof(wx_scene, bbox_center[0]), .range = R_FINITE },
    { "centerY", T_FLOAT, offsetof(wx_scene, bbox_center[1]), .range = R_FINITE },
    { "centerZ", T_FLOAT, offsetof(wx_scene, bbox_center[2]), .range = R_FINITE },
};

static const attr_spec simulation_attrs[] = {
    { "timeStep", T_DOUBLE, offsetof(wx_scene, time_step), .range = R_POSITIVE },
    { "steps", T_INT64, offsetof(wx_scene, steps), .lo = 1, .hi = SCENE_MAX_STEPS },
    { "seed", T_UINT64, offsetof(wx_scene, seed), .range = R_FINITE },
    // docs/design.md section 9: the simulation's steps, repeated.
    { "iterations", T_INT, offsetof(wx_scene, iterations), .lo = 1,
      .hi = SCENE_MAX_ITERATIONS },
};

static wx_result parse_bounding_box(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    return LEAF(bbox_attrs, p->scene, NULL);
}

static wx_result parse_simulation(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    return LEAF(simulation_attrs, p->scene, NULL);
}

static const child_spec solver_children[] = {
    { "BoundingBox", parse_bounding_box, false },
    { "Simulation", parse_simulation, false },
};

wx_result xml_parse_solver(parser *p, const xmlNode *node, void *user)
{
    wx_result r = NO_ATTRS();
    return r != WX_OK ? r : CHILDREN(solver_children, user, NULL);
}

// ---------------------------------------------------------------------------
// <ForceFields>

static const attr_spec gravity_attrs[] = {
    { "acceleration", T_FLOAT, offsetof(wx_field, strength), .range = R_FINITE },
};

static const attr_spec wind_attrs[] = {
    { "strength", T_FLOAT, offsetof(wx_field, strength), .range = R_NONNEG },
    { "dirX", T_FLOAT, offsetof(wx_field, dir[0]), .range = R_FINITE },
    { "dirY", T_FLOAT, offsetof(wx_field, dir[1]), .range = R_FINITE },
    { "dirZ", T_FLOAT, offsetof(wx_field, dir[2]), .range = R_FINITE },
};

static const attr_spec turbulence_attrs[] = {
    { "strength", T_FLOAT, offsetof(wx_field, strength), .range = R_NONNEG },
    { "frequency", T_FLOAT, offsetof(wx_field, frequency), .range = R_POSITIVE },
    { "octaves", T_INT, offsetof(wx_field, octaves), .lo = 1, .hi = 16 },
};

static wx_result add_field(parser *p, const xmlNode *node, wx_field_kind kind, wx_field **out)
{
    wx_scene *s = p->scene;
    wx_result r = xml_grow_list(p, node, (void **)&s->fields, s->field_count, &p->field_cap,
                                sizeof *s->fields, SCENE_MAX_FIELDS, "force fields");
    if (r != WX_OK) {
        return r;
    }
    wx_field *f = &s->fields[s->field_count++];
    // Defaults (docs/design.md section 3; the Wind direction is ours: +X).
    *f = (wx_field){ .kind = kind, .strength = 0.0f, .frequency = 1.0f, .octaves = 4,
                     .line = line_of(node) };
    if (kind == WX_FIELD_GRAVITY) {
        f->strength = 9.8f;
        f->dir[1] = -1.0f;
    } else if (kind == WX_FIELD_WIND) {
        f->dir[0] = 1.0f;
    }
    *out = f;
    return WX_OK;
}

static wx_result parse_gravity(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    wx_field *f;
    wx_result r = add_field(p, node, WX_FIELD_GRAVITY, &f);
    return r != WX_OK ? r : LEAF(gravity_attrs, f, NULL);
}

static wx_result parse_wind(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    wx_field *f;
    wx_result r = add_field(p, node, WX_FIELD_WIND, &f);
    if (r != WX_OK || (r = LEAF(wind_attrs, f, NULL)) != WX_OK) {
        return r;
    }
    double len = sqrt((double)f->dir[0] * f->dir[0] + (double)f->dir[1] * f->dir[1] +
                      (double)f->dir[2] * f->dir[2]);
    if (!(len > 0.0) || !isfinite(len)) {
        return fail(p, node, WX_CAUSE_BAD_VALUE,
                    "<Wind> direction (dirX, dirY, dirZ) must not be zero");
    }
    for (int i = 0; i < 3; ++i) {
        f->dir[i] = (float)(f->dir[i] / len);
    }
    return WX_OK;
}

static wx_result parse_turbulence(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    wx_field *f;
    wx_result r = add_field(p, node, WX_FIELD_TURBULENCE, &f);
    return r != WX_OK ? r : LEAF(turbulence_attrs, f, NULL);
}

static const child_spec force_field_children[] = {
    { "Gravity", parse_gravity, true },
    { "Wind", parse_wind, true },
    { "Turbulence", parse_turbulence, true },
};

wx_result xml_parse_force_fields(parser *p, const xmlNode *node, void *user)
{
    wx_result r = NO_ATTRS();
    return r != WX_OK ? r : CHILDREN(force_field_children, user, NULL);
}

// ---------------------------------------------------------------------------
// <Emitters>

/// An emitter as its attributes give it: `dirt` apart, since it is the load of
/// substance "dirt", wherever <Substances> puts that one.
typedef struct emitter_def {
    wx_emitter e;
    float dirt; ///< NAN when the attribute is absent
} emitter_def;

#define EMITTER_NAME                                                                         \
    { "name", T_TEXT, offsetof(emitter_def, e.name), .size = sizeof(((wx_emitter *)0)->name) }

#define EMITTER_ATTRS                                                                        \
    EMITTER_NAME,                                                                            \
    { "centerX", T_FLOAT, offsetof(emitter_def, e.center[0]), .range = R_FINITE },           \
    { "centerY", T_FLOAT, offsetof(emitter_def, e.center[1]), .range = R_FINITE },           \
    { "centerZ", T_FLOAT, offsetof(emitter_def, e.center[2]), .range = R_FINITE },           \
    EMITTER_FLIGHT

// What every emitter has besides its place: rate, times, speed, load.
#define EMITTER_FLIGHT                                                                       \
    { "rate", T_DOUBLE, offsetof(emitter_def, e.rate), .range = R_NONNEG },                  \
    { "start", T_DOUBLE, offsetof(emitter_def, e.start), .range = R_NONNEG },                \
    { "end", T_DOUBLE, offsetof(emitter_def, e.end), .range = R_NONNEG },                    \
    { "speed", T_FLOAT, offsetof(emitter_def, e.speed), .range = R_NONNEG },                 \
    { "mass", T_FLOAT, offsetof(emitter_def, e.mass), .range = R_POSITIVE },                 \
    { "dirt", T_FLOAT, offsetof(emitter_def, dirt), .range = R_NONNEG },                     \
    { "maxCollisions", T_INT, offsetof(emitter_def, e.max_collisions), .lo = 1,              \
      .hi = SCENE_MAX_COLLISIONS }

static const attr_spec point_emitter_attrs[] = { EMITTER_ATTRS };

static const attr_spec hemisphere_emitter_attrs[] = {
    EMITTER_ATTRS,
    { "radius", T_FLOAT, offsetof(emitter_def, e.radius), .range = R_POSITIVE },
};

// docs/design.md section 8: the box's corners are required (a box has no
// natural default), the direction defaults to straight down.
static const attr_spec box_emitter_attrs[] = {
    EMITTER_NAME,
    { "minX", T_FLOAT, offsetof(emitter_def, e.box_min[0]), .range = R_FINITE,
      .required = true },
    { "minY", T_FLOAT, offsetof(emitter_def, e.box_min[1]), .range = R_FINITE,
      .required = true },
    { "minZ", T_FLOAT, offsetof(emitter_def, e.box_min[2]), .range = R_FINITE,
      .required = true },
    { "maxX", T_FLOAT, offsetof(emitter_def, e.box_max[0]), .range = R_FINITE,
      .required = true },
    { "maxY", T_FLOAT, offsetof(emitter_def, e.box_max[1]), .range = R_FINITE,
      .required = true },
    { "maxZ", T_FLOAT, offsetof(emitter_def, e.box_max[2]), .range = R_FINITE,
      .required = true },
    { "dirX", T_FLOAT, offsetof(emitter_def, e.dir[0]), .range = R_FINITE },
    { "dirY", T_FLOAT, offsetof(emitter_def, e.dir[1]), .range = R_FINITE },
    { "dirZ", T_FLOAT, offsetof(emitter_def, e.dir[2]), .range = R_FINITE },
    { "spread", T_FLOAT, offsetof(emitter_def, e.spread), .range = R_NONNEG },
    EMITTER_FLIGHT,
};

// A box emitter's corners in order on every axis, its direction not zero (made
// unit) and its spread below 90 degrees.
static wx_result check_box_emitter(parser *p, const xmlNode *node, wx_emitter *e)
{
    static const char axes[] = "XYZ";
    for (int k = 0; k < 3; ++k) {
        if (!(e->box_min[k] <= e->box_max[k])) {
            return fail(p, node, WX_CAUSE_BAD_VALUE,
                        "<BoxEmitter> min%c=%g is above max%c=%g (min <= max on every axis)",
                        axes[k], (double)e->box_min[k], axes[k], (double)e->box_max[k]);
        }
    }
    double len = sqrt((double)e->dir[0] * e->dir[0] + (double)e->dir[1] * e->dir[1] +
                      (double)e->dir[2] * e->dir[2]);
    if (!(len > 0.0) || !isfinite(len)) {
        return fail(p, node, WX_CAUSE_BAD_VALUE,
                    "<BoxEmitter> direction (dirX, dirY, dirZ) must not be zero");
    }
    for (int k = 0; k < 3; ++k) {
        e->dir[k] = (float)(e->dir[k] / len);
    }
    if (!(e->spread < 90.0f)) {
        return fail(p, node, WX_CAUSE_BAD_VALUE,
                    "<BoxEmitter> spread=\"%g\" must be in [0, 90) degrees", (double)e->spread);
    }
    return WX_OK;
}

/// An emitter's <Load> children: which substances they gave, and where.
typedef struct load_state {
    wx_emitter *e;
    bool dirt_attribute; ///< the emitter gives dirt=, substance dirt's load
    unsigned given;      ///< bit k: a <Load> of substance k was read
    int lines[WX_MAX_SUBSTANCES];
} load_state;

typedef struct load_def {
    char substance[SCENE_REF_MAX];
    float amount;
} load_def;

static const attr_spec load_attrs[] = {
    { "substance", T_TEXT, offsetof(load_def, substance), .size = SCENE_REF_MAX,
      .required = true },
    { "amount", T_FLOAT, offsetof(load_def, amount), .range = R_NONNEG, .required = true },
};

static wx_result parse_load(parser *p, const xmlNode *node, void *user)
{
    load_state *st = user;
    load_def d = { .amount = 0.0f };
    int k;
    wx_result r = LEAF(load_attrs, &d, NULL);
    if (r != WX_OK || (r = xml_find_substance(p, node, "substance", d.substance, &k)) != WX_OK) {
        return r;
    }
    if (st->given & (1u << k)) {
        return fail(p, node, WX_CAUSE_DUPLICATE,
                    "<Load> of substance '%s' appears twice in this emitter (first at line %d)",
                    d.substance, st->lines[k]);
    }
    if (k == p->scene->dirt_substance && st->dirt_attribute) {
        return fail(p, node, WX_CAUSE_DUPLICATE,
                    "<Load> of substance 'dirt' repeats the emitter's dirt attribute (line %d), "
                    "which is that load: give one or the other",
                    st->e->line);
    }
    st->given |= 1u << k;
    st->lines[k] = line_of(node);
    st->e->load[k] = d.amount;
    return xml_add_amount(p, true, (int)(st->e - p->scene->emitters), k, d.amount, line_of(node),
                          "<Load> amount");
}

static const child_spec load_children[] = {
    { "Load", parse_load, true },
};

static wx_result parse_emitter(parser *p, const xmlNode *node, wx_emitter_kind kind)
{
    wx_scene *s = p->scene;
    wx_result r = xml_grow_list(p, node, (void **)&s->emitters, s->emitter_count, &p->emitter_cap,
                                sizeof *s->emitters, SCENE_MAX_EMITTERS, "emitters");
    if (r != WX_OK) {
        return r;
    }
    wx_emitter *e = &s->emitters[s->emitter_count++];
    // end = NAN until the simulation's duration is known (xml_finish_emitters).
    // Loads: 1 of dirt without <Substances> (version 1), else 0 of everything.
    emitter_def d = {
        .e = { .kind = kind, .radius = kind == WX_EMITTER_HEMISPHERE ? 1.0f : 0.0f,
               .dir = { 0.0f, -1.0f, 0.0f }, .rate = 1000.0, .start = 0.0, .end = NAN,
               .speed = 1.0f, .mass = 1.0f, .max_collisions = 100, .line = line_of(node) },
        .dirt = NAN,
    };
    if (!s->substances_declared) {
        d.e.load[s->dirt_substance] = 1.0f;
    }
    switch (kind) {
    case WX_EMITTER_POINT:
        r = ATTRS(point_emitter_attrs, &d, NULL);
        break;
    case WX_EMITTER_HEMISPHERE:
        r = ATTRS(hemisphere_emitter_attrs, &d, NULL);
        break;
    case WX_EMITTER_BOX:
        r = ATTRS(box_emitter_attrs, &d, NULL);
        if (r == WX_OK) {
            r = check_box_emitter(p, node, &d.e);
        }
        break;
    }
    *e = d.e;
    if (r != WX_OK) {
        return r;
    }
    bool dirt_attribute = !isnan(d.dirt); // the range check refused a given NaN
    if (dirt_attribute) {
        if (s->dirt_substance < 0) {
            return fail(p, node, WX_CAUSE_BAD_SCENE,
                        "<%s> dirt=\"%g\" is the load of substance 'dirt', which <Substances> "
                        "(line %d) does not declare: give loads by <Load substance=... amount=...>",
                        name_of(node), (double)d.dirt, line_of(p->substances));
        }
        e->load[s->dirt_substance] = d.dirt;
    }
    if (s->dirt_substance >= 0) {
        // dirt=, or version 1's default load of 1.
        static const char *const dirt_of[2][3] = {
            { "<PointEmitter>'s default dirt", "<HemisphereEmitter>'s default dirt",
              "<BoxEmitter>'s default dirt" },
            { "<PointEmitter> dirt", "<HemisphereEmitter> dirt", "<BoxEmitter> dirt" },
        };
        r = xml_add_amount(p, true, s->emitter_count - 1, s->dirt_substance,
                           e->load[s->dirt_substance], e->line, dirt_of[dirt_attribute][kind]);
        if (r != WX_OK) {
            return r;
        }
    }
    for (int i = 0; e->name[0] != '\0' && i < s->emitter_count - 1; ++i) {
        if (strcmp(s->emitters[i].name, e->name) == 0) {
            return fail(p, node, WX_CAUSE_DUPLICATE,
                        "emitter name '%s' is used twice (first at line %d)", e->name,
                        s->emitters[i].line);
        }
    }
    load_state loads = { .e = e, .dirt_attribute = dirt_attribute };
    return CHILDREN(load_children, &loads, NULL);
}

static wx_result parse_point_emitter(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    return parse_emitter(p, node, WX_EMITTER_POINT);
}

static wx_result parse_hemisphere_emitter(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    return parse_emitter(p, node, WX_EMITTER_HEMISPHERE);
}

static wx_result parse_box_emitter(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    return parse_emitter(p, node, WX_EMITTER_BOX);
}

static const child_spec emitter_children[] = {
    { "PointEmitter", parse_point_emitter, true },
    { "HemisphereEmitter", parse_hemisphere_emitter, true },
    { "BoxEmitter", parse_box_emitter, true },
};

wx_result xml_parse_emitters(parser *p, const xmlNode *node, void *user)
{
    wx_result r = NO_ATTRS();
    return r != WX_OK ? r : CHILDREN(emitter_children, user, NULL);
}

/// Emitter end times default to the end of the simulation, known only now.
wx_result xml_finish_emitters(parser *p)
{
    double duration = wx_scene_duration(p->scene);
    for (int i = 0; i < p->scene->emitter_count; ++i) {
        wx_emitter *e = &p->scene->emitters[i];
        if (isnan(e->end)) {
            e->end = duration;
        }
        if (e->start > e->end) {
            return fail_line(
                p, e->line, WX_CAUSE_BAD_VALUE, "emitter%s%s%s start=%g is after its end=%g%s",
                e->name[0] != '\0' ? " '" : "", e->name, e->name[0] != '\0' ? "'" : "", e->start,
                e->end, e->end == duration ? " (the end of the simulation)" : "");
        }
    }
    return WX_OK;
}
