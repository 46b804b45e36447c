// scene_xml_table.h: the table engine of the scene reader (private to io/scene_xml*.c):
// the parser's state and its errors ("scene.xml:LINE: message"), one table of
// the attributes an element allows (name, type, range, where the value goes)
// and one of the children it allows, so that an unknown element or attribute
// is an error that names it. Only the scene reader includes libxml2 (through
// this header; tests/test_layers.c).
#ifndef WX_SCENE_XML_TABLE_H
#define WX_SCENE_XML_TABLE_H

#include <limits.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include <libxml/tree.h>

#include "core/error.h"
#include "model/scene.h"

// ---------------------------------------------------------------------------
// Parser state and errors

typedef struct parser {
    const char *path; ///< the scene file as given, the prefix of every message
    wx_error *err;
    wx_scene *scene;
    int64_t field_cap, emitter_cap, camera_cap, mesh_cap, rule_cap, texture_cap;
    const xmlNode *collider; ///< <Collider>, once seen
    const xmlNode *substances; ///< <Substances>, read before everything else (or NULL)
    /// The line of each declared <Substance> (a mask may not take its name).
    int substance_lines[WX_MAX_SUBSTANCES];
    int output_map_line; ///< the output camera's <OutputMap>, 0 when it has none
    /// Every load and initial amount the scene gives, for check_amounts.
    struct amount_source *sources;
    int64_t source_count, source_cap;
} parser;

/// Where an amount comes from: an emitter's load of a substance (<Load>, or the
/// emitter's dirt=) or a surface's initial amount per square metre (<Exchange
/// initial>, or the <Surface>'s dirt=); Grow's amounts are the rules'.
typedef struct amount_source {
    bool load;          ///< else an initial amount
    int emitter;        ///< a load's emitter (index)
    int substance;
    double amount;
    int line;
    const char *element; ///< "<Load> amount", "<BoxEmitter> dirt", ...
} amount_source;

static inline int line_of(const xmlNode *node)
{
    long line = node != NULL ? xmlGetLineNo(node) : 0;
    return line > 0 && line < INT_MAX ? (int)line : 0;
}

static inline const char *name_of(const xmlNode *node)
{
    return (const char *)node->name;
}

static inline wx_result vfail_line(parser *p, int line, wx_cause cause, const char *fmt, va_list args)
{
    char message[WX_ERROR_MAX];
    vsnprintf(message, sizeof message, fmt, args);
    return wx_fail(p->err, cause, "%s:%d: %s", p->path, line, message);
}

/// "path:LINE: message" with the line of `node`; returns the cause's result.
static inline wx_result fail(parser *p, const xmlNode *node, wx_cause cause, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static inline wx_result fail(parser *p, const xmlNode *node, wx_cause cause, const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    wx_result r = vfail_line(p, line_of(node), cause, fmt, args);
    va_end(args);
    return r;
}

static inline wx_result fail_line(parser *p, int line, wx_cause cause, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static inline wx_result fail_line(parser *p, int line, wx_cause cause, const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    wx_result r = vfail_line(p, line, cause, fmt, args);
    va_end(args);
    return r;
}

static inline wx_result out_of_memory(parser *p)
{
    return wx_fail(p->err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", p->path);
}

// ---------------------------------------------------------------------------
// Attribute values

typedef enum attr_type {
    T_FLOAT,      ///< float, range by `range`
    T_DOUBLE,     ///< double, range by `range`
    T_INT,        ///< int in [lo, hi]
    T_INT64,      ///< int64_t in [lo, hi]
    T_UINT64,     ///< uint64_t, any
    T_BOOL,       ///< "true" or "false"
    T_VEC3,       ///< float[3], "x y z"
    T_MATRIX,     ///< float[16]
    T_RESOLUTION, ///< int[2], "px [py]" in [lo, hi]
    T_NAME,       ///< plain name: letters digits _ - . , not starting with '.'
    T_TEXT,       ///< any non-empty text (labels), into a buffer of `size`
    T_STRING,     ///< any non-empty text shorter than `size` (paths), as an owned char *
    T_ENUM,       ///< int: index into `choices`
} attr_type;

typedef enum attr_range {
    R_FINITE,    ///< any finite number
    R_POSITIVE,  ///< > 0
    R_NONNEG,    ///< >= 0
    R_UNIT,      ///< [0, 1]
    R_ELEVATION, ///< [-90, 90] (degrees above the horizon)
} attr_range;

typedef struct attr_spec {
    const char *name;
    attr_type type;
    size_t offset;  ///< where the value goes in the destination struct
    attr_range range;
    long long lo, hi;            ///< T_INT, T_INT64, T_RESOLUTION bounds (inclusive)
    size_t size;                 ///< T_NAME, T_TEXT: buffer size with the NUL; T_STRING: limit
    const char *const *choices;  ///< T_ENUM: NULL-terminated
    bool required;
} attr_spec;

#define ATTRS(table, dst, present) \
    xml_parse_attributes(p, node, table, (int)(sizeof table / sizeof table[0]), dst, present)
#define NO_ATTRS() xml_parse_attributes(p, node, NULL, 0, NULL, NULL)

// ---------------------------------------------------------------------------
// Child elements

typedef wx_result (*child_fn)(parser *p, const xmlNode *node, void *user);

typedef struct child_spec {
    const char *name;
    child_fn parse;
    bool repeat; ///< may appear more than once
} child_spec;

enum { MAX_CHILD_KINDS = 16 };

#define CHILDREN(table, user, seen) \
    xml_parse_children(p, node, table, (int)(sizeof table / sizeof table[0]), user, seen)
/// An element that holds no elements: any child is an unknown element.
#define NO_CHILDREN() xml_parse_children(p, node, NULL, 0, NULL, NULL)

#define LEAF(table, dst, present) \
    xml_parse_leaf(p, node, table, (int)(sizeof table / sizeof table[0]), dst, present)

// ---------------------------------------------------------------------------
// The engine (scene_xml_table.c)

/// Records an amount for check_amounts (0 needs no check).
wx_result xml_add_amount(parser *p, bool load, int emitter, int substance, double amount,
                         int line, const char *element);

/// Makes room for one more item at the end of a scene array of at most `max`
/// items (core/array.h): "too many WHAT (at most MAX)" at the element's line
/// when full, or out of memory.
wx_result xml_grow_list(parser *p, const xmlNode *node, void **items, int count,
                        int64_t *capacity, size_t item_size, int max, const char *what);

/// Checks the whole subtree of `element`: only elements, comments and
/// whitespace inside, no entity reference anywhere (also in attribute values).
wx_result xml_check_content(parser *p, const xmlNode *element);

/// Parses the attributes of `node` by its table into `dst`. An attribute that
/// is not in the table is an error naming it; `present` (may be NULL) gets bit i
/// set for each table entry i that the element gives.
wx_result xml_parse_attributes(parser *p, const xmlNode *node, const attr_spec *specs,
                               int count, void *dst, unsigned *present);

/// Parses the element children of `parent` by its table. `seen` (may be NULL)
/// gets, per table entry, the first element of that name or NULL.
wx_result xml_parse_children(parser *p, const xmlNode *parent, const child_spec *specs,
                             int count, void *user, const xmlNode **seen);

/// The attributes of an element without children.
wx_result xml_parse_leaf(parser *p, const xmlNode *node, const attr_spec *specs, int count,
                         void *dst, unsigned *present);

/// Resolves `file` against the scene's folder (absolute paths stay as they are)
/// into the owned string *out.
wx_result xml_resolve_path(parser *p, const xmlNode *node, const char *file, char **out);

#endif
