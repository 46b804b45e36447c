// scene_xml_geometry.c: <Geometry> (docs/design.md sections 3 and 11): meshes,
// their <Surface>s with their exchanges and own rules, and <TextureMap>s.
#include "io/scene_xml_internal.h"

#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/input_file.h"
#include "model/mesh.h"

// ---------------------------------------------------------------------------
// <Geometry>

static const char *const color_use_names[] = { "none", "impact", "dirt", NULL };

typedef struct surface_def {
    char material[128];
    float absorption, bounce, dirt, deposit, erosion;
    int colors;
} surface_def;

enum { SF_MATERIAL, SF_ABSORPTION, SF_BOUNCE, SF_DIRT, SF_DEPOSIT, SF_EROSION, SF_COLORS };

static const attr_spec surface_attrs[] = {
    [SF_MATERIAL] = { "material", T_TEXT, offsetof(surface_def, material),
                      .size = sizeof(((surface_def *)0)->material), .required = true },
    [SF_ABSORPTION] = { "absorption", T_FLOAT, offsetof(surface_def, absorption),
                        .range = R_UNIT },
    [SF_BOUNCE] = { "bounce", T_FLOAT, offsetof(surface_def, bounce), .range = R_UNIT },
    // Substance dirt's exchange values (docs/design.md section 9).
    [SF_DIRT] = { "dirt", T_FLOAT, offsetof(surface_def, dirt), .range = R_NONNEG },
    [SF_DEPOSIT] = { "deposit", T_FLOAT, offsetof(surface_def, deposit), .range = R_UNIT },
    [SF_EROSION] = { "erosion", T_FLOAT, offsetof(surface_def, erosion), .range = R_UNIT },
    [SF_COLORS] = { "vertexColors", T_ENUM, offsetof(surface_def, colors),
                    .choices = color_use_names },
};

typedef struct mesh_state {
    wx_mesh *mesh;
    int index; ///< of the mesh in wx_scene.meshes
    int64_t surface_cap;
} mesh_state;

/// A <Surface>'s children: its own rules (first, so that the rule handlers
/// take this struct as their rule_list) and its <Exchange>s.
typedef struct surface_state {
    rule_list rules;
    int64_t rule_cap;
    wx_surface *sf;
    /// Substance dirt's values come from the attributes (or vertex colours).
    bool dirt_attributes;
    unsigned exchanged; ///< bit k: an <Exchange> of substance k was read
    int lines[WX_MAX_SUBSTANCES];
} surface_state;

typedef struct exchange_def {
    char substance[SCENE_REF_MAX];
    float initial, deposit, erosion;
} exchange_def;

static const attr_spec exchange_attrs[] = {
    { "substance", T_TEXT, offsetof(exchange_def, substance), .size = SCENE_REF_MAX,
      .required = true },
    { "initial", T_FLOAT, offsetof(exchange_def, initial), .range = R_NONNEG },
    { "deposit", T_FLOAT, offsetof(exchange_def, deposit), .range = R_UNIT },
    { "erosion", T_FLOAT, offsetof(exchange_def, erosion), .range = R_UNIT },
};

static wx_result parse_exchange(parser *p, const xmlNode *node, void *user)
{
    surface_state *st = user;
    exchange_def d = { .initial = 0.0f };
    int k;
    wx_result r = LEAF(exchange_attrs, &d, NULL);
    if (r != WX_OK || (r = xml_find_substance(p, node, "substance", d.substance, &k)) != WX_OK) {
        return r;
    }
    if (st->exchanged & (1u << k)) {
        return fail(p, node, WX_CAUSE_DUPLICATE,
                    "<Exchange> of substance '%s' appears twice in this <Surface> (first at line "
                    "%d)",
                    d.substance, st->lines[k]);
    }
    if (k == p->scene->dirt_substance && st->dirt_attributes) {
        return fail(p, node, WX_CAUSE_DUPLICATE,
                    "<Exchange> of substance 'dirt' repeats the <Surface>'s dirt, deposit, "
                    "erosion or vertexColors=\"dirt\" (line %d), which are its values: give one "
                    "or the other",
                    st->sf->line);
    }
    st->exchanged |= 1u << k;
    st->lines[k] = line_of(node);
    st->sf->initial[k] = d.initial;
    st->sf->deposit[k] = d.deposit;
    st->sf->erosion[k] = d.erosion;
    return xml_add_amount(p, false, -1, k, d.initial, line_of(node), "<Exchange> initial");
}

static const child_spec surface_children[] = {
    { "Exchange", parse_exchange, true }, { "Transfer", xml_parse_transfer, true },
    { "Decay", xml_parse_decay, true },   { "Grow", xml_parse_grow, true },
    { "Seed", xml_parse_seed, true },     { "Spread", xml_parse_spread, true },
    { "Crack", xml_parse_crack, true },   { "Peel", xml_parse_peel, true },
};

static wx_result parse_surface(parser *p, const xmlNode *node, void *user)
{
    mesh_state *m = user;
    wx_mesh *mesh = m->mesh;
    const wx_scene *s = p->scene;
    surface_def d = { .colors = 0 };
    unsigned given;
    wx_result r = ATTRS(surface_attrs, &d, &given);
    if (r != WX_OK) {
        return r;
    }
    static const int dirt_attrs[] = { SF_DIRT, SF_DEPOSIT, SF_EROSION };
    for (int i = 0; i < 3 && s->dirt_substance < 0; ++i) {
        if (given & (1u << dirt_attrs[i])) {
            return fail(p, node, WX_CAUSE_BAD_SCENE,
                        "<Surface> %s= is substance 'dirt''s, which <Substances> (line %d) does "
                        "not declare: give each substance's values by <Exchange substance=...>",
                        surface_attrs[dirt_attrs[i]].name, line_of(p->substances));
        }
    }
    static const wx_color_use colors[] = { WX_COLOR_NONE, WX_COLOR_IMPACT, WX_COLOR_DIRT };
    if (colors[d.colors] == WX_COLOR_DIRT && s->dirt_substance < 0) {
        return fail(p, node, WX_CAUSE_BAD_SCENE,
                    "<Surface> vertexColors=\"dirt\" gives substance 'dirt''s values, which "
                    "<Substances> (line %d) does not declare",
                    line_of(p->substances));
    }
    for (int i = 0; i < mesh->surface_count; ++i) {
        if (strcmp(mesh->surfaces[i].material, d.material) == 0) {
            return fail(p, node, WX_CAUSE_DUPLICATE,
                        "material '%s' appears twice in this <Mesh> (first at line %d)", d.material,
                        mesh->surfaces[i].line);
        }
    }
    r = xml_grow_list(p, node, (void **)&mesh->surfaces, mesh->surface_count, &m->surface_cap,
                      sizeof *mesh->surfaces, SCENE_MAX_SURFACES, "surfaces");
    if (r != WX_OK) {
        return r;
    }
    wx_surface *sf = &mesh->surfaces[mesh->surface_count++];
    // Every substance's initial amount, deposit and erosion default to 0;
    // substance dirt's come from the attributes.
    *sf = (wx_surface){ .absorption = d.absorption, .bounce = d.bounce,
                        .colors = colors[d.colors], .line = line_of(node) };
    if (s->dirt_substance >= 0) {
        sf->initial[s->dirt_substance] = d.dirt;
        sf->deposit[s->dirt_substance] = d.deposit;
        sf->erosion[s->dirt_substance] = d.erosion;
        r = xml_add_amount(p, false, -1, s->dirt_substance, d.dirt, sf->line, "<Surface> dirt");
        if (r != WX_OK) {
            return r;
        }
    }
    memcpy(sf->material, d.material, sizeof d.material);
    surface_state st = { .sf = sf };
    st.rules = (rule_list){ .rules = &sf->rules, .count = &sf->rule_count,
                            .capacity = &st.rule_cap };
    st.dirt_attributes = (given & ((1u << SF_DIRT) | (1u << SF_DEPOSIT) | (1u << SF_EROSION))) ||
                         sf->colors == WX_COLOR_DIRT;
    return CHILDREN(surface_children, &st, NULL);
}

// <TextureMap> (docs/design.md section 11): the mask's channels in the mesh's
// UV layout.
typedef struct texture_def {
    char file[256];
    int resolution, width, height, padding, uv, every;
    float radius, noise, max_radius;
    int tiles;
} texture_def;

enum { TX_FILE, TX_RESOLUTION, TX_WIDTH, TX_HEIGHT, TX_PADDING, TX_UV, TX_EVERY, TX_RADIUS,
       TX_NOISE, TX_MAX_RADIUS, TX_TILES }; // bits of `present`

/// `tiles`, in the order of wx_uv_tiles.
static const char *const uv_tiles_names[] = { "repeat", "udim", "clip", NULL };

static const attr_spec texture_attrs[] = {
    // Required: a default name would clash between two TextureMaps.
    [TX_FILE] = { "file", T_NAME, offsetof(texture_def, file),
                  .size = sizeof(((texture_def *)0)->file), .required = true },
    [TX_RESOLUTION] = { "resolution", T_INT, offsetof(texture_def, resolution), .lo = 1,
                        .hi = WX_MAP_MAX_SIDE },
    [TX_WIDTH] = { "width", T_INT, offsetof(texture_def, width), .lo = 1,
                   .hi = WX_MAP_MAX_SIDE },
    [TX_HEIGHT] = { "height", T_INT, offsetof(texture_def, height), .lo = 1,
                    .hi = WX_MAP_MAX_SIDE },
    [TX_PADDING] = { "padding", T_INT, offsetof(texture_def, padding), .lo = 0,
                     .hi = SCENE_MAX_PADDING },
    [TX_UV] = { "uv", T_INT, offsetof(texture_def, uv), .lo = 0,
                .hi = WX_MESH_MAX_UV_CHANNELS - 1 },
    [TX_EVERY] = { "every", T_INT, offsetof(texture_def, every), .lo = 0,
                   .hi = SCENE_MAX_ITERATIONS },
    [TX_RADIUS] = { "radius", T_FLOAT, offsetof(texture_def, radius), .range = R_NONNEG },
    [TX_NOISE] = { "noise", T_FLOAT, offsetof(texture_def, noise), .range = R_POSITIVE },
    [TX_MAX_RADIUS] = { "maxRadius", T_FLOAT, offsetof(texture_def, max_radius),
                        .range = R_POSITIVE },
    [TX_TILES] = { "tiles", T_ENUM, offsetof(texture_def, tiles), .choices = uv_tiles_names },
};

static wx_result parse_texture_map(parser *p, const xmlNode *node, void *user)
{
    mesh_state *m = user;
    wx_scene *s = p->scene;
    texture_def d = { .resolution = WX_DEFAULT_TEXTURE_RESOLUTION,
                      .padding = WX_DEFAULT_TEXTURE_PADDING, .noise = WX_DEFAULT_NOISE };
    unsigned given;
    wx_result r = LEAF(texture_attrs, &d, &given);
    if (r != WX_OK) {
        return r;
    }
    size_t len = strlen(d.file);
    if (len < 5 || strcasecmp(d.file + len - 4, ".exr") != 0) {
        return fail(p, node, WX_CAUSE_BAD_VALUE, "<TextureMap> file=\"%s\" must end in .exr",
                    d.file);
    }
    int width = given & (1u << TX_WIDTH) ? d.width : d.resolution;
    int height = given & (1u << TX_HEIGHT) ? d.height : d.resolution;
    if ((long long)width * height > WX_MAP_MAX_TEXELS) {
        return fail(p, node, WX_CAUSE_BAD_VALUE,
                    "<TextureMap> size %dx%d is over %lld texels", width, height,
                    (long long)WX_MAP_MAX_TEXELS);
    }
    // No radius: the adaptive smoothing, which noise and maxRadius tune.
    bool adaptive = !(given & (1u << TX_RADIUS));
    if (!adaptive && (given & ((1u << TX_NOISE) | (1u << TX_MAX_RADIUS)))) {
        return fail(p, node, WX_CAUSE_BAD_SCENE,
                    "<TextureMap> gives a radius and %s: %s tunes the adaptive smoothing, which "
                    "a radius replaces; give one or the other",
                    given & (1u << TX_NOISE) ? "noise" : "maxRadius",
                    given & (1u << TX_NOISE) ? "noise" : "maxRadius");
    }
    r = xml_grow_list(p, node, (void **)&s->textures, s->texture_count, &p->texture_cap,
                      sizeof *s->textures, SCENE_MAX_TEXTURES, "texture maps");
    if (r != WX_OK) {
        return r;
    }
    wx_texture_map *t = &s->textures[s->texture_count++];
    // max_radius 0 without maxRadius: WX_DEFAULT_MAX_RADIUS_TEXELS texels of
    // the camera the smoothing runs on, known only then.
    *t = (wx_texture_map){ .mesh = m->index, .width = width, .height = height,
                           .padding = d.padding, .uv = d.uv, .every = d.every,
                           .adaptive = adaptive, .radius = adaptive ? 0.0f : d.radius,
                           .noise = d.noise, .max_radius = d.max_radius,
                           .tiles = (wx_uv_tiles)d.tiles, .line = line_of(node) };
    memcpy(t->file, d.file, sizeof d.file);
    return WX_OK;
}

static const attr_spec mesh_attrs[] = {
    { "file", T_STRING, offsetof(map_def, file), .size = WX_PATH_MAX, .required = true },
};

static const child_spec mesh_children[] = {
    { "Surface", parse_surface, true },
    { "TextureMap", parse_texture_map, true },
};

static wx_result parse_mesh(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    wx_scene *s = p->scene;
    wx_result r = xml_grow_list(p, node, (void **)&s->meshes, s->mesh_count, &p->mesh_cap,
                                sizeof *s->meshes, SCENE_MAX_MESHES, "meshes");
    if (r != WX_OK) {
        return r;
    }
    wx_mesh *mesh = &s->meshes[s->mesh_count++];
    memset(mesh, 0, sizeof *mesh);
    mesh->line = line_of(node);
    map_def file = { NULL };
    r = ATTRS(mesh_attrs, &file, NULL);
    char why[WX_INPUT_WHY_MAX];
    wx_cause cause = WX_CAUSE_NONE;
    if (r == WX_OK && (r = xml_resolve_path(p, node, file.file, &mesh->path)) == WX_OK &&
        !wx_is_regular_file(mesh->path, why, &cause)) {
        r = fail(p, node, cause, "mesh file '%s' %s", file.file,
                 cause == WX_CAUSE_FILE_MISSING ? "not found" : why);
    }
    free(file.file);
    mesh_state m = { .mesh = mesh, .index = s->mesh_count - 1 };
    return r != WX_OK ? r : CHILDREN(mesh_children, &m, NULL);
}

static const child_spec geometry_children[] = {
    { "Mesh", parse_mesh, true },
};

wx_result xml_parse_geometry(parser *p, const xmlNode *node, void *user)
{
    wx_result r = NO_ATTRS();
    return r != WX_OK ? r : CHILDREN(geometry_children, user, NULL);
}
