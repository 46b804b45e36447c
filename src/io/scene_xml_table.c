// scene_xml_table.c: the table engine of the scene reader (scene_xml_table.h):
// the content no element may hold, attribute values by their type and range,
// child elements by their table, and paths relative to the scene's folder.
#include "io/scene_xml_table.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/array.h"

#define XSI_NAMESPACE "http://www.w3.org/2001/XMLSchema-instance"

/// Records an amount for check_amounts (0 needs no check).
wx_result xml_add_amount(parser *p, bool load, int emitter, int substance, double amount,
                         int line, const char *element)
{
    if (!(amount > 0.0)) {
        return WX_OK;
    }
    if (!wx_array_reserve((void **)&p->sources, &p->source_cap, p->source_count + 1,
                          sizeof *p->sources, 16)) {
        return out_of_memory(p);
    }
    p->sources[p->source_count++] = (amount_source){ .load = load, .emitter = emitter,
                                                     .substance = substance, .amount = amount,
                                                     .line = line, .element = element };
    return WX_OK;
}

/// Makes room for one more item at the end of a scene array of at most `max`
/// items (core/array.h): "too many WHAT (at most MAX)" at the element's line
/// when full, or out of memory.
wx_result xml_grow_list(parser *p, const xmlNode *node, void **items, int count,
                        int64_t *capacity, size_t item_size, int max, const char *what)
{
    if (count >= max) {
        return fail(p, node, WX_CAUSE_TOO_MANY, "too many %s (at most %d)", what, max);
    }
    if (!wx_array_reserve(items, capacity, (int64_t)count + 1, item_size, 4)) {
        return out_of_memory(p);
    }
    return WX_OK;
}

// ---------------------------------------------------------------------------
// Content that is never allowed: text, entity references, processing instructions

static bool is_blank(const xmlChar *s)
{
    for (; s != NULL && *s != '\0'; ++s) {
        if (*s != ' ' && *s != '\t' && *s != '\n' && *s != '\r') {
            return false;
        }
    }
    return true;
}

/// Checks the whole subtree of `element`: only elements, comments and
/// whitespace inside, no entity reference anywhere (also in attribute values).
wx_result xml_check_content(parser *p, const xmlNode *element)
{
    for (const xmlAttr *a = element->properties; a != NULL; a = a->next) {
        for (const xmlNode *c = a->children; c != NULL; c = c->next) {
            if (c->type == XML_ENTITY_REF_NODE) {
                return fail(p, element, WX_CAUSE_XML_CONTENT,
                            "entity reference '&%s;' in attribute '%s' is not allowed", name_of(c),
                            (const char *)a->name);
            }
        }
    }
    for (const xmlNode *n = element->children; n != NULL; n = n->next) {
        switch (n->type) {
        case XML_ELEMENT_NODE: {
            wx_result r = xml_check_content(p, n);
            if (r != WX_OK) {
                return r;
            }
            break;
        }
        case XML_COMMENT_NODE:
            break;
        case XML_TEXT_NODE:
        case XML_CDATA_SECTION_NODE:
            if (!is_blank(n->content)) {
                const char *text = (const char *)n->content;
                while (*text == ' ' || *text == '\t' || *text == '\n' || *text == '\r') {
                    ++text;
                }
                int len = 0;
                while (len < 30 && text[len] != '\0' && text[len] != '\n' && text[len] != '\r') {
                    ++len;
                }
                // libxml2 gives a text node the line where it ends: count back
                // to the line of its first non-blank character.
                int line = line_of(n);
                for (const char *c = text; *c != '\0' && line > 0; ++c) {
                    line -= *c == '\n';
                }
                return fail_line(p, line > 0 ? line : line_of(element), WX_CAUSE_XML_CONTENT,
                                 "unexpected text '%.*s' in <%s>", len, text, name_of(element));
            }
            break;
        case XML_ENTITY_REF_NODE:
            return fail(p, element, WX_CAUSE_XML_CONTENT,
                        "entity reference '&%s;' in <%s> is not allowed", name_of(n),
                        name_of(element));
        case XML_PI_NODE:
            return fail(p, element, WX_CAUSE_XML_CONTENT,
                        "processing instruction '<?%s' in <%s> is not allowed", name_of(n),
                        name_of(element));
        default:
            return fail(p, element, WX_CAUSE_XML_CONTENT, "unexpected content in <%s>",
                        name_of(element));
        }
    }
    return WX_OK;
}

// ---------------------------------------------------------------------------
// Attribute values

static bool is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

/// Splits a whitespace-separated list of decimal numbers. Stores up to `max`
/// of them and returns how many there are, or -1 when one is not a number.
static int parse_numbers(const char *s, double *out, int max)
{
    int count = 0;
    for (;;) {
        while (is_space(*s)) {
            ++s;
        }
        if (*s == '\0') {
            return count;
        }
        const char *token = s;
        while (*s != '\0' && !is_space(*s)) {
            if (*s == 'x' || *s == 'X') {
                return -1; // no hexadecimal floats
            }
            ++s;
        }
        char *end;
        double v = strtod(token, &end);
        if (end != s || end == token) {
            return -1;
        }
        if (count < max) {
            out[count] = v;
        }
        ++count;
    }
}

/// A whole string holding one integer (optional sign, digits), with optional
/// surrounding whitespace. False when it is not one or overflows.
static bool parse_integer(const char *s, long long *out)
{
    while (is_space(*s)) {
        ++s;
    }
    const char *digits = (*s == '+' || *s == '-') ? s + 1 : s;
    if (*digits < '0' || *digits > '9') {
        return false;
    }
    errno = 0;
    char *end;
    long long v = strtoll(s, &end, 10);
    if (errno == ERANGE) {
        return false;
    }
    while (is_space(*end)) {
        ++end;
    }
    *out = v;
    return *end == '\0';
}

/// A whitespace-separated list of integers in [lo, hi]: stores up to `max` and
/// returns how many there are, or -1 when one is not such an integer.
static int parse_integers(const char *s, int *out, int max, long long lo, long long hi)
{
    int count = 0;
    for (;;) {
        while (is_space(*s)) {
            ++s;
        }
        if (*s == '\0') {
            return count;
        }
        char token[32];
        size_t len = 0;
        while (s[len] != '\0' && !is_space(s[len])) {
            ++len;
        }
        long long v;
        if (len >= sizeof token) {
            return -1;
        }
        memcpy(token, s, len);
        token[len] = '\0';
        if (!parse_integer(token, &v) || v < lo || v > hi) {
            return -1;
        }
        if (count < max) {
            out[count] = (int)v;
        }
        ++count;
        s += len;
    }
}

static bool parse_unsigned(const char *s, unsigned long long *out)
{
    while (is_space(*s)) {
        ++s;
    }
    const char *digits = *s == '+' ? s + 1 : s;
    if (*digits < '0' || *digits > '9') {
        return false;
    }
    errno = 0;
    char *end;
    unsigned long long v = strtoull(digits, &end, 10);
    if (errno == ERANGE) {
        return false;
    }
    while (is_space(*end)) {
        ++end;
    }
    *out = v;
    return *end == '\0';
}

/// The token of a list, trimmed, for messages: at most 40 characters.
static void trimmed(const char *s, char out[48])
{
    while (is_space(*s)) {
        ++s;
    }
    size_t n = strlen(s);
    while (n > 0 && is_space(s[n - 1])) {
        --n;
    }
    snprintf(out, 48, "%.*s%s", (int)(n > 40 ? 40 : n), s, n > 40 ? "..." : "");
}

/// "path:LINE: <Element> name="value" <what>" (WX_CAUSE_BAD_VALUE), the value
/// trimmed for the message.
static wx_result bad_value(parser *p, const xmlNode *node, const attr_spec *s, const char *text,
                           const char *fmt, ...) __attribute__((format(printf, 5, 6)));
static wx_result bad_value(parser *p, const xmlNode *node, const attr_spec *s, const char *text,
                           const char *fmt, ...)
{
    char shown[48], what[256];
    trimmed(text, shown);
    va_list args;
    va_start(args, fmt);
    vsnprintf(what, sizeof what, fmt, args);
    va_end(args);
    return fail(p, node, WX_CAUSE_BAD_VALUE, "<%s> %s=\"%s\" %s", name_of(node), s->name, shown,
                what);
}

static wx_result check_range(parser *p, const xmlNode *node, const attr_spec *s, const char *text,
                             double v)
{
    const char *what = NULL;
    switch (s->range) {
    case R_FINITE:
        break;
    case R_POSITIVE:
        what = v > 0.0 ? NULL : "> 0";
        break;
    case R_NONNEG:
        what = v >= 0.0 ? NULL : ">= 0";
        break;
    case R_UNIT:
        what = v >= 0.0 && v <= 1.0 ? NULL : "in [0, 1]";
        break;
    case R_ELEVATION:
        what = v >= -90.0 && v <= 90.0 ? NULL : "in [-90, 90]";
        break;
    }
    if (what != NULL) {
        return bad_value(p, node, s, text, "must be %s", what);
    }
    return WX_OK;
}

/// Parses numbers for T_FLOAT, T_DOUBLE, T_VEC3, T_MATRIX: exactly `want`
/// finite numbers (floats when `as_float`).
static wx_result parse_finite_list(parser *p, const xmlNode *node, const attr_spec *s,
                                   const char *text, double *values, int want, bool as_float)
{
    int count = parse_numbers(text, values, want);
    if (count < 0 || (want == 1 && count != 1)) {
        return bad_value(p, node, s, text, "is not a number%s", want == 1 ? "" : " list");
    }
    if (count != want) {
        return fail(p, node, WX_CAUSE_BAD_VALUE, "<%s> %s has %d numbers, expected %d",
                    name_of(node), s->name, count, want);
    }
    for (int i = 0; i < want; ++i) {
        if (!isfinite(values[i])) {
            return bad_value(p, node, s, text, "is not a finite number");
        }
        if (as_float) {
            float f = (float)values[i];
            if (!isfinite(f)) {
                return bad_value(p, node, s, text, "is out of range");
            }
            values[i] = f;
        }
    }
    return WX_OK;
}

/// T_FLOAT, T_DOUBLE (with their range), T_VEC3, T_MATRIX.
static wx_result parse_real_value(parser *p, const xmlNode *node, const attr_spec *s,
                                  const char *text, void *dst)
{
    double values[16];
    int want = s->type == T_VEC3 ? 3 : s->type == T_MATRIX ? 16 : 1;
    bool is_float = s->type != T_DOUBLE;
    wx_result r = parse_finite_list(p, node, s, text, values, want, is_float);
    if (r != WX_OK) {
        return r;
    }
    if (s->type == T_DOUBLE) {
        r = check_range(p, node, s, text, values[0]);
        memcpy(dst, &values[0], sizeof values[0]);
        return r;
    }
    float f[16];
    for (int i = 0; i < want; ++i) {
        f[i] = (float)values[i];
    }
    if (s->type == T_FLOAT) {
        r = check_range(p, node, s, text, f[0]);
    }
    memcpy(dst, f, sizeof f[0] * (size_t)want);
    return r;
}

/// T_INT, T_INT64, T_UINT64, T_RESOLUTION.
static wx_result parse_integer_value(parser *p, const xmlNode *node, const attr_spec *s,
                                     const char *text, void *dst)
{
    if (s->type == T_UINT64) {
        unsigned long long v;
        if (!parse_unsigned(text, &v)) {
            return bad_value(p, node, s, text, "is not an integer in [0, 2^64-1]");
        }
        uint64_t u = (uint64_t)v;
        memcpy(dst, &u, sizeof u);
        return WX_OK;
    }
    if (s->type == T_RESOLUTION) {
        int px[2];
        int count = parse_integers(text, px, 2, s->lo, s->hi);
        if (count < 1 || count > 2) {
            return bad_value(p, node, s, text, "must be one or two integers in [%lld, %lld]", s->lo,
                             s->hi);
        }
        if (count == 1) {
            px[1] = px[0];
        }
        memcpy(dst, px, sizeof px);
        return WX_OK;
    }
    long long v;
    if (!parse_integer(text, &v)) {
        return bad_value(p, node, s, text, "is not an integer");
    }
    if (v < s->lo || v > s->hi) {
        return bad_value(p, node, s, text, "must be in [%lld, %lld]", s->lo, s->hi);
    }
    if (s->type == T_INT) {
        int i = (int)v;
        memcpy(dst, &i, sizeof i);
    } else {
        int64_t i = (int64_t)v;
        memcpy(dst, &i, sizeof i);
    }
    return WX_OK;
}

/// T_BOOL ("true", "false") and T_ENUM (one of `choices`, stored as its index).
static wx_result parse_keyword_value(parser *p, const xmlNode *node, const attr_spec *s,
                                     const char *text, void *dst)
{
    char shown[48];
    trimmed(text, shown);
    if (s->type == T_BOOL) {
        bool b = strcmp(shown, "true") == 0;
        if (!b && strcmp(shown, "false") != 0) {
            return bad_value(p, node, s, text, "must be \"true\" or \"false\"");
        }
        memcpy(dst, &b, sizeof b);
        return WX_OK;
    }
    char list[256] = "";
    for (int i = 0; s->choices[i] != NULL; ++i) {
        if (strcmp(shown, s->choices[i]) == 0) {
            memcpy(dst, &i, sizeof i);
            return WX_OK;
        }
        wx_list_append(list, sizeof list, s->choices[i]);
    }
    return bad_value(p, node, s, text, "must be one of: %s", list);
}

static bool is_plain_name(const char *text)
{
    if (text[0] == '.') {
        return false; // no hidden files, no "." or ".."
    }
    for (const char *c = text; *c != '\0'; ++c) {
        bool ok = (*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') ||
                  (*c >= '0' && *c <= '9') || *c == '_' || *c == '-' || *c == '.';
        if (!ok) {
            return false;
        }
    }
    return true;
}

/// T_NAME (a plain name) and T_TEXT (any text without control characters).
static wx_result parse_text_value(parser *p, const xmlNode *node, const attr_spec *s,
                                  const char *text, void *dst)
{
    size_t len = strlen(text);
    if (len == 0) {
        return fail(p, node, WX_CAUSE_BAD_VALUE, "<%s> %s is empty", name_of(node), s->name);
    }
    if (len >= s->size) {
        return fail(p, node, WX_CAUSE_BAD_VALUE, "<%s> %s is too long (at most %zu characters)",
                    name_of(node), s->name, s->size - 1);
    }
    if (s->type == T_NAME && !is_plain_name(text)) {
        return bad_value(p, node, s, text,
                         "must be a plain name (letters, digits, '_', '-', '.', not starting "
                         "with '.'; no folders)");
    }
    for (size_t i = 0; i < len; ++i) {
        if ((unsigned char)text[i] < 0x20) {
            return fail(p, node, WX_CAUSE_BAD_VALUE, "<%s> %s holds a control character",
                        name_of(node), s->name);
        }
    }
    if (s->type == T_STRING) {
        char **slot = dst;
        return wx_scene_set_path(slot, text) ? WX_OK : out_of_memory(p);
    }
    memcpy(dst, text, len + 1);
    return WX_OK;
}

static wx_result parse_value(parser *p, const xmlNode *node, const attr_spec *s, const char *text,
                             void *dst)
{
    switch (s->type) {
    case T_FLOAT:
    case T_DOUBLE:
    case T_VEC3:
    case T_MATRIX:
        return parse_real_value(p, node, s, text, dst);
    case T_INT:
    case T_INT64:
    case T_UINT64:
    case T_RESOLUTION:
        return parse_integer_value(p, node, s, text, dst);
    case T_BOOL:
    case T_ENUM:
        return parse_keyword_value(p, node, s, text, dst);
    case T_NAME:
    case T_TEXT:
    case T_STRING:
        return parse_text_value(p, node, s, text, dst);
    }
    return fail(p, node, WX_CAUSE_BAD_ARGUMENT, "internal error: unknown attribute type");
}

/// Parses the attributes of `node` by its table into `dst`. An attribute that
/// is not in the table is an error naming it; `present` (may be NULL) gets bit i
/// set for each table entry i that the element gives.
wx_result xml_parse_attributes(parser *p, const xmlNode *node, const attr_spec *specs,
                               int count, void *dst, unsigned *present)
{
    unsigned seen = 0;
    for (const xmlAttr *a = node->properties; a != NULL; a = a->next) {
        const char *name = (const char *)a->name;
        if (a->ns != NULL) {
            // xsi:noNamespaceSchemaLocation and friends, on the root only.
            bool xsi = a->ns->href != NULL && strcmp((const char *)a->ns->href, XSI_NAMESPACE) == 0;
            if (xsi && node->parent != NULL && node->parent->type == XML_DOCUMENT_NODE) {
                continue;
            }
            return fail(p, node, WX_CAUSE_UNKNOWN_NAME, "unknown attribute '%s:%s' of <%s>",
                        a->ns->prefix != NULL ? (const char *)a->ns->prefix : "", name,
                        name_of(node));
        }
        int i = 0;
        while (i < count && strcmp(specs[i].name, name) != 0) {
            ++i;
        }
        if (i == count) {
            char allowed[512] = "";
            for (int k = 0; k < count; ++k) {
                wx_list_append(allowed, sizeof allowed, specs[k].name);
            }
            return fail(p, node, WX_CAUSE_UNKNOWN_NAME,
                        "unknown attribute '%s' of <%s> (allowed: %s)", name, name_of(node),
                        count > 0 ? allowed : "none");
        }
        xmlChar *value = xmlNodeListGetString(node->doc, a->children, 1);
        wx_result r = parse_value(p, node, &specs[i], value != NULL ? (const char *)value : "",
                                  (char *)dst + specs[i].offset);
        xmlFree(value);
        if (r != WX_OK) {
            return r;
        }
        seen |= 1u << i;
    }
    for (int i = 0; i < count; ++i) {
        if (specs[i].required && !(seen & (1u << i))) {
            return fail(p, node, WX_CAUSE_MISSING, "<%s> needs attribute '%s'", name_of(node),
                        specs[i].name);
        }
    }
    if (present != NULL) {
        *present = seen;
    }
    return WX_OK;
}

// ---------------------------------------------------------------------------
// Child elements

/// Parses the element children of `parent` by its table. `seen` (may be NULL)
/// gets, per table entry, the first element of that name or NULL.
wx_result xml_parse_children(parser *p, const xmlNode *parent, const child_spec *specs,
                             int count, void *user, const xmlNode **seen)
{
    const xmlNode *first[MAX_CHILD_KINDS] = { 0 };
    for (const xmlNode *n = parent->children; n != NULL; n = n->next) {
        if (n->type != XML_ELEMENT_NODE) {
            continue; // comments and whitespace; xml_check_content refused the rest
        }
        int i = 0;
        while (i < count && (n->ns != NULL || strcmp(specs[i].name, name_of(n)) != 0)) {
            ++i;
        }
        if (i == count) {
            char allowed[512] = "";
            for (int k = 0; k < count; ++k) {
                wx_list_append(allowed, sizeof allowed, specs[k].name);
            }
            return fail(p, n, WX_CAUSE_UNKNOWN_NAME,
                        "unknown element <%s%s%s> in <%s> (allowed: %s)",
                        n->ns != NULL && n->ns->prefix != NULL ? (const char *)n->ns->prefix : "",
                        n->ns != NULL && n->ns->prefix != NULL ? ":" : "", name_of(n),
                        name_of(parent), count > 0 ? allowed : "none");
        }
        if (first[i] != NULL && !specs[i].repeat) {
            return fail(p, n, WX_CAUSE_DUPLICATE, "<%s> appears twice in <%s> (first at line %d)",
                        name_of(n), name_of(parent), line_of(first[i]));
        }
        if (first[i] == NULL) {
            first[i] = n;
        }
        wx_result r = specs[i].parse(p, n, user);
        if (r != WX_OK) {
            return r;
        }
    }
    if (seen != NULL) {
        memcpy(seen, first, sizeof(first[0]) * (size_t)count);
    }
    return WX_OK;
}

/// The attributes of an element without children.
wx_result xml_parse_leaf(parser *p, const xmlNode *node, const attr_spec *specs, int count,
                         void *dst, unsigned *present)
{
    wx_result r = xml_parse_attributes(p, node, specs, count, dst, present);
    return r != WX_OK ? r : NO_CHILDREN();
}

// ---------------------------------------------------------------------------
// Paths

/// Resolves `file` against the scene's folder (absolute paths stay as they are)
/// into the owned string *out.
wx_result xml_resolve_path(parser *p, const xmlNode *node, const char *file, char **out)
{
    const char *dir = p->scene->dir;
    char joined[WX_PATH_MAX];
    int n;
    if (file[0] == '/' || strcmp(dir, ".") == 0) {
        n = snprintf(joined, sizeof joined, "%s", file);
    } else {
        size_t len = strlen(dir);
        n = snprintf(joined, sizeof joined, "%s%s%s", dir,
                     len > 0 && dir[len - 1] == '/' ? "" : "/", file);
    }
    if (n < 0 || n >= (int)sizeof joined) {
        return fail(p, node, WX_CAUSE_PATH_TOO_LONG, "path '%.200s...' is too long", file);
    }
    return wx_scene_set_path(out, joined) ? WX_OK : out_of_memory(p);
}
