// scene_xml.c: loads and validates a scene file (docs/design.md sections 3, 8,
// 9, 10, 11 and 12) with libxml2.
//
// The document is parsed without network access, entity substitution or
// XInclude; any entity declaration stops the parser at once (so an entity bomb
// or an external entity never expands), and libxml2 prints nothing: its first
// error becomes "scene.xml:LINE: message". The tree is then walked element by
// element. Each element has one table of the attributes it allows (name, type,
// range, where the value goes) and one table of the children it allows, so an
// unknown element or attribute is an error that names it. Once the whole file is
// read, the checks that need the whole picture run (emitter end times, map
// files and their sizes, names that must be unique, per-surface rules against
// pre-rendered maps). <Substances> is read first, wherever it stands, since
// loads, exchanges, rules and the terms of <Masks> name its substances. Choices
// where docs/design.md is silent are written down in docs/scene-format-notes.md.
#include "io/scene_xml.h"

#include <errno.h>
#include <float.h>
#include <limits.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <libxml/parser.h>
#include <libxml/tree.h>
#include <libxml/xmlerror.h>

#include "core/array.h"
#include "core/matrix.h"
#include "io/exr.h"
#include "core/input_file.h"
#include "model/mesh.h"
#include "model/naming.h"

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

/// CTWMatrix must be the inverse of WTCMatrix to this relative tolerance
/// (wx_camera_inverse_error): matrices printed with 4-6 digits pass.
#define SCENE_INVERSE_TOLERANCE 1e-3f

#define XSI_NAMESPACE "http://www.w3.org/2001/XMLSchema-instance"

/// The elements of a camera's maps, in model/naming.h's order of the kinds.
static const char *const map_elements[WX_MAP_KINDS] = { "DepthMap", "NormalMap", "ImpactMap",
                                                        "DirtMap" };

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

static int line_of(const xmlNode *node)
{
    long line = node != NULL ? xmlGetLineNo(node) : 0;
    return line > 0 && line < INT_MAX ? (int)line : 0;
}

static const char *name_of(const xmlNode *node)
{
    return (const char *)node->name;
}

static wx_result vfail_line(parser *p, int line, wx_cause cause, const char *fmt, va_list args)
{
    char message[WX_ERROR_MAX];
    vsnprintf(message, sizeof message, fmt, args);
    return wx_fail(p->err, cause, "%s:%d: %s", p->path, line, message);
}

/// "path:LINE: message" with the line of `node`; returns the cause's result.
static wx_result fail(parser *p, const xmlNode *node, wx_cause cause, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static wx_result fail(parser *p, const xmlNode *node, wx_cause cause, const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    wx_result r = vfail_line(p, line_of(node), cause, fmt, args);
    va_end(args);
    return r;
}

static wx_result fail_line(parser *p, int line, wx_cause cause, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static wx_result fail_line(parser *p, int line, wx_cause cause, const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    wx_result r = vfail_line(p, line, cause, fmt, args);
    va_end(args);
    return r;
}

static wx_result out_of_memory(parser *p)
{
    return wx_fail(p->err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", p->path);
}

/// Records an amount for check_amounts (0 needs no check).
static wx_result add_amount(parser *p, bool load, int emitter, int substance, double amount,
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
static wx_result grow_list(parser *p, const xmlNode *node, void **items, int count,
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
// Reading the document: libxml2 quiet, no entities

typedef struct xml_errors {
    bool set;
    int line;
    wx_cause cause;
    char message[WX_ERROR_MAX];
} xml_errors;

static void record_xml_error(xml_errors *st, int line, wx_cause cause, const char *message)
{
    if (st->set) {
        return;
    }
    st->set = true;
    st->line = line;
    st->cause = cause;
    snprintf(st->message, sizeof st->message, "%s", message != NULL ? message : "parse error");
    size_t n = strlen(st->message);
    while (n > 0 && (st->message[n - 1] == '\n' || st->message[n - 1] == ' ')) {
        st->message[--n] = '\0';
    }
    // One line: libxml2 puts the offending bytes on a line of their own
    // ("...encoding !\nBytes: 0xC8 ...").
    for (char *c = st->message; *c != '\0'; ++c) {
        if ((unsigned char)*c < 0x20) {
            *c = ' ';
        }
    }
}

#if LIBXML_VERSION >= 21200
static void on_xml_error(void *data, const xmlError *e)
#else
static void on_xml_error(void *data, xmlErrorPtr e)
#endif
{
    if (e != NULL && e->level >= XML_ERR_ERROR) {
        record_xml_error(data, e->line, WX_CAUSE_XML_SYNTAX, e->message);
    }
}

// Any entity declaration (general or parameter, internal or external) stops the
// parser before the entity can be used, so nothing is ever expanded or fetched.
static void on_entity_decl(void *ctx, const xmlChar *name, int type, const xmlChar *public_id,
                           const xmlChar *system_id, xmlChar *content)
{
    (void)type;
    (void)public_id;
    (void)system_id;
    (void)content;
    xmlParserCtxtPtr ctxt = ctx;
    xml_errors *st = ctxt->_private;
    char message[256];
    snprintf(message, sizeof message,
             "entity declarations are not allowed in a scene file (entity '%.100s')",
             name != NULL ? (const char *)name : "");
    record_xml_error(st, ctxt->input != NULL ? ctxt->input->line : 0, WX_CAUSE_XML_CONTENT,
                     message);
    xmlStopParser(ctxt);
}

static wx_result read_file(const char *path, char **text, size_t *size, wx_error *err)
{
    *text = NULL;
    *size = 0;
    char why[WX_INPUT_WHY_MAX];
    wx_cause cause = WX_CAUSE_NONE;
    int fd = wx_open_regular(path, why, &cause); // never waits on a FIFO
    FILE *f = fd >= 0 ? fdopen(fd, "rb") : NULL;
    if (f == NULL) {
        if (fd >= 0) {
            snprintf(why, sizeof why, "cannot open (%s)", strerror(errno));
            cause = WX_CAUSE_OUT_OF_MEMORY;
            close(fd);
        }
        return wx_fail(err, cause, "%s: %s", path, why);
    }
    struct stat st;
    if (fstat(fileno(f), &st) != 0) {
        int e = errno;
        fclose(f);
        return wx_fail(err, WX_CAUSE_UNREADABLE, "%s: cannot open (%s)", path, strerror(e));
    }
    if (st.st_size > SCENE_MAX_BYTES) {
        fclose(f);
        return wx_fail(err, WX_CAUSE_TOO_MANY, "%s: scene file too large (over %ld bytes)", path,
                            SCENE_MAX_BYTES);
    }
    char *buf = malloc((size_t)st.st_size + 1);
    if (buf == NULL) {
        fclose(f);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    size_t got = fread(buf, 1, (size_t)st.st_size, f);
    bool failed = ferror(f) != 0;
    fclose(f);
    if (failed) {
        free(buf);
        return wx_fail(err, WX_CAUSE_IO, "%s: read error", path);
    }
    buf[got] = '\0';
    *text = buf;
    *size = got;
    return WX_OK;
}

/// Parses `size` bytes of scene text; `path` names it in messages.
static wx_result parse_document(const char *path, const char *text, size_t size, xmlDocPtr *out,
                                wx_error *err)
{
    *out = NULL;
    if (size > (size_t)SCENE_MAX_BYTES) {
        return wx_fail(err, WX_CAUSE_TOO_MANY, "%s: scene file too large (over %ld bytes)", path,
                       SCENE_MAX_BYTES);
    }
    xmlParserCtxtPtr ctxt = xmlNewParserCtxt();
    if (ctxt == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    xml_errors st = { 0 };
    ctxt->_private = &st;
    ctxt->sax->entityDecl = on_entity_decl;
    xmlStructuredErrorFunc old_handler = xmlStructuredError;
    void *old_context = xmlStructuredErrorContext;
    xmlSetStructuredErrorFunc(&st, on_xml_error);
    xmlDocPtr doc = xmlCtxtReadMemory(ctxt, text, (int)size, path, NULL,
                                      XML_PARSE_NONET | XML_PARSE_NOBLANKS | XML_PARSE_BIG_LINES);
    bool well_formed = ctxt->wellFormed != 0;
    xmlSetStructuredErrorFunc(old_context, old_handler);
    xmlFreeParserCtxt(ctxt);
    if (st.set || doc == NULL || !well_formed) {
        xmlFreeDoc(doc);
        if (st.set) {
            return wx_fail(err, st.cause, "%s:%d: %s", path, st.line, st.message);
        }
        return wx_fail(err, WX_CAUSE_XML_SYNTAX, "%s: not a well-formed XML document", path);
    }
    *out = doc;
    return WX_OK;
}

static wx_result read_document(const char *path, xmlDocPtr *out, wx_error *err)
{
    *out = NULL;
    char *text;
    size_t size;
    wx_result r = read_file(path, &text, &size, err);
    if (r == WX_OK) {
        r = parse_document(path, text, size, out, err);
        free(text);
    }
    return r;
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
static wx_result check_content(parser *p, const xmlNode *element)
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
            wx_result r = check_content(p, n);
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
static wx_result parse_attributes(parser *p, const xmlNode *node, const attr_spec *specs,
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

#define ATTRS(table, dst, present) \
    parse_attributes(p, node, table, (int)(sizeof table / sizeof table[0]), dst, present)
#define NO_ATTRS() parse_attributes(p, node, NULL, 0, NULL, NULL)

// ---------------------------------------------------------------------------
// Child elements

typedef wx_result (*child_fn)(parser *p, const xmlNode *node, void *user);

typedef struct child_spec {
    const char *name;
    child_fn parse;
    bool repeat; ///< may appear more than once
} child_spec;

enum { MAX_CHILD_KINDS = 16 };

/// Parses the element children of `parent` by its table. `seen` (may be NULL)
/// gets, per table entry, the first element of that name or NULL.
static wx_result parse_children(parser *p, const xmlNode *parent, const child_spec *specs,
                                int count, void *user, const xmlNode **seen)
{
    const xmlNode *first[MAX_CHILD_KINDS] = { 0 };
    for (const xmlNode *n = parent->children; n != NULL; n = n->next) {
        if (n->type != XML_ELEMENT_NODE) {
            continue; // comments and whitespace; check_content refused the rest
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

#define CHILDREN(table, user, seen) \
    parse_children(p, node, table, (int)(sizeof table / sizeof table[0]), user, seen)
/// An element that holds no elements: any child is an unknown element.
#define NO_CHILDREN() parse_children(p, node, NULL, 0, NULL, NULL)

/// The attributes of an element without children.
static wx_result parse_leaf(parser *p, const xmlNode *node, const attr_spec *specs, int count,
                            void *dst, unsigned *present)
{
    wx_result r = parse_attributes(p, node, specs, count, dst, present);
    return r != WX_OK ? r : NO_CHILDREN();
}

#define LEAF(table, dst, present) \
    parse_leaf(p, node, table, (int)(sizeof table / sizeof table[0]), dst, present)

// ---------------------------------------------------------------------------
// Paths

/// Resolves `file` against the scene's folder (absolute paths stay as they are)
/// into the owned string *out.
static wx_result resolve_path(parser *p, const xmlNode *node, const char *file, char **out)
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

static wx_result parse_solver(parser *p, const xmlNode *node, void *user)
{
    wx_result r = NO_ATTRS();
    return r != WX_OK ? r : CHILDREN(solver_children, user, NULL);
}

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
static bool is_substance_name(const char *name)
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
    if (!is_substance_name(d.name)) {
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
static wx_result parse_substances(parser *p, const xmlNode *node, void *user)
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
static wx_result skip_substances(parser *p, const xmlNode *node, void *user)
{
    (void)p;
    (void)node;
    (void)user;
    return WX_OK;
}

/// The index of the substance that attribute `attr` of `node` names; an
/// undeclared one is an error at the element's line.
static wx_result find_substance(parser *p, const xmlNode *node, const char *attr,
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

/// Where rules go: the scene's global list or a surface's own.
typedef struct rule_list {
    wx_rule **rules;
    int *count;
    int64_t *capacity;
} rule_list;

typedef struct rule_def {
    char from[SCENE_REF_MAX], to[SCENE_REF_MAX], substance[SCENE_REF_MAX];
    float rate, amount;
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

/// Appends the rule `node` gives to `user` (a rule_list, or a struct that
/// starts with one).
static wx_result parse_rule(parser *p, const xmlNode *node, wx_rule_kind kind, void *user)
{
    rule_list *list = user;
    rule_def d = { .rate = 0.0f };
    wx_result r = WX_OK;
    wx_rule rule = { .kind = kind, .substance = -1, .to = -1, .line = line_of(node) };
    switch (kind) {
    case WX_RULE_TRANSFER:
        if ((r = LEAF(transfer_attrs, &d, NULL)) == WX_OK &&
            (r = find_substance(p, node, "from", d.from, &rule.substance)) == WX_OK) {
            r = find_substance(p, node, "to", d.to, &rule.to);
        }
        if (r == WX_OK && rule.substance == rule.to) {
            return fail(p, node, WX_CAUSE_BAD_VALUE,
                        "<Transfer> from and to are the same substance '%s'", d.from);
        }
        break;
    case WX_RULE_DECAY:
        if ((r = LEAF(decay_attrs, &d, NULL)) == WX_OK) {
            r = find_substance(p, node, "substance", d.substance, &rule.substance);
        }
        break;
    case WX_RULE_GROW:
        if ((r = LEAF(grow_attrs, &d, NULL)) == WX_OK) {
            r = find_substance(p, node, "substance", d.substance, &rule.substance);
        }
        break;
    }
    if (r != WX_OK) {
        return r;
    }
    rule.rate = kind == WX_RULE_GROW ? 0.0f : d.rate;
    rule.amount = kind == WX_RULE_GROW ? d.amount : 0.0f;
    r = grow_list(p, node, (void **)list->rules, *list->count, list->capacity, sizeof rule,
                  SCENE_MAX_RULES, "ageing rules");
    if (r != WX_OK) {
        return r;
    }
    (*list->rules)[(*list->count)++] = rule;
    return WX_OK;
}

static wx_result parse_transfer(parser *p, const xmlNode *node, void *user)
{
    return parse_rule(p, node, WX_RULE_TRANSFER, user);
}

static wx_result parse_decay(parser *p, const xmlNode *node, void *user)
{
    return parse_rule(p, node, WX_RULE_DECAY, user);
}

static wx_result parse_grow(parser *p, const xmlNode *node, void *user)
{
    return parse_rule(p, node, WX_RULE_GROW, user);
}

static const child_spec ageing_children[] = {
    { "Transfer", parse_transfer, true },
    { "Decay", parse_decay, true },
    { "Grow", parse_grow, true },
};

/// <Ageing>: the global rules, run on every surface texel after each iteration.
static wx_result parse_ageing(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    wx_scene *s = p->scene;
    rule_list list = { .rules = &s->rules, .count = &s->rule_count, .capacity = &p->rule_cap };
    wx_result r = NO_ATTRS();
    return r != WX_OK ? r : CHILDREN(ageing_children, &list, NULL);
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
    wx_result r = grow_list(p, node, (void **)&s->fields, s->field_count, &p->field_cap,
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

static wx_result parse_force_fields(parser *p, const xmlNode *node, void *user)
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
    if (r != WX_OK || (r = find_substance(p, node, "substance", d.substance, &k)) != WX_OK) {
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
    return add_amount(p, true, (int)(st->e - p->scene->emitters), k, d.amount, line_of(node),
                      "<Load> amount");
}

static const child_spec load_children[] = {
    { "Load", parse_load, true },
};

static wx_result parse_emitter(parser *p, const xmlNode *node, wx_emitter_kind kind)
{
    wx_scene *s = p->scene;
    wx_result r = grow_list(p, node, (void **)&s->emitters, s->emitter_count, &p->emitter_cap,
                            sizeof *s->emitters, SCENE_MAX_EMITTERS, "emitters");
    if (r != WX_OK) {
        return r;
    }
    wx_emitter *e = &s->emitters[s->emitter_count++];
    // end = NAN until the simulation's duration is known (finish_emitters).
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
        r = add_amount(p, true, s->emitter_count - 1, s->dirt_substance,
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

static wx_result parse_emitters(parser *p, const xmlNode *node, void *user)
{
    wx_result r = NO_ATTRS();
    return r != WX_OK ? r : CHILDREN(emitter_children, user, NULL);
}

/// Emitter end times default to the end of the simulation, known only now.
static wx_result finish_emitters(parser *p)
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

// ---------------------------------------------------------------------------
// <Collider>, <ProjectedMaps>, <Ortho>

static const attr_spec collider_attrs[] = {
    { "resilience", T_FLOAT, offsetof(wx_collider_def, resilience), .range = R_UNIT },
    { "friction", T_FLOAT, offsetof(wx_collider_def, friction), .range = R_UNIT },
    { "adherence", T_FLOAT, offsetof(wx_collider_def, adherence), .range = R_NONNEG },
    { "deposit", T_FLOAT, offsetof(wx_collider_def, deposit), .range = R_NONNEG },
    { "erosion", T_FLOAT, offsetof(wx_collider_def, erosion), .range = R_NONNEG },
};

typedef struct ortho_attrs_def {
    char name[64];
    bool out;
    int layers;
} ortho_attrs_def;

static const attr_spec ortho_attrs[] = {
    { "cameraName", T_NAME, offsetof(ortho_attrs_def, name),
      .size = sizeof(((ortho_attrs_def *)0)->name), .required = true },
    { "out", T_BOOL, offsetof(ortho_attrs_def, out), .range = R_FINITE },
    // docs/design.md section 14: the crossings each texel records.
    { "layers", T_INT, offsetof(ortho_attrs_def, layers), .lo = 1, .hi = WX_MAX_LAYERS },
};

typedef struct matrix_def {
    float m[16];
} matrix_def;

static const attr_spec matrix_attrs[] = {
    { "matrix", T_MATRIX, offsetof(matrix_def, m), .required = true },
};

typedef struct map_def {
    char *file; ///< owned
} map_def;

static const attr_spec map_attrs[] = {
    { "file", T_STRING, offsetof(map_def, file), .size = WX_PATH_MAX, .required = true },
};

typedef struct output_def {
    char file[256];
    int width, height;
    float radius;
    int second_pass;
    bool normalize;
    float noise, max_radius;
    int every;
} output_def;

static const char *const second_pass_names[] = { "mean", "sum", NULL };

enum { OUT_FILE, OUT_WIDTH, OUT_HEIGHT, OUT_RADIUS, OUT_SECOND_PASS, OUT_NORMALIZE, OUT_NOISE,
       OUT_MAX_RADIUS, OUT_EVERY }; // bits of `present`

static const attr_spec output_attrs[] = {
    [OUT_FILE] = { "file", T_NAME, offsetof(output_def, file),
                   .size = sizeof(((output_def *)0)->file) },
    [OUT_WIDTH] = { "width", T_INT, offsetof(output_def, width), .lo = 1, .hi = WX_MAP_MAX_SIDE },
    [OUT_HEIGHT] = { "height", T_INT, offsetof(output_def, height), .lo = 1,
                     .hi = WX_MAP_MAX_SIDE },
    [OUT_RADIUS] = { "radius", T_FLOAT, offsetof(output_def, radius), .range = R_NONNEG },
    [OUT_SECOND_PASS] = { "secondPass", T_ENUM, offsetof(output_def, second_pass),
                          .choices = second_pass_names },
    [OUT_NORMALIZE] = { "normalize", T_BOOL, offsetof(output_def, normalize) },
    [OUT_NOISE] = { "noise", T_FLOAT, offsetof(output_def, noise), .range = R_POSITIVE },
    [OUT_MAX_RADIUS] = { "maxRadius", T_FLOAT, offsetof(output_def, max_radius),
                         .range = R_POSITIVE },
    // docs/design.md section 10: BASE.NNNN.exr after every k-th iteration (0: none).
    [OUT_EVERY] = { "every", T_INT, offsetof(output_def, every), .lo = 0,
                    .hi = SCENE_MAX_ITERATIONS },
};

typedef struct view_def {
    float eye[3], target[3], up[3];
    float width, height;
    int resolution[2];
} view_def;

static const attr_spec view_attrs[] = {
    { "eye", T_VEC3, offsetof(view_def, eye), .required = true },
    { "target", T_VEC3, offsetof(view_def, target), .required = true },
    { "up", T_VEC3, offsetof(view_def, up), .range = R_FINITE },
    { "width", T_FLOAT, offsetof(view_def, width), .range = R_POSITIVE, .required = true },
    { "height", T_FLOAT, offsetof(view_def, height), .range = R_POSITIVE, .required = true },
    { "resolution", T_RESOLUTION, offsetof(view_def, resolution), .lo = 1,
      .hi = WX_MAP_MAX_SIDE, .required = true },
};

/// What one <Ortho> says, before it is checked as a whole.
typedef struct ortho_def {
    wx_scene_camera *cam;
    const xmlNode *ctw_node, *wtc_node, *view_node, *output_node;
    float ctw[16], wtc[16];
    const xmlNode *map_nodes[WX_MAP_KINDS];
    char *map_files[WX_MAP_KINDS]; ///< as written in the scene (owned)
    unsigned output_present;
} ortho_def;

static wx_result parse_matrix(parser *p, const xmlNode *node, void *user)
{
    ortho_def *o = user;
    bool is_ctw = strcmp(name_of(node), "CTWMatrix") == 0;
    matrix_def m;
    wx_result r = LEAF(matrix_attrs, &m, NULL);
    if (r != WX_OK) {
        return r;
    }
    memcpy(is_ctw ? o->ctw : o->wtc, m.m, sizeof m.m);
    *(is_ctw ? &o->ctw_node : &o->wtc_node) = node;
    return WX_OK;
}

static wx_result parse_map(parser *p, const xmlNode *node, void *user)
{
    ortho_def *o = user;
    int k = 0;
    while (k < WX_MAP_KINDS && strcmp(map_elements[k], name_of(node)) != 0) {
        ++k;
    }
    map_def m = { NULL };
    wx_result r = LEAF(map_attrs, &m, NULL);
    if (r == WX_OK) {
        free(o->map_files[k]);
        o->map_files[k] = m.file;
        o->map_nodes[k] = node;
    } else {
        free(m.file);
    }
    return r;
}

static wx_result parse_output_map(parser *p, const xmlNode *node, void *user)
{
    ortho_def *o = user;
    wx_scene_camera *cam = o->cam;
    output_def out = { .second_pass = WX_SECOND_PASS_MEAN, .noise = WX_DEFAULT_NOISE };
    snprintf(out.file, sizeof out.file, "mask.exr");
    wx_result r = LEAF(output_attrs, &out, &o->output_present);
    if (r != WX_OK) {
        return r;
    }
    size_t len = strlen(out.file);
    if (len < 5 || strcasecmp(out.file + len - 4, ".exr") != 0) {
        return fail(p, node, WX_CAUSE_BAD_VALUE, "<OutputMap> file=\"%s\" must end in .exr",
                    out.file);
    }
    memcpy(cam->output_file, out.file, sizeof out.file);
    cam->output_width = out.width;
    cam->output_height = out.height;
    cam->radius = out.radius;
    cam->noise = out.noise;
    cam->max_radius = out.max_radius;
    cam->second_pass = out.second_pass == 1 ? WX_SECOND_PASS_SUM : WX_SECOND_PASS_MEAN;
    cam->normalize = out.normalize;
    cam->every = out.every;
    o->output_node = node;
    if (cam->is_output) {
        p->output_map_line = line_of(node);
    }
    return WX_OK;
}

static wx_result parse_view(parser *p, const xmlNode *node, void *user)
{
    ortho_def *o = user;
    view_def v = { .up = { 0.0f, 1.0f, 0.0f } };
    wx_result r = LEAF(view_attrs, &v, NULL);
    if (r != WX_OK) {
        return r;
    }
    wx_view *view = &o->cam->view;
    memcpy(view->eye, v.eye, sizeof v.eye);
    memcpy(view->target, v.target, sizeof v.target);
    memcpy(view->up, v.up, sizeof v.up);
    view->width_ws = v.width;
    view->height_ws = v.height;
    view->width_px = v.resolution[0];
    view->height_px = v.resolution[1];
    o->cam->has_view = true;
    o->view_node = node;
    return WX_OK;
}

static const child_spec ortho_children[] = {
    { "CTWMatrix", parse_matrix, false }, { "WTCMatrix", parse_matrix, false },
    { "DepthMap", parse_map, false },     { "NormalMap", parse_map, false },
    { "ImpactMap", parse_map, false },    { "DirtMap", parse_map, false },
    { "OutputMap", parse_output_map, false }, { "View", parse_view, false },
};

/// Every later phase can use the camera's matrices (the collider's and the
/// gather's tests, made here so that a bad camera is refused at its line).
static wx_result check_camera(parser *p, const xmlNode *node, const wx_scene_camera *cam)
{
    const char *problem = wx_camera_problem(&cam->camera);
    if (problem != NULL) {
        return fail(p, node, WX_CAUSE_BAD_CAMERA, "camera '%s': %s", cam->name, problem);
    }
    return WX_OK;
}

/// The matrices of a camera: from its <View>, or both given (and checked), or
/// one given and the other its inverse.
static wx_result camera_matrices(parser *p, const xmlNode *node, ortho_def *o)
{
    wx_scene_camera *cam = o->cam;
    if (o->view_node != NULL) {
        if (o->ctw_node != NULL || o->wtc_node != NULL) {
            return fail(p, o->view_node, WX_CAUSE_BAD_SCENE,
                        "camera '%s' has both a <View> and a %s (ambiguous): give one or the other",
                        cam->name, o->wtc_node != NULL ? "<WTCMatrix>" : "<CTWMatrix>");
        }
        wx_error view_err;
        if (wx_camera_from_view(&cam->view, &cam->camera, &view_err) != WX_OK) {
            return fail(p, o->view_node, WX_CAUSE_BAD_CAMERA, "camera '%s': %s", cam->name,
                        view_err.message);
        }
        return check_camera(p, o->view_node, cam);
    }
    if (o->wtc_node == NULL && o->ctw_node == NULL) {
        return fail(p, node, WX_CAUSE_MISSING,
                    "camera '%s' needs a <WTCMatrix> (and/or <CTWMatrix>) or a <View>", cam->name);
    }
    if (o->wtc_node != NULL && o->ctw_node != NULL) {
        float error = wx_matrix_inverse_error(o->wtc, o->ctw);
        if (!(error <= SCENE_INVERSE_TOLERANCE)) {
            return fail(p, o->ctw_node, WX_CAUSE_BAD_CAMERA,
                        "<CTWMatrix> of camera '%s' is not the inverse of its <WTCMatrix> "
                        "(error %.3g, tolerance %g)",
                        cam->name, (double)error, (double)SCENE_INVERSE_TOLERANCE);
        }
        memcpy(cam->camera.wtc, o->wtc, sizeof o->wtc);
        memcpy(cam->camera.ctw, o->ctw, sizeof o->ctw);
    } else if (o->wtc_node != NULL) {
        memcpy(cam->camera.wtc, o->wtc, sizeof o->wtc);
        if (!wx_matrix_invert(o->wtc, cam->camera.ctw)) {
            return fail(p, o->wtc_node, WX_CAUSE_BAD_CAMERA,
                        "<WTCMatrix> of camera '%s' is singular", cam->name);
        }
    } else {
        memcpy(cam->camera.ctw, o->ctw, sizeof o->ctw);
        if (!wx_matrix_invert(o->ctw, cam->camera.wtc)) {
            return fail(p, o->ctw_node, WX_CAUSE_BAD_CAMERA,
                        "<CTWMatrix> of camera '%s' is singular", cam->name);
        }
    }
    return check_camera(p, o->wtc_node != NULL ? o->wtc_node : o->ctw_node, cam);
}

/// Which maps a camera must name, the ones it names, and their sizes.
static wx_result camera_maps(parser *p, const xmlNode *node, ortho_def *o)
{
    wx_scene_camera *cam = o->cam;
    char **paths[WX_MAP_KINDS] = { &cam->depth_path, &cam->normal_path, &cam->impact_path,
                                   &cam->dirt_path };
    int needed = cam->is_output ? 2 : 4; // depth, normal (+ impact, dirt for inputs)
    int named = 0;
    for (int k = 0; k < needed; ++k) {
        named += o->map_nodes[k] != NULL;
    }
    if (named < needed && (o->view_node == NULL || named > 0)) {
        int k = 0;
        while (o->map_nodes[k] != NULL) {
            ++k;
        }
        if (o->view_node == NULL) {
            return fail(p, node, WX_CAUSE_MISSING,
                        "camera '%s' needs a <%s> (or a <View> so that bake makes it)", cam->name,
                        map_elements[k]);
        }
        return fail(p, node, WX_CAUSE_MISSING,
                    "camera '%s' names some of its maps but not <%s>: with a <View>, name all "
                    "of them or none (bake writes them)",
                    cam->name, map_elements[k]);
    }
    const char *first_file = NULL;
    for (int k = 0; k < WX_MAP_KINDS; ++k) {
        const xmlNode *map = o->map_nodes[k];
        if (map == NULL) {
            continue;
        }
        const char *file = o->map_files[k];
        wx_result r = resolve_path(p, map, file, paths[k]);
        const char *path = *paths[k];
        if (r != WX_OK) {
            return r;
        }
        char why[WX_INPUT_WHY_MAX];
        wx_cause cause = WX_CAUSE_NONE;
        if (!wx_is_regular_file(path, why, &cause)) {
            return fail(p, map, cause, "map file '%s' %s", file,
                        cause == WX_CAUSE_FILE_MISSING ? "not found" : why);
        }
        wx_image header;
        wx_error exr_err;
        memset(&header, 0, sizeof header);
        r = wx_exr_read_header(path, &header, &exr_err);
        int w = header.width, h = header.height;
        wx_image_free(&header);
        if (r != WX_OK) {
            return fail(p, map, exr_err.cause, "%s map of camera '%s': %s", wx_map_kind_name(k),
                        cam->name, exr_err.message);
        }
        if (o->view_node != NULL) {
            if (w != cam->view.width_px || h != cam->view.height_px) {
                return fail(p, map, WX_CAUSE_MAP_SIZE,
                            "map file '%s' is %dx%d but the <View> resolution of camera '%s' is "
                            "%dx%d",
                            file, w, h, cam->name, cam->view.width_px, cam->view.height_px);
            }
        } else if (first_file == NULL) {
            cam->camera.width = w;
            cam->camera.height = h;
            first_file = file;
        } else if (w != cam->camera.width || h != cam->camera.height) {
            return fail(p, map, WX_CAUSE_MAP_SIZE,
                        "map file '%s' is %dx%d but '%s' is %dx%d: the maps of camera '%s' "
                        "must agree in size",
                        file, w, h, first_file, cam->camera.width, cam->camera.height, cam->name);
        }
    }
    return WX_OK;
}

/// The <OutputMap> of the output camera, with its defaults.
static wx_result camera_output(parser *p, const xmlNode *node, ortho_def *o)
{
    wx_scene_camera *cam = o->cam;
    if (!cam->is_output) {
        if (o->output_node != NULL) {
            return fail(p, o->output_node, WX_CAUSE_BAD_SCENE,
                        "<OutputMap> in camera '%s', which is not the output camera (out=\"true\")",
                        cam->name);
        }
        return WX_OK;
    }
    if (o->output_node == NULL) {
        if (o->view_node == NULL) {
            return fail(p, node, WX_CAUSE_MISSING, "output camera '%s' needs an <OutputMap>",
                        cam->name);
        }
        snprintf(cam->output_file, sizeof cam->output_file, "mask.exr");
        cam->second_pass = WX_SECOND_PASS_MEAN;
        cam->noise = WX_DEFAULT_NOISE;
    }
    unsigned given = o->output_present;
    int w = cam->camera.width, h = cam->camera.height;
    if (!(given & (1u << OUT_WIDTH))) {
        cam->output_width = w;
    }
    if (!(given & (1u << OUT_HEIGHT))) {
        cam->output_height = h;
    }
    if (cam->output_width != w || cam->output_height != h) {
        return fail(p, o->output_node, WX_CAUSE_MAP_SIZE,
                    "<OutputMap> size %dx%d differs from the %dx%d maps of output camera '%s'",
                    cam->output_width, cam->output_height, w, h, cam->name);
    }
    // No radius: the adaptive smoothing, which noise and maxRadius tune.
    cam->adaptive = !(given & (1u << OUT_RADIUS));
    if (!cam->adaptive && (given & ((1u << OUT_NOISE) | (1u << OUT_MAX_RADIUS)))) {
        return fail(p, o->output_node, WX_CAUSE_BAD_SCENE,
                    "<OutputMap> gives a radius and %s: %s tunes the adaptive smoothing, which a "
                    "radius replaces; give one or the other",
                    given & (1u << OUT_NOISE) ? "noise" : "maxRadius",
                    given & (1u << OUT_NOISE) ? "noise" : "maxRadius");
    }
    if (cam->adaptive && cam->second_pass == WX_SECOND_PASS_SUM) {
        return fail(p, o->output_node, WX_CAUSE_BAD_SCENE,
                    "<OutputMap> secondPass=\"sum\" needs a radius (the thesis' unnormalised "
                    "sum is defined over a fixed radius)");
    }
    if (cam->adaptive && !(given & (1u << OUT_MAX_RADIUS))) {
        float frame_w, frame_h;
        wx_camera_frame_size(&cam->camera, &frame_w, &frame_h);
        cam->max_radius = WX_DEFAULT_MAX_RADIUS_TEXELS * frame_w / (float)cam->output_width;
    }
    return WX_OK;
}

/// `layers` (docs/design.md section 14) is for input cameras that bake peels:
/// the maps a scene names hold one layer, and the mask shows the first surface
/// the output camera sees.
static wx_result camera_layers(parser *p, const xmlNode *node, ortho_def *o)
{
    const wx_scene_camera *cam = o->cam;
    if (cam->layers <= 1) {
        return WX_OK;
    }
    if (cam->is_output) {
        return fail(p, node, WX_CAUSE_BAD_SCENE,
                    "output camera '%s' has layers=\"%d\": layers are for input cameras (the "
                    "mask shows the first surface the output camera sees); remove it",
                    cam->name, cam->layers);
    }
    for (int k = 0; k < WX_MAP_KINDS; ++k) {
        if (o->map_nodes[k] != NULL) {
            return fail(p, node, WX_CAUSE_BAD_SCENE,
                        "camera '%s' has layers=\"%d\" and names its map files: maps given as "
                        "files hold one layer; give it a <View> without map files so that "
                        "bake peels %d layers",
                        cam->name, cam->layers, cam->layers);
        }
    }
    return WX_OK;
}

static wx_result parse_ortho(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    wx_scene *s = p->scene;
    ortho_attrs_def attrs = { .out = false, .layers = 1 };
    wx_result r = ATTRS(ortho_attrs, &attrs, NULL);
    if (r != WX_OK) {
        return r;
    }
    for (int i = 0; i < s->camera_count; ++i) {
        if (strcmp(s->cameras[i].name, attrs.name) == 0) {
            return fail(p, node, WX_CAUSE_DUPLICATE,
                        "camera name '%s' is used twice (first at line %d)", attrs.name,
                        s->cameras[i].line);
        }
    }
    if (attrs.out && s->output_index >= 0) {
        const wx_scene_camera *first = &s->cameras[s->output_index];
        return fail(p, node, WX_CAUSE_DUPLICATE,
                    "camera '%s' is a second output camera (the first is '%s' at line %d); a scene "
                    "has at most one",
                    attrs.name, first->name, first->line);
    }
    if (s->camera_count < SCENE_MAX_CAMERAS && !attrs.out &&
        s->input_count >= WX_MAX_INPUT_CAMERAS) {
        return fail(p, node, WX_CAUSE_TOO_MANY,
                    "too many input cameras (the collider takes at most %d)",
                    WX_MAX_INPUT_CAMERAS);
    }
    r = grow_list(p, node, (void **)&s->cameras, s->camera_count, &p->camera_cap,
                  sizeof *s->cameras, SCENE_MAX_CAMERAS, "cameras");
    if (r != WX_OK) {
        return r;
    }
    wx_scene_camera *cam = &s->cameras[s->camera_count];
    memset(cam, 0, sizeof *cam);
    memcpy(cam->name, attrs.name, sizeof attrs.name);
    cam->is_output = attrs.out;
    cam->layers = attrs.layers;
    cam->line = line_of(node);
    if (attrs.out) {
        s->output_index = s->camera_count;
    } else {
        s->input_count++;
    }
    s->camera_count++;

    ortho_def o = { .cam = cam };
    if ((r = CHILDREN(ortho_children, &o, NULL)) == WX_OK &&
        (r = camera_matrices(p, node, &o)) == WX_OK && (r = camera_maps(p, node, &o)) == WX_OK &&
        (r = camera_layers(p, node, &o)) == WX_OK) {
        r = camera_output(p, node, &o);
    }
    for (int k = 0; k < WX_MAP_KINDS; ++k) {
        free(o.map_files[k]);
    }
    return r;
}

static const child_spec projected_maps_children[] = {
    { "Ortho", parse_ortho, true },
};

static wx_result parse_projected_maps(parser *p, const xmlNode *node, void *user)
{
    wx_result r = NO_ATTRS();
    if (r != WX_OK || (r = CHILDREN(projected_maps_children, user, NULL)) != WX_OK) {
        return r;
    }
    if (p->scene->input_count == 0) {
        return fail(p, node, WX_CAUSE_MISSING,
                    "no input camera: at least one <Ortho> must not be out=\"true\"");
    }
    return WX_OK;
}

static const child_spec collider_children[] = {
    { "ProjectedMaps", parse_projected_maps, false },
};

static wx_result parse_collider(parser *p, const xmlNode *node, void *user)
{
    p->collider = node;
    const xmlNode *seen[1];
    wx_result r = ATTRS(collider_attrs, &p->scene->collider, NULL);
    if (r != WX_OK || (r = CHILDREN(collider_children, user, seen)) != WX_OK) {
        return r;
    }
    if (seen[0] == NULL) {
        return fail(p, node, WX_CAUSE_MISSING,
                    "<Collider> needs a <ProjectedMaps> with the cameras");
    }
    return WX_OK;
}

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
    if (r != WX_OK || (r = find_substance(p, node, "substance", d.substance, &k)) != WX_OK) {
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
    return add_amount(p, false, -1, k, d.initial, line_of(node), "<Exchange> initial");
}

static const child_spec surface_children[] = {
    { "Exchange", parse_exchange, true },
    { "Transfer", parse_transfer, true },
    { "Decay", parse_decay, true },
    { "Grow", parse_grow, true },
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
    r = grow_list(p, node, (void **)&mesh->surfaces, mesh->surface_count, &m->surface_cap,
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
        r = add_amount(p, false, -1, s->dirt_substance, d.dirt, sf->line, "<Surface> dirt");
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
    r = grow_list(p, node, (void **)&s->textures, s->texture_count, &p->texture_cap,
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
    wx_result r = grow_list(p, node, (void **)&s->meshes, s->mesh_count, &p->mesh_cap,
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
    if (r == WX_OK && (r = resolve_path(p, node, file.file, &mesh->path)) == WX_OK &&
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

static wx_result parse_geometry(parser *p, const xmlNode *node, void *user)
{
    wx_result r = NO_ATTRS();
    return r != WX_OK ? r : CHILDREN(geometry_children, user, NULL);
}

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
    if (!is_substance_name(name)) {
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
    float constant, weight, offset, steepness;
} term_def;

// Bits of `present`.
enum { TM_MASK, TM_SUBSTANCE, TM_CONSTANT, TM_WEIGHT, TM_OFFSET, TM_STEEPNESS };

static const attr_spec term_attrs[] = {
    [TM_MASK] = { "mask", T_TEXT, offsetof(term_def, mask), .size = SCENE_REF_MAX },
    [TM_SUBSTANCE] = { "substance", T_TEXT, offsetof(term_def, substance),
                       .size = SCENE_REF_MAX },
    [TM_CONSTANT] = { "constant", T_FLOAT, offsetof(term_def, constant), .range = R_FINITE },
    [TM_WEIGHT] = { "weight", T_FLOAT, offsetof(term_def, weight), .range = R_FINITE },
    [TM_OFFSET] = { "offset", T_FLOAT, offsetof(term_def, offset), .range = R_FINITE },
    [TM_STEEPNESS] = { "steepness", T_FLOAT, offsetof(term_def, steepness), .range = R_NONNEG },
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
    static const int sources[] = { TM_MASK, TM_SUBSTANCE, TM_CONSTANT };
    int first = -1;
    for (int i = 0; i < 3; ++i) {
        if (!(given & (1u << sources[i]))) {
            continue;
        }
        if (first >= 0) {
            return fail(p, node, WX_CAUSE_BAD_SCENE,
                        "<Term> gives both %s and %s: a term has one source (mask, substance or "
                        "constant)",
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
        r = find_substance(p, node, "substance", d.substance, &t.index);
        break;
    case TM_CONSTANT:
        t.kind = WX_TERM_CONSTANT;
        t.constant = d.constant;
        break;
    default:
        return fail(p, node, WX_CAUSE_MISSING,
                    "<Term> needs one of mask, substance or constant");
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
};

/// <Masks>: after <Substances> (read first), since names are shared and terms
/// name substances; an empty <Masks> is no mask at all.
static wx_result parse_masks(parser *p, const xmlNode *node, void *user)
{
    wx_result r = NO_ATTRS();
    return r != WX_OK ? r : CHILDREN(masks_children, user, NULL);
}

// ---------------------------------------------------------------------------
// <Weathering> and the checks that need the whole scene

static const child_spec root_children[] = {
    { "Solver", parse_solver, false },         { "ForceFields", parse_force_fields, false },
    { "Emitters", parse_emitters, false },     { "Collider", parse_collider, false },
    { "Geometry", parse_geometry, false },     { "Substances", skip_substances, false },
    { "Ageing", parse_ageing, false },         { "Masks", parse_masks, false },
};

static const char *const rule_elements[] = { [WX_RULE_TRANSFER] = "Transfer",
                                             [WX_RULE_DECAY] = "Decay",
                                             [WX_RULE_GROW] = "Grow" };

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

/// The first <Substances> child of the root, read before the rest (a second
/// one is then refused as a duplicate by the main pass).
static wx_result read_substances_first(parser *p, const xmlNode *root)
{
    for (const xmlNode *n = root->children; n != NULL; n = n->next) {
        if (n->type == XML_ELEMENT_NODE && n->ns == NULL &&
            strcmp(name_of(n), "Substances") == 0) {
            return parse_substances(p, n, NULL);
        }
    }
    return WX_OK;
}

/// The mask must not take the name of a map that bake or simulate writes.
static wx_result check_output_name(parser *p)
{
    const wx_scene *s = p->scene;
    if (s->output_index < 0) {
        return WX_OK;
    }
    const wx_scene_camera *out = &s->cameras[s->output_index];
    for (int c = 0; c < s->camera_count; ++c) {
        for (int k = 0; k < WX_MAP_KINDS; ++k) {
            char name[128];
            wx_map_file_name(s->cameras[c].name, k, name, sizeof name);
            if (strcmp(name, out->output_file) == 0) {
                return fail_line(p, out->line, WX_CAUSE_BAD_SCENE,
                                 "<OutputMap> file=\"%s\" is the name of camera '%s''s %s map in "
                                 "the output folder; choose another",
                                 out->output_file, s->cameras[c].name, wx_map_kind_name(k));
            }
        }
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

/// Most previews one output writes: one per substance and per derived mask.
#define SCENE_MAX_PREVIEWS (WX_MAX_SUBSTANCES + WX_MAX_MASKS)

/// The previews of `file` (docs/design.md section 10): BASE.png for the one
/// channel Y of a scene with neither <Substances> nor <Masks>, else
/// BASE_NAME.png per substance and per mask (a TextureMap's seen has none).
/// Returns how many.
static int preview_names(const wx_scene *s, const char *file,
                         char names[SCENE_MAX_PREVIEWS][WX_OUTPUT_NAME_MAX])
{
    if (!s->substances_declared && s->mask_count == 0) {
        // BASE.png: `file` ends in .exr (parse_output_map, parse_texture_map),
        // so never BASE.preview.png here.
        wx_preview_name(file, names[0], WX_OUTPUT_NAME_MAX);
        return 1;
    }
    int n = 0;
    for (int k = 0; k < s->substance_count; ++k) {
        wx_channel_preview_name(file, s->substances[k], names[n++], WX_OUTPUT_NAME_MAX);
    }
    for (int k = 0; k < s->mask_count; ++k) {
        wx_channel_preview_name(file, s->masks[k].name, names[n++], WX_OUTPUT_NAME_MAX);
    }
    return n;
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
    char mine[SCENE_MAX_PREVIEWS][WX_OUTPUT_NAME_MAX];
    char theirs[SCENE_MAX_PREVIEWS][WX_OUTPUT_NAME_MAX];
    int n_mine = preview_names(s, t->file, mine);
    int n_theirs = preview_names(s, e->file, theirs);
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
        for (int c = 0; c < s->camera_count; ++c) {
            for (int k = 0; k < WX_MAP_KINDS; ++k) {
                char name[128];
                wx_map_file_name(s->cameras[c].name, k, name, sizeof name);
                if (strcmp(name, tex->file) == 0) {
                    return fail_line(p, tex->line, WX_CAUSE_BAD_SCENE,
                                     "<TextureMap> file=\"%s\" is the name of camera '%s''s %s "
                                     "map in the output folder; choose another",
                                     tex->file, s->cameras[c].name, wx_map_kind_name(k));
                }
            }
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

/// `name` replaces the name the scene file's own name gives (the default
/// output folder out/NAME/): a scene that `run MESH` generated as scene.xml
/// keeps its mesh's name (docs/scene-format-notes.md).
static const attr_spec root_attrs[] = {
    { "name", T_NAME, offsetof(wx_scene, name), .size = sizeof(((wx_scene *)0)->name) },
};

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

static wx_result parse_root(parser *p, const xmlNode *node)
{
    if (node == NULL) {
        return wx_fail(p->err, WX_CAUSE_XML_SYNTAX, "%s: no root element", p->path);
    }
    if (node->ns != NULL || strcmp(name_of(node), "Weathering") != 0) {
        return fail(p, node, WX_CAUSE_UNKNOWN_NAME,
                    "the root element is <%s>, expected <Weathering>", name_of(node));
    }
    wx_result r = check_content(p, node);
    if (r != WX_OK || (r = ATTRS(root_attrs, p->scene, NULL)) != WX_OK ||
        (r = read_substances_first(p, node)) != WX_OK ||
        (r = CHILDREN(root_children, NULL, NULL)) != WX_OK) {
        return r;
    }
    if (p->collider == NULL) {
        return fail(p, node, WX_CAUSE_MISSING, "<Weathering> needs a <Collider> with the cameras");
    }
    if ((r = finish_emitters(p)) != WX_OK || (r = check_output_name(p)) != WX_OK ||
        (r = check_texture_names(p)) != WX_OK || (r = check_output_name_lengths(p)) != WX_OK ||
        (r = check_amounts(p)) != WX_OK) {
        return r;
    }
    return check_surface_rules(p);
}

// ---------------------------------------------------------------------------
// Public API

/// path, dir and name of the scene, and the defaults of everything else.
static wx_result scene_init(wx_scene *s, const char *path, wx_error *err)
{
    if (strlen(path) >= WX_PATH_MAX) {
        return wx_fail(err, WX_CAUSE_PATH_TOO_LONG, "%.200s...: path too long", path);
    }
    const char *slash = strrchr(path, '/');
    char dir[WX_PATH_MAX];
    if (slash == NULL) {
        snprintf(dir, sizeof dir, ".");
    } else if (slash == path) {
        snprintf(dir, sizeof dir, "/");
    } else {
        snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    }
    if (!wx_scene_set_path(&s->path, path) || !wx_scene_set_path(&s->dir, dir)) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    const char *base = slash != NULL ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    size_t len = dot != NULL && dot != base ? (size_t)(dot - base) : strlen(base);
    if (len >= sizeof s->name) {
        len = sizeof s->name - 1;
    }
    memcpy(s->name, base, len);
    s->name[len] = '\0';

    s->bbox_size = 100.0f;
    s->time_step = 0.01;
    s->steps = 1000;
    s->seed = 1;
    s->collider = wx_default_collider_def();
    s->output_index = -1;
    s->substance_count = 1;
    strcpy(s->substances[0], "dirt");
    s->dirt_substance = 0;
    s->iterations = 1;
    return WX_OK;
}

/// Loads the scene from its file, or from `text` (size bytes) when not NULL.
static wx_result scene_load(const char *path, const char *text, size_t size, wx_scene *out,
                            wx_error *err)
{
    memset(out, 0, sizeof *out);
    wx_result r = scene_init(out, path, err);
    xmlDocPtr doc = NULL;
    if (r == WX_OK) {
        r = text != NULL ? parse_document(path, text, size, &doc, err)
                         : read_document(path, &doc, err);
    }
    if (r == WX_OK) {
        // Numbers are read with '.' as the decimal point whatever the locale.
        locale_t c_locale = newlocale(LC_NUMERIC_MASK, "C", (locale_t)0);
        locale_t previous = c_locale != (locale_t)0 ? uselocale(c_locale) : (locale_t)0;
        parser p = { .path = path, .err = err, .scene = out };
        r = parse_root(&p, xmlDocGetRootElement(doc));
        free(p.sources);
        if (c_locale != (locale_t)0) {
            uselocale(previous);
            freelocale(c_locale);
        }
    }
    xmlFreeDoc(doc);
    if (r != WX_OK) {
        wx_scene_free(out);
    }
    return r;
}

wx_result wx_scene_load(const char *path, wx_scene *out, wx_error *err)
{
    return scene_load(path, NULL, 0, out, err);
}

wx_result wx_scene_load_text(const char *path, const char *text, size_t size, wx_scene *out,
                             wx_error *err)
{
    return scene_load(path, text, size, out, err);
}
