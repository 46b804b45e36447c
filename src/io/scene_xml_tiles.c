// scene_xml_tiles.c: a tile's scene made from the whole scene's file
// (docs/tiles.md): the same document, comments included, with the tile's name,
// its <Tile>, its input cameras' <View>s cropped to the tile and its halo, and
// relative paths of meshes and maps rewritten for the tile's folder.
#define _XOPEN_SOURCE 700 // realpath
#include "io/scene_xml.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/scene_xml_internal.h"

static bool is_element(const xmlNode *n, const char *name)
{
    return n->type == XML_ELEMENT_NODE && n->ns == NULL && strcmp(name_of(n), name) == 0;
}

static xmlNode *child_named(xmlNode *parent, const char *name)
{
    for (xmlNode *n = parent->children; n != NULL; n = n->next) {
        if (is_element(n, name)) {
            return n;
        }
    }
    return NULL;
}

// `target` (an absolute path without "." or ".." parts) relative to the
// absolute folder `from`: "../../meshes/house.obj".
static void relative_to(const char *from, const char *target, char *out, size_t cap)
{
    size_t common = 0; // length of the common leading folders, through a '/'
    for (size_t k = 0; from[k] != '\0' && from[k] == target[k]; ++k) {
        if (from[k] == '/') {
            common = k + 1;
        }
    }
    size_t from_len = strlen(from);
    if (from[from_len] == '\0' && target[from_len] == '/' && strncmp(from, target, from_len) == 0) {
        common = from_len + 1; // target lies inside from
    }
    size_t used = 0;
    out[0] = '\0';
    // One "../" for each folder of `from` after the common part.
    for (size_t k = common; k < from_len; ++k) {
        bool starts = k == common || from[k - 1] == '/';
        if (starts && from[k] != '/' && used + 3 < cap) {
            memcpy(out + used, "../", 4);
            used += 3;
        }
    }
    snprintf(out + used, cap - used, "%s", target + common);
}

// A relative `file` attribute, made relative to the tile's folder instead of
// the scene's (absolute paths stay).
static wx_result rewrite_path(parser *p, xmlNode *node, const char *scene_dir, const char *to_dir)
{
    xmlChar *value = xmlGetProp(node, (const xmlChar *)"file");
    if (value == NULL) {
        return WX_OK;
    }
    wx_result r = WX_OK;
    if (value[0] != '/') {
        char joined[PATH_MAX * 2], resolved[PATH_MAX], rel[PATH_MAX * 2];
        snprintf(joined, sizeof joined, "%s/%s", scene_dir, (const char *)value);
        if (realpath(joined, resolved) == NULL) {
            r = fail(p, node, WX_CAUSE_FILE_MISSING, "<%s> file '%s' cannot be found",
                     name_of(node), (const char *)value);
        } else {
            relative_to(to_dir, resolved, rel, sizeof rel);
            xmlSetProp(node, (const xmlChar *)"file", (const xmlChar *)rel);
        }
    }
    xmlFree(value);
    return r;
}

static void set_number(xmlNode *node, const char *name, double v)
{
    char text[64];
    snprintf(text, sizeof text, "%.17g", v);
    xmlSetProp(node, (const xmlChar *)name, (const xmlChar *)text);
}

static void set_vec3(xmlNode *node, const char *name, const float v[3])
{
    char text[128];
    snprintf(text, sizeof text, "%.9g %.9g %.9g", (double)v[0], (double)v[1], (double)v[2]);
    xmlSetProp(node, (const xmlChar *)name, (const xmlChar *)text);
}

static void set_view(xmlNode *view, const wx_view *v)
{
    set_vec3(view, "eye", v->eye);
    set_vec3(view, "target", v->target);
    set_vec3(view, "up", v->up);
    char text[64];
    snprintf(text, sizeof text, "%.9g", (double)v->width_ws);
    xmlSetProp(view, (const xmlChar *)"width", (const xmlChar *)text);
    snprintf(text, sizeof text, "%.9g", (double)v->height_ws);
    xmlSetProp(view, (const xmlChar *)"height", (const xmlChar *)text);
    snprintf(text, sizeof text, "%d %d", v->width_px, v->height_px);
    xmlSetProp(view, (const xmlChar *)"resolution", (const xmlChar *)text);
}

static const wx_view *view_of(const wx_tile_scene_edit *edit, const char *camera)
{
    for (int k = 0; k < edit->view_count; ++k) {
        if (strcmp(edit->view_names[k], camera) == 0) {
            return &edit->views[k];
        }
    }
    return NULL;
}

// The <Ortho>s: input cameras cropped (their <View>) or left out, every map
// path rewritten.
static wx_result edit_cameras(parser *p, xmlNode *maps, const wx_tile_scene_edit *edit,
                              const char *scene_dir)
{
    static const char *const map_elements[] = { "DepthMap", "NormalMap", "ImpactMap", "DirtMap" };
    xmlNode *next = NULL;
    for (xmlNode *ortho = maps->children; ortho != NULL; ortho = next) {
        next = ortho->next;
        if (!is_element(ortho, "Ortho")) {
            continue;
        }
        xmlChar *out = xmlGetProp(ortho, (const xmlChar *)"out");
        bool is_output = out != NULL && strcmp((const char *)out, "true") == 0;
        xmlFree(out);
        xmlNode *output_map = is_output ? child_named(ortho, "OutputMap") : NULL;
        xmlNode *output_view = is_output ? child_named(ortho, "View") : NULL;
        if (output_view != NULL && output_map != NULL && edit->output_view != NULL) {
            const wx_view *v = edit->output_view;
            set_view(output_view, v);
            char text[32];
            snprintf(text, sizeof text, "%d", v->width_px);
            xmlSetProp(output_map, (const xmlChar *)"width", (const xmlChar *)text);
            snprintf(text, sizeof text, "%d", v->height_px);
            xmlSetProp(output_map, (const xmlChar *)"height", (const xmlChar *)text);
        }
        if (!is_output) {
            xmlChar *name = xmlGetProp(ortho, (const xmlChar *)"cameraName");
            const wx_view *v = name != NULL ? view_of(edit, (const char *)name) : NULL;
            xmlFree(name);
            xmlNode *view = child_named(ortho, "View");
            if (v == NULL || view == NULL) {
                xmlUnlinkNode(ortho);
                xmlFreeNode(ortho);
                continue;
            }
            set_view(view, v);
        }
        for (xmlNode *m = ortho->children; m != NULL; m = m->next) {
            for (size_t k = 0; k < sizeof map_elements / sizeof map_elements[0]; ++k) {
                wx_result r = WX_OK;
                if (is_element(m, map_elements[k]) &&
                    (r = rewrite_path(p, m, scene_dir, edit->to_dir)) != WX_OK) {
                    return r;
                }
            }
        }
    }
    return WX_OK;
}

static wx_result edit_document(parser *p, xmlDoc *doc, const wx_tile_scene_edit *edit,
                               const char *scene_dir)
{
    xmlNode *root = xmlDocGetRootElement(doc);
    if (root == NULL || !is_element(root, "Weathering")) {
        return wx_fail(p->err, WX_CAUSE_UNKNOWN_NAME, "%s: the root element is not <Weathering>",
                       p->path);
    }
    xmlSetProp(root, (const xmlChar *)"name", (const xmlChar *)edit->name);
    wx_result r = WX_OK;
    xmlNode *collider = child_named(root, "Collider");
    xmlNode *maps = collider != NULL ? child_named(collider, "ProjectedMaps") : NULL;
    if (maps != NULL) {
        r = edit_cameras(p, maps, edit, scene_dir);
    }
    xmlNode *geometry = child_named(root, "Geometry");
    for (xmlNode *m = geometry != NULL ? geometry->children : NULL; m != NULL && r == WX_OK;
         m = m->next) {
        if (is_element(m, "Mesh")) {
            r = rewrite_path(p, m, scene_dir, edit->to_dir);
        }
    }
    if (r != WX_OK) {
        return r;
    }
    xmlNode *old = child_named(root, "Tile");
    if (old != NULL) {
        xmlUnlinkNode(old);
        xmlFreeNode(old);
    }
    xmlNode *tile = xmlNewChild(root, NULL, (const xmlChar *)"Tile", NULL);
    if (tile == NULL) {
        return wx_fail(p->err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", p->path);
    }
    const wx_tile_def *t = &edit->tile;
    const char *names[2][2] = { { "minX", "maxX" }, { "minZ", "maxZ" } };
    for (int a = 0; a < 2; ++a) {
        if (isfinite(t->min[a])) {
            set_number(tile, names[a][0], t->min[a]);
        }
        if (isfinite(t->max[a])) {
            set_number(tile, names[a][1], t->max[a]);
        }
    }
    set_number(tile, "halo", t->halo);
    return WX_OK;
}

wx_result wx_scene_tile_text(const char *path, const wx_tile_scene_edit *edit, char **text,
                             size_t *size, wx_error *err)
{
    *text = NULL;
    *size = 0;
    xmlDocPtr doc = NULL;
    wx_result r = xml_read_document(path, &doc, err);
    if (r != WX_OK) {
        return r;
    }
    // The folder the scene's relative paths resolve in, absolute.
    char dir[PATH_MAX * 2], scene_dir[PATH_MAX];
    snprintf(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    if (slash == NULL) {
        snprintf(dir, sizeof dir, ".");
    } else {
        slash[slash == dir ? 1 : 0] = '\0';
    }
    if (realpath(dir, scene_dir) == NULL) {
        xmlFreeDoc(doc);
        return wx_fail(err, WX_CAUSE_UNREADABLE, "%s: its folder cannot be resolved", path);
    }
    parser p = { .path = path, .err = err };
    r = edit_document(&p, doc, edit, scene_dir);
    if (r == WX_OK) {
        xmlChar *buffer = NULL;
        int length = 0;
        xmlDocDumpFormatMemoryEnc(doc, &buffer, &length, "UTF-8", 1);
        if (buffer == NULL || length <= 0) {
            r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", path);
        } else {
            *text = malloc((size_t)length + 1);
            if (*text == NULL) {
                r = wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory", path);
            } else {
                memcpy(*text, buffer, (size_t)length);
                (*text)[length] = '\0';
                *size = (size_t)length;
            }
        }
        xmlFree(buffer);
    }
    xmlFreeDoc(doc);
    return r;
}
