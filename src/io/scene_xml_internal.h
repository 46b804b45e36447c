// scene_xml_internal.h: what the files of the scene reader share (private to
// io/scene_xml*.c): the limits of a scene, the types two element groups use,
// and each group's entry points, which the root element's table calls.
#ifndef WX_SCENE_XML_INTERNAL_H
#define WX_SCENE_XML_INTERNAL_H

#include "io/scene_xml_table.h"

/// Limits that bound memory before anything else is checked.
#define SCENE_MAX_BYTES (64L * 1024 * 1024)
#define SCENE_MAX_CAMERAS 256
#define SCENE_MAX_FIELDS 10000
#define SCENE_MAX_EMITTERS 10000
#define SCENE_MAX_MESHES 1000
#define SCENE_MAX_SURFACES 10000
#define SCENE_MAX_TEXTURES 1000
/// <TextureMap padding>: texels of island bleed.
#define SCENE_MAX_PADDING 1024
#define SCENE_MAX_STEPS 1000000000LL
#define SCENE_MAX_COLLISIONS 1000000000LL
/// <Simulation iterations> and <OutputMap every>: a huge count is refused
/// rather than run for ever.
#define SCENE_MAX_ITERATIONS 100000
/// Ageing rules in <Ageing>, and in each <Surface>.
#define SCENE_MAX_RULES 1000
/// Buffer for a substance named by a Load, Exchange or rule: longer than any
/// declared name, so a long undeclared one is reported as undeclared.
#define SCENE_REF_MAX 128
/// <Accessibility rays>: rays per surface point (docs/design.md section 12).
#define SCENE_MAX_RAYS 4096

/// Reads and parses a scene file safely (no network, no entities): the
/// document, or an error naming the file and line.
wx_result xml_read_document(const char *path, xmlDocPtr *out, wx_error *err);

/// CTWMatrix must be the inverse of WTCMatrix to this relative tolerance
/// (wx_camera_inverse_error): matrices printed with 4-6 digits pass.
#define SCENE_INVERSE_TOLERANCE 1e-3f

/// Where rules go: the scene's global list or a surface's own.
typedef struct rule_list {
    wx_rule **rules;
    int *count;
    int64_t *capacity;
} rule_list;

typedef struct map_def {
    char *file; ///< owned
} map_def;

// ---------------------------------------------------------------------------
// <Solver>, <ForceFields>, <Emitters> (scene_xml_particles.c)

wx_result xml_parse_solver(parser *p, const xmlNode *node, void *user);

wx_result xml_parse_force_fields(parser *p, const xmlNode *node, void *user);

wx_result xml_parse_emitters(parser *p, const xmlNode *node, void *user);

/// Emitter end times default to the end of the simulation, known only now.
wx_result xml_finish_emitters(parser *p);

// ---------------------------------------------------------------------------
// <Substances> and the ageing rules (scene_xml_substances.c)

/// Letters, digits and '_', starting with a letter (ASCII, whatever the locale).
bool xml_is_substance_name(const char *name);

/// Read before the other children of <Weathering> (parse_root).
wx_result xml_parse_substances(parser *p, const xmlNode *node, void *user);

/// The main pass meets <Substances> again: it was read first.
wx_result xml_skip_substances(parser *p, const xmlNode *node, void *user);

/// The index of the substance that attribute `attr` of `node` names; an
/// undeclared one is an error at the element's line.
wx_result xml_find_substance(parser *p, const xmlNode *node, const char *attr,
                             const char *name, int *index);

wx_result xml_parse_transfer(parser *p, const xmlNode *node, void *user);

wx_result xml_parse_decay(parser *p, const xmlNode *node, void *user);

wx_result xml_parse_grow(parser *p, const xmlNode *node, void *user);
wx_result xml_parse_seed(parser *p, const xmlNode *node, void *user);
wx_result xml_parse_spread(parser *p, const xmlNode *node, void *user);
wx_result xml_parse_crack(parser *p, const xmlNode *node, void *user);
wx_result xml_parse_peel(parser *p, const xmlNode *node, void *user);

/// <Ageing>: the global rules, run on every surface texel after each iteration.
wx_result xml_parse_ageing(parser *p, const xmlNode *node, void *user);

// ---------------------------------------------------------------------------
// <Collider>, <ProjectedMaps>, <Ortho> (scene_xml_cameras.c)

wx_result xml_parse_collider(parser *p, const xmlNode *node, void *user);

// ---------------------------------------------------------------------------
// <Geometry> (scene_xml_geometry.c)

wx_result xml_parse_geometry(parser *p, const xmlNode *node, void *user);

// ---------------------------------------------------------------------------
// <Masks> (scene_xml_masks.c)

/// <Masks>: after <Substances> (read first), since names are shared and terms
/// name substances; an empty <Masks> is no mask at all.
wx_result xml_parse_masks(parser *p, const xmlNode *node, void *user);

// ---------------------------------------------------------------------------
// The checks that need the whole scene (scene_xml_checks.c)

/// The checks that need the whole scene, once every element is read, in this
/// order: the mask's and the textures' names, their lengths, the amounts, the
/// per-surface rules.
wx_result xml_check_scene(parser *p);

#endif
