// test_init.c: the commands around the generated scenes (docs/design.md
// section 13, docs/presets.md): `run MESH --preset P` and `split`, the folder
// and the scene `run MESH` writes, what `init` never overwrites; bad input is
// exit 2. The scenes themselves are tests/test_preset.c's.
#define _XOPEN_SOURCE 700 // realpath
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <libxml/parser.h>
#include <libxml/xmlschemas.h>

#include "ensure.h"
#include "run_fixture.h"
#include "io/exr.h"
#include "model/image.h"

// `weathering` in `dir` with the arguments of `fmt` (two strings), its failures
// expected as often as not (not shown).
static int run_in(const char *dir, const char *fmt, const char *a, const char *b)
{
    char args[4 * PATH_MAX];
    snprintf(args, sizeof args, fmt, a, b);
    return weathering_in(dir, args, false);
}

// Validates a scene against xml_scenes/weathering.xsd.
static bool schema_accepts(const char *path)
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

// `run MESH --preset P` writes the scene into the output folder and runs it;
// `split` writes each channel as a file of its own.
TEST(run_a_mesh_and_split_its_texture)
{
    const char *dir = ensure_tmpdir();
    ENSURE(run_in(dir, "run '%s' --preset dust --resolution 96 --out %s -q",
                  data_file("texture_cube.obj"), "dust") == 0);
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/dust/scene.xml", dir);
    ENSURE(schema_accepts(path));
    ENSURE(run_in(dir, "split dust/%s%s", "texture_cube_texture.exr", "") == 0);
    ENSURE(strstr(out, "dust/texture_cube_texture_Y.exr") != NULL);
    ENSURE(strstr(out, "dust/texture_cube_texture_seen.exr") != NULL);
    snprintf(path, sizeof path, "%s/dust/texture_cube_texture.exr", dir);
    int w = 0, h = 0, w2 = -1, h2 = -1;
    float *y = ensure_read_channel(path, "Y", &w, &h);
    snprintf(path, sizeof path, "%s/dust/texture_cube_texture_Y.exr", dir);
    float *y2 = ensure_read_channel(path, "Y", &w2, &h2);
    ENSURE(y != NULL && y2 != NULL && w == w2 && h == h2);
    if (y != NULL && y2 != NULL && w == w2 && h == h2) {
        ENSURE(memcmp(y, y2, (size_t)w * (size_t)h * sizeof(float)) == 0);
    }
    free(y);
    free(y2);
}

// Bad input: exit 2 with one message; an existing scene is never replaced
// without --force.
TEST(bad_input_is_exit_2)
{
    const char *dir = ensure_tmpdir();
    ensure_write_file(dir, "keep.xml", "mine");
    ENSURE(run_in(dir, "init '%s' -o %s", data_file("texture_cube.obj"), "keep.xml") == 2);
    ENSURE(strstr(out, "keep.xml exists; give --force") != NULL);
    char path[PATH_MAX + 16];
    snprintf(path, sizeof path, "%s/keep.xml", dir);
    char *kept = ensure_read_file(path);
    ENSURE(kept != NULL && strcmp(kept, "mine") == 0);
    free(kept);
    ENSURE(run_in(dir, "init '%s' -o %s --force -q", data_file("texture_cube.obj"), "keep.xml") ==
           0);
    ENSURE(run_in(dir, "init '%s' --preset %s", data_file("texture_cube.obj"), "hail") == 2);
    ENSURE(strstr(out, "unknown preset 'hail'") != NULL);
    ensure_write_file(dir, "points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    ENSURE(run_in(dir, "init %s%s", "points.obj", "") == 2);
    ENSURE(strstr(out, "points.obj") != NULL && (strstr(out, "no triangles") != NULL ||
                                               strstr(out, "no faces") != NULL));
    ENSURE(run_in(dir, "init %s%s", "missing.obj", "") == 2);
    ENSURE(strstr(out, "missing.obj") != NULL);
    ENSURE(run_in(dir, "info keep.xml --preset %s%s", "rain", "") == 2);
}

// `run MESH` names its folder and scene after the mesh by the scene-name rule
// (issue 24): "...obj" writes into out/__/, never into out/.. (the current
// folder); the scene it writes there runs into the same folder again.
TEST(run_mesh_folder_is_plain_and_named_after_the_mesh)
{
    char dir[PATH_MAX + 16];
    snprintf(dir, sizeof dir, "%s/dots", ensure_tmpdir());
    ENSURE(ensure_shell(NULL, 0, "mkdir -p '%s' && cp '%s' '%s/...obj'", dir,
                        data_file("texture_cube.obj"), dir) == 0);
    ensure_write_file(dir, "scene.xml", "mine");
    ENSURE(run_in(dir, "run %s --resolution 48 -q%s", "...obj", "") == 0);
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/scene.xml", dir);
    char *kept = ensure_read_file(path);
    ENSURE(kept != NULL && strcmp(kept, "mine") == 0);
    free(kept);
    snprintf(path, sizeof path, "%s/mask.exr", dir);
    ENSURE(access(path, F_OK) != 0);
    snprintf(path, sizeof path, "%s/out/__/scene.xml", dir);
    char *scene = ensure_read_file(path);
    ENSURE(scene != NULL && strstr(scene, "<Weathering name=\"__\">") != NULL);
    free(scene);
    // Run again from its own scene: the same folder, not out/scene.
    ENSURE(run_in(dir, "run out/__/scene.xml -q%s%s", "", "") == 0);
    snprintf(path, sizeof path, "%s/out/scene", dir);
    ENSURE(access(path, F_OK) != 0);
}

// `run MESH --out DIR` never replaces a DIR/scene.xml of the user's (one that
// no `run MESH` generated), and a refusal leaves no folder and no scene.
TEST(run_mesh_keeps_a_users_scene_and_leaves_nothing_on_refusal)
{
    char dir[PATH_MAX + 16];
    snprintf(dir, sizeof dir, "%s/users", ensure_tmpdir());
    ENSURE(ensure_shell(NULL, 0, "mkdir -p '%s/mine'", dir) == 0);
    ensure_write_file(dir, "mine/scene.xml", "<Weathering/>");
    ENSURE(run_in(dir, "run '%s' --out mine --resolution 48 -q%s", data_file("texture_cube.obj"),
                  "") == 2);
    ENSURE(strstr(out, "mine/scene.xml: exists and is not a scene that `weathering run MESH` "
                       "generated") != NULL);
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/mine/scene.xml", dir);
    char *kept = ensure_read_file(path);
    ENSURE(kept != NULL && strcmp(kept, "<Weathering/>") == 0);
    free(kept);
    // A generated scene is replaced by the next run of a mesh.
    ENSURE(run_in(dir, "run '%s' --out gen --resolution 48 -q%s", data_file("texture_cube.obj"),
                  "") == 0);
    ENSURE(run_in(dir, "run '%s' --out gen --resolution 48 --preset dust -q%s",
                  data_file("texture_cube.obj"), "") == 0);
    // Refused for memory: nothing at all is made.
    char build[PATH_MAX];
    ENSURE(realpath(ensure_build_dir(), build) != NULL);
    int status = ensure_shell(out, sizeof out,
                              "cd '%s' && WX_MEMORY_AVAILABLE_MB=50 '%s/weathering' run '%s' "
                              "--out fresh/sub -q",
                              dir, build, data_file("texture_cube.obj"));
    ENSURE(status == 2 && strstr(out, "memory") != NULL);
    snprintf(path, sizeof path, "%s/fresh", dir);
    ENSURE(access(path, F_OK) != 0);
}

// `init` never writes over the mesh (an Ogre X.mesh.xml, with or without
// --force); -o into a missing folder or onto a folder is exit 2, nothing written.
TEST(init_never_writes_over_the_mesh_and_checks_its_target)
{
    char dir[PATH_MAX + 16];
    snprintf(dir, sizeof dir, "%s/ogre", ensure_tmpdir());
    ENSURE(ensure_shell(NULL, 0, "mkdir -p '%s'", dir) == 0);
    static const char ogre[] =
        "<mesh><submeshes><submesh material=\"wall\" usesharedvertices=\"false\" "
        "operationtype=\"triangle_list\"><faces count=\"2\"><face v1=\"0\" v2=\"1\" "
        "v3=\"2\"/><face v1=\"0\" v2=\"2\" v3=\"3\"/></faces><geometry vertexcount=\"4\">"
        "<vertexbuffer positions=\"true\"><vertex><position x=\"0\" y=\"0\" z=\"0\"/></vertex>"
        "<vertex><position x=\"1\" y=\"0\" z=\"0\"/></vertex><vertex><position x=\"1\" "
        "y=\"0\" z=\"1\"/></vertex><vertex><position x=\"0\" y=\"0.5\" z=\"1\"/></vertex>"
        "</vertexbuffer></geometry></submesh></submeshes></mesh>\n";
    ensure_write_file(dir, "cube.mesh.xml", ogre);
    ENSURE(run_in(dir, "init cube.mesh.xml --force -q%s%s", "", "") == 0);
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/cube.mesh.xml", dir);
    char *mesh = ensure_read_file(path);
    ENSURE(mesh != NULL && strcmp(mesh, ogre) == 0);
    free(mesh);
    snprintf(path, sizeof path, "%s/cube.xml", dir);
    ENSURE(schema_accepts(path));
    // The mesh under another name (a hard link) is still the mesh.
    ENSURE(ensure_shell(NULL, 0, "cd '%s' && ln cube.mesh.xml same.xml && mkdir folder.xml",
                        dir) == 0);
    ENSURE(run_in(dir, "init cube.mesh.xml -o %s --force%s", "same.xml", "") == 2);
    ENSURE(strstr(out, "is the mesh itself") != NULL);
    ENSURE(run_in(dir, "init cube.mesh.xml -o %s --force%s", "cube.mesh.xml", "") == 2);
    ENSURE(run_in(dir, "init cube.mesh.xml -o %s --force%s", "folder.xml", "") == 2);
    ENSURE(strstr(out, "folder.xml: exists and is a folder") != NULL);
    ENSURE(run_in(dir, "init cube.mesh.xml -o %s%s", "missing/x.xml", "") == 2);
    ENSURE(strstr(out, "folder missing does not exist") != NULL);
    snprintf(path, sizeof path, "%s/missing", dir);
    ENSURE(access(path, F_OK) != 0);
    snprintf(path, sizeof path, "%s/cube.mesh.xml", dir);
    mesh = ensure_read_file(path);
    ENSURE(mesh != NULL && strcmp(mesh, ogre) == 0);
    free(mesh);
}

int main(void)
{
    RUN(run_a_mesh_and_split_its_texture);
    RUN(bad_input_is_exit_2);
    RUN(run_mesh_folder_is_plain_and_named_after_the_mesh);
    RUN(run_mesh_keeps_a_users_scene_and_leaves_nothing_on_refusal);
    RUN(init_never_writes_over_the_mesh_and_checks_its_target);
    return ensure_summary();
}
