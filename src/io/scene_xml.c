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
//
// The files of the reader: this one reads the document and the root element;
// scene_xml_table.c is the table engine; scene_xml_particles.c,
// scene_xml_substances.c, scene_xml_cameras.c, scene_xml_geometry.c and
// scene_xml_masks.c read the element groups; scene_xml_checks.c checks the
// whole scene.
#include "io/scene_xml.h"

#include <errno.h>
#include <locale.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <libxml/parser.h>
#include <libxml/xmlerror.h>

#include "core/input_file.h"
#include "io/scene_xml_internal.h"

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

wx_result xml_read_document(const char *path, xmlDocPtr *out, wx_error *err)
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
// <Tile> (docs/tiles.md): the region of a larger scene this scene is a tile of

typedef struct tile_attrs {
    double min_x, max_x, min_z, max_z, halo;
} tile_attrs;

static const attr_spec tile_specs[] = {
    { "minX", T_DOUBLE, offsetof(tile_attrs, min_x), .range = R_FINITE },
    { "maxX", T_DOUBLE, offsetof(tile_attrs, max_x), .range = R_FINITE },
    { "minZ", T_DOUBLE, offsetof(tile_attrs, min_z), .range = R_FINITE },
    { "maxZ", T_DOUBLE, offsetof(tile_attrs, max_z), .range = R_FINITE },
    { "halo", T_DOUBLE, offsetof(tile_attrs, halo), .range = R_NONNEG },
};

static wx_result parse_tile(parser *p, const xmlNode *node, void *user)
{
    (void)user;
    tile_attrs a = { 0 };
    unsigned given = 0;
    wx_result r = LEAF(tile_specs, &a, &given);
    if (r != WX_OK) {
        return r;
    }
    wx_tile_def *t = &p->scene->tile;
    t->present = true;
    t->min[0] = (given & 1u) ? a.min_x : -INFINITY;
    t->max[0] = (given & 2u) ? a.max_x : INFINITY;
    t->min[1] = (given & 4u) ? a.min_z : -INFINITY;
    t->max[1] = (given & 8u) ? a.max_z : INFINITY;
    t->halo = a.halo;
    t->line = line_of(node);
    if (!(t->min[0] < t->max[0]) || !(t->min[1] < t->max[1])) {
        return fail(p, node, WX_CAUSE_BAD_VALUE,
                    "<Tile>: the region is empty (minX must be below maxX, minZ below maxZ)");
    }
    return WX_OK;
}

// ---------------------------------------------------------------------------
// <Weathering>

static const child_spec root_children[] = {
    { "Solver", xml_parse_solver, false },         { "ForceFields", xml_parse_force_fields, false },
    { "Emitters", xml_parse_emitters, false },     { "Collider", xml_parse_collider, false },
    { "Geometry", xml_parse_geometry, false },     { "Substances", xml_skip_substances, false },
    { "Ageing", xml_parse_ageing, false },         { "Masks", xml_parse_masks, false },
    { "Tile", parse_tile, false },
};

/// The first <Substances> child of the root, read before the rest (a second
/// one is then refused as a duplicate by the main pass).
static wx_result read_substances_first(parser *p, const xmlNode *root)
{
    for (const xmlNode *n = root->children; n != NULL; n = n->next) {
        if (n->type == XML_ELEMENT_NODE && n->ns == NULL &&
            strcmp(name_of(n), "Substances") == 0) {
            return xml_parse_substances(p, n, NULL);
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

static wx_result parse_root(parser *p, const xmlNode *node)
{
    if (node == NULL) {
        return wx_fail(p->err, WX_CAUSE_XML_SYNTAX, "%s: no root element", p->path);
    }
    if (node->ns != NULL || strcmp(name_of(node), "Weathering") != 0) {
        return fail(p, node, WX_CAUSE_UNKNOWN_NAME,
                    "the root element is <%s>, expected <Weathering>", name_of(node));
    }
    wx_result r = xml_check_content(p, node);
    if (r != WX_OK || (r = ATTRS(root_attrs, p->scene, NULL)) != WX_OK ||
        (r = read_substances_first(p, node)) != WX_OK ||
        (r = CHILDREN(root_children, NULL, NULL)) != WX_OK) {
        return r;
    }
    if (p->collider == NULL) {
        return fail(p, node, WX_CAUSE_MISSING, "<Weathering> needs a <Collider> with the cameras");
    }
    r = xml_finish_emitters(p);
    return r != WX_OK ? r : xml_check_scene(p);
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
                         : xml_read_document(path, &doc, err);
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
