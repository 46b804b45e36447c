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

#include "ensure.h"
#include "run_fixture.h"
#include "io/exr.h"
#include "model/image.h"

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

// Two quads side by side (x in [-0.8, 0] and [0, 0.8], y = 0, facing up), the
// first's UVs from (u[0], v[0]) to (u[1], v[1]), the second's from (u[2], v[2])
// to (u[3], v[3]), written as dir/name.
static void write_two_quads(const char *dir, const char *name, const double u[4],
                            const double v[4])
{
    char text[1024];
    snprintf(text, sizeof text,
             "v -0.8 0 0.8\nv 0 0 0.8\nv 0 0 -0.8\nv -0.8 0 -0.8\nv 0.8 0 0.8\nv 0.8 0 -0.8\n"
             "vt %g %g\nvt %g %g\nvt %g %g\nvt %g %g\nvt %g %g\nvt %g %g\nvt %g %g\nvt %g %g\n"
             "vn 0 1 0\nf 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n"
             "f 2/5/1 5/6/1 6/7/1\nf 2/5/1 6/7/1 3/8/1\n",
             u[0], v[0], u[1], v[0], u[1], v[1], u[0], v[1], u[2], v[2], u[3], v[2], u[3], v[3],
             u[2], v[3]);
    ensure_write_file(dir, name, text);
}

// init reads the UV layout (docs/presets.md): UVs in UDIM tiles 1001 and 1002
// give tiles="udim"; a layout in [0,1] that overshoots by a hair, and one
// spread over -7.6 .. 8.5, the default REPEAT (with a comment saying how far
// they reach); a layout without area no TextureMap, with a note in the scene
// and on stderr. Every scene validates and `info` reads it.
TEST(init_reads_the_uv_layout)
{
    const char *dir = ensure_tmpdir();
    static const struct {
        const char *name;
        double u[4], v[4];
        const char *want, *not_want;
    } layouts[] = {
        { "udim", { 0, 0.5, 1.5, 2 }, { 0, 1, 0, 1 },
          "<TextureMap file=\"udim_texture.exr\" resolution=\"64\" tiles=\"udim\"/>",
          "covers no texel" },
        { "over", { -0.01, 0.5, 0.5, 1.01 }, { 0, 1, 0, 1.001 },
          "<TextureMap file=\"over_texture.exr\" resolution=\"64\"/>", "tiles=" },
        { "spread", { -7.6, -7.1, 8, 8.5 }, { -3, -2, 3, 4 },
          "They reach from (-7.6, -3) to (8.5, 4): outside [0,1] they wrap", "tiles=" },
        { "flat", { 0.5, 0.5, 0.5, 0.5 }, { 0.5, 0.5, 0.5, 0.5 },
          "covers no texel at 64 x 64:\n           of its 4 triangles, 4 have no area in UV",
          "<TextureMap file" },
    };
    for (size_t k = 0; k < sizeof layouts / sizeof layouts[0]; ++k) {
        char mesh[64], scene[64], path[PATH_MAX + 64];
        snprintf(mesh, sizeof mesh, "%s.obj", layouts[k].name);
        snprintf(scene, sizeof scene, "%s.xml", layouts[k].name);
        write_two_quads(dir, mesh, layouts[k].u, layouts[k].v);
        ENSURE(run_in(dir, "init %s --resolution 64 -o %s", mesh, scene) == 0);
        bool noted = strstr(out, "weathering: note: flat.obj: the mesh's UV layout covers no "
                                 "texel at 64 x 64") != NULL;
        ENSURE(noted == (k == 3));
        snprintf(path, sizeof path, "%s/%s", dir, scene);
        char *text = ensure_read_file(path);
        ENSURE(text != NULL);
        bool ok = strstr(text, layouts[k].want) != NULL && strstr(text, layouts[k].not_want) == NULL;
        if (!ok) {
            fprintf(stderr, "        %s:\n%s\n", scene, text);
        }
        free(text);
        ENSURE(ok);
        ENSURE(schema_accepts(path));
        ENSURE(run_in(dir, "info %s%s", scene, "") == 0);
    }
    // info names the UDIM files.
    ENSURE(run_in(dir, "info %s%s", "udim.xml", "") == 0);
    ENSURE(strstr(out, "UDIM tiles: 2 (where a texel centre lies inside a triangle): "
                       "udim_texture.1001.exr, udim_texture.1002.exr") != NULL);
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
    SLOW();
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
    SLOW();
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

// A tetrahedron with corners at the origin and at `size` along each axis,
// offset by (ox, oy, oz).
static void write_tetrahedron(const char *dir, const char *name, double size, double ox,
                              double oy, double oz)
{
    char text[1024];
    snprintf(text, sizeof text,
             "v %.17g %.17g %.17g\nv %.17g %.17g %.17g\nv %.17g %.17g %.17g\n"
             "v %.17g %.17g %.17g\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
             ox, oy, oz, ox + size, oy, oz, ox, oy + size, oz, ox, oy, oz + size);
    ensure_write_file(dir, name, text);
}

// Whether `dir` holds no file but the meshes (*.obj).
static bool only_meshes_in(const char *dir)
{
    char listing[4096];
    ensure_shell(listing, sizeof listing, "cd '%s' && ls -A | grep -v '\\.obj$'", dir);
    return listing[0] == '\0';
}

// `init` used to exit 1 "the generated scene does not load (a bug)" and leave
// that scene behind for meshes at 1e30, 3e38 or 1e-30 across, a 1 m model at
// UTM coordinates, and a mesh whose file name breaks the XML (a "--" in the
// header comment, Latin-1 bytes in the path). Now each one either gets a
// scene that loads, or is refused with exit 2 naming the mesh, and no file is
// written; the scene is checked in memory before it is written.
TEST(init_makes_a_valid_scene_or_refuses_the_mesh)
{
    static char dir[PATH_MAX];
    snprintf(dir, sizeof dir, "%s/refuse", ensure_tmpdir());
    ENSURE(ensure_shell(out, sizeof out, "mkdir -p '%s'", dir) == 0);
    write_tetrahedron(dir, "huge.obj", 1e30, 0, 0, 0);
    write_tetrahedron(dir, "max.obj", 3e38, -1.5e38, 0, 0);
    write_tetrahedron(dir, "tiny.obj", 1e-30, 0, 0, 0);
    write_tetrahedron(dir, "utm.obj", 1.0, 500000.0, 0.0, 5e6);
    write_tetrahedron(dir, "latin\xe9.obj", 1.0, 0, 0, 0);
    static const char *const refused[][2] = {
        { "huge.obj", "is 1e+30 across, larger than" },
        { "max.obj", "is 3e+38 across, larger than" },
        { "tiny.obj", "is 1e-30 across, smaller than" },
        { "utm.obj", "is only 1 across but has coordinates up to 5e+06" },
        { "latin\xe9.obj", "not UTF-8 text" },
    };
    for (size_t k = 0; k < sizeof refused / sizeof refused[0]; ++k) {
        char name[64];
        snprintf(name, sizeof name, "'%s'", refused[k][0]);
        ENSURE(run_in(dir, "init %s%s", name, "") == 2);
        ENSURE(strstr(out, "weathering: ") == out && strchr(out, '\n') == out + strlen(out) - 1);
        char shown[128];
        wx_printable(refused[k][0], shown, sizeof shown);
        ENSURE(strstr(out, shown) != NULL);
        ENSURE(strstr(out, refused[k][1]) != NULL);
        ENSURE(strstr(out, "a bug") == NULL);
        ENSURE(only_meshes_in(dir));
        // `run MESH` refuses it the same way, before making its folder.
        ENSURE(run_in(dir, "run %s --out o -q%s", name, "") == 2);
        ENSURE(only_meshes_in(dir));
    }
    // Made: "--" in the name (the header comment shows "-_"), a mesh 1e4 or
    // 1e-5 across, a 1 m model 500 m from the origin.
    write_tetrahedron(dir, "a--b.obj", 1.0, 0, 0, 0);
    write_tetrahedron(dir, "wide.obj", 1e4, 0, 0, 0);
    write_tetrahedron(dir, "small.obj", 1e-5, 0, 0, 0);
    write_tetrahedron(dir, "near.obj", 1.0, 300.0, 0.0, 400.0);
    static const char *const made[] = { "a--b", "wide", "small", "near" };
    for (size_t k = 0; k < sizeof made / sizeof made[0]; ++k) {
        ENSURE(run_in(dir, "init %s.obj -q%s", made[k], "") == 0);
        char path[PATH_MAX + 64];
        snprintf(path, sizeof path, "%s/%s.xml", dir, made[k]);
        ENSURE(schema_accepts(path));
        ENSURE(run_in(dir, "info %s.xml%s", made[k], "") == 0);
        ENSURE(strstr(out, "every vertex lies inside an input camera's frame") != NULL);
    }
}

// A mesh with no thickness along an axis (every vertex at z = 0) is seen
// edge-on by the cameras along the other axes: they record no surface, so
// the collider lets every particle through and the run is all zero. `init`
// and `info` used to say nothing; both warn now, naming the cameras and the
// flat axis. A solid mesh gets no such warning.
TEST(a_mesh_without_thickness_is_warned_about)
{
    const char *dir = ensure_tmpdir();
    ensure_write_file(dir, "sheet.obj",
                      "v -1 0 0\nv 1 0 0\nv 1 2 0\nv -1 2 0\nf 1 2 3\nf 1 3 4\n");
    ENSURE(run_in(dir, "init sheet.obj%s%s", "", "") == 0);
    const char *warning = "cameras 'left', 'right' and 'top' record no surface";
    ENSURE(strstr(out, warning) != NULL);
    ENSURE(strstr(out, "has no thickness along Z (every vertex at z = 0)") != NULL);
    ENSURE(run_in(dir, "info sheet.xml%s%s", "", "") == 0);
    ENSURE(strstr(out, "weathering: warning: sheet.xml: ") != NULL && strstr(out, warning));
    ENSURE(run_in(dir, "init '%s' -o cube.xml%s", data_file("texture_cube.obj"), "") == 0);
    ENSURE(strstr(out, "record no surface") == NULL);
    ENSURE(run_in(dir, "info cube.xml%s%s", "", "") == 0);
    ENSURE(strstr(out, "record no surface") == NULL);
}

int main(void)
{
    RUN(run_a_mesh_and_split_its_texture);
    RUN(init_reads_the_uv_layout);
    RUN(bad_input_is_exit_2);
    RUN(run_mesh_folder_is_plain_and_named_after_the_mesh);
    RUN(run_mesh_keeps_a_users_scene_and_leaves_nothing_on_refusal);
    RUN(init_never_writes_over_the_mesh_and_checks_its_target);
    RUN(init_makes_a_valid_scene_or_refuses_the_mesh);
    RUN(a_mesh_without_thickness_is_warned_about);
    return ensure_summary();
}
