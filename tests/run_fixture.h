// run_fixture.h: what the tests that run the `weathering` command on scenes of
// their own share: running it in a folder (its output kept in `out`), the
// path of a file in tests/data (ensure_read_channel reads what it wrote), and
// the schema check of a scene file. Include after defining _XOPEN_SOURCE 700
// (realpath).
#ifndef WX_RUN_FIXTURE_H
#define WX_RUN_FIXTURE_H

#include <limits.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>

#include <libxml/parser.h>
#include <libxml/xmlschemas.h>

#include "ensure.h"
#include "io/exr.h"
#include "model/image.h"

/// What the last command printed (stdout and stderr).
static char out[65536];

/// Runs `weathering ARGS` in `dir`; its exit status. With show_failure, a
/// failure's output goes to stderr.
static inline int weathering_in(const char *dir, const char *args, bool show_failure)
{
    char build[PATH_MAX];
    if (realpath(ensure_build_dir(), build) == NULL) {
        return -1;
    }
    int status = ensure_shell(out, sizeof out, "cd '%s' && '%s/weathering' %s 2>&1", dir, build,
                              args);
    if (status != 0 && show_failure) {
        fprintf(stderr, "        %s", out);
    }
    return status;
}

/// `weathering` in `dir` with the arguments of `fmt` (two strings), its
/// failures expected as often as not (not shown).
static inline int run_in(const char *dir, const char *fmt, const char *a, const char *b)
{
    char args[4 * PATH_MAX];
    snprintf(args, sizeof args, fmt, a, b);
    return weathering_in(dir, args, false);
}

/// Validates a scene against xml_scenes/weathering.xsd.
static inline bool schema_accepts(const char *path)
{
    char xsd[PATH_MAX + 64];
    snprintf(xsd, sizeof xsd, "%s/../xml_scenes/weathering.xsd", ensure_tests_dir());
    xmlSchemaParserCtxtPtr pc = xmlSchemaNewParserCtxt(xsd);
    xmlSchemaPtr schema = pc != NULL ? xmlSchemaParse(pc) : NULL;
    xmlSchemaValidCtxtPtr vc = schema != NULL ? xmlSchemaNewValidCtxt(schema) : NULL;
    xmlDocPtr doc = xmlReadFile(path, NULL, XML_PARSE_NONET);
    bool ok = vc != NULL && doc != NULL && xmlSchemaValidateDoc(vc, doc) == 0;
    xmlFreeDoc(doc);
    xmlSchemaFreeValidCtxt(vc);
    xmlSchemaFree(schema);
    xmlSchemaFreeParserCtxt(pc);
    return ok;
}

/// The absolute path of tests/data/NAME.
static inline const char *data_file(const char *name)
{
    static char path[PATH_MAX + 64], tests[PATH_MAX];
    if (realpath(ensure_tests_dir(), tests) == NULL) {
        return name;
    }
    snprintf(path, sizeof path, "%s/data/%s", tests, name);
    return path;
}

#endif
