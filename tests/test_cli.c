// test_cli.c: the `weathering` command line: options, exit statuses, messages.
#define _XOPEN_SOURCE 700 // realpath
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "ensure.h"

static char out[65536];

static int weathering(const char *args)
{
    return ensure_shell(out, sizeof out, "%s/weathering %s", ensure_build_dir(), args);
}

TEST(help_lists_commands_and_options)
{
    ENSURE(weathering("--help") == 0);
    ENSURE(ensure_contains(out, "usage: weathering COMMAND SCENE.xml"));
    ENSURE(ensure_contains(out, "info"));
    ENSURE(ensure_contains(out, "--out DIR"));
    ENSURE(ensure_contains(out, "--threads N"));
    ENSURE(weathering("-h") == 0);
}

TEST(version)
{
    ENSURE(weathering("--version") == 0);
    ENSURE(strncmp(out, "weathering ", 11) == 0);
}

TEST(no_command_is_a_usage_error)
{
    ENSURE(weathering("") == 2);
    ENSURE(ensure_contains(out, "usage:"));
}

TEST(unknown_command_and_option)
{
    ENSURE(weathering("frobnicate xml_scenes/building.xml") == 2);
    ENSURE(ensure_contains(out, "unknown command 'frobnicate'"));
    ENSURE(weathering("info xml_scenes/building.xml --frob") == 2);
    ENSURE(ensure_contains(out, "unknown option '--frob'"));
}

TEST(option_values_are_checked)
{
    ENSURE(weathering("info xml_scenes/building.xml --threads 0") == 2);
    ENSURE(ensure_contains(out, "--threads takes a whole number"));
    ENSURE(weathering("info xml_scenes/building.xml --threads x") == 2);
    ENSURE(weathering("info xml_scenes/building.xml --seed -3") == 2);
    ENSURE(ensure_contains(out, "--seed takes a whole number"));
    ENSURE(weathering("info xml_scenes/building.xml --out") == 2);
    ENSURE(ensure_contains(out, "--out needs a value"));
    ENSURE(weathering("info") == 2);
    ENSURE(ensure_contains(out, "info needs a scene file"));
    ENSURE(weathering("info a.xml b.xml") == 2);
    ENSURE(ensure_contains(out, "unexpected argument 'b.xml'"));
}

TEST(missing_scene_names_the_file)
{
    ENSURE(weathering("info no/such/scene.xml") == 2);
    ENSURE(ensure_contains(out, "no/such/scene.xml"));
}

TEST(info_summarises_the_default_scene)
{
    ENSURE(weathering("info xml_scenes/building.xml --seed=7 --out /tmp/x") == 0);
    ENSURE(ensure_contains(out, "cameras (3 input, 1 output)"));
    ENSURE(ensure_contains(out, "front"));
    ENSURE(ensure_contains(out, "1024 x 1024"));
    // Frame 16 m over 1024 texels.
    ENSURE(ensure_contains(out, "texel 0.01562 m"));
    // 150000 particles/s for 4 s.
    ENSURE(ensure_contains(out, "600000 particles"));
    ENSURE(ensure_contains(out, "seed 7"));
    ENSURE(ensure_contains(out, "output folder: /tmp/x"));
    // Version 1's one substance, in version 1's words.
    ENSURE(ensure_contains(out, "substances (1): dirt (default)\n"));
    ENSURE(ensure_contains(out, "mass 1, dirt 0.05, max collisions 150"));
    ENSURE(ensure_contains(out, "material 'wall' absorption 0 bounce 0.1 dirt 0 deposit 0.03 "
                                "erosion 0.02;"));
    ENSURE(!ensure_contains(out, "ageing:"));
    ENSURE(!ensure_contains(out, "iterations"));
}

// info on a scene with substances and ageing (docs/design.md section 9) lists
// the substances, each emitter's loads, each surface's exchanges and rules, the
// global rules, the iterations and the mask's channels and frames (issue 16).
TEST(info_lists_substances_loads_exchanges_and_rules)
{
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/info_substances", ensure_tmpdir());
    ENSURE(ensure_shell(NULL, 0, "mkdir -p '%s'", dir) == 0);
    ensure_write_file(dir, "plane.obj",
                      "mtllib plane.mtl\n"
                      "v -1 0 -1\nv 0 0 -1\nv 0 0 1\nv -1 0 1\nv 1 0 -1\nv 1 0 1\n"
                      "vn 0 1 0\n"
                      "usemtl iron\nf 1//1 4//1 3//1 2//1\n"
                      "usemtl stone\nf 2//1 3//1 6//1 5//1\n");
    ensure_write_file(dir, "plane.mtl", "newmtl iron\nKd 0.5 0.5 0.5\nnewmtl stone\nKd 1 1 1\n");
    const char *path = ensure_write_file(
        dir, "s.xml",
        "<Weathering>\n"
        "  <Substances>\n"
        "    <Substance name=\"water\"/>\n"
        "    <Substance name=\"dirt\"/>\n"
        "    <Substance name=\"rust\"/>\n"
        "    <Substance name=\"moss\"/>\n"
        "  </Substances>\n"
        "  <Solver>\n"
        "    <BoundingBox size=\"8\"/>\n"
        "    <Simulation timeStep=\"0.01\" steps=\"50\" iterations=\"4\"/>\n"
        "  </Solver>\n"
        "  <Emitters>\n"
        "    <BoxEmitter name=\"rain\" minX=\"-1\" minY=\"1\" minZ=\"-1\" maxX=\"1\" "
        "maxY=\"1\" maxZ=\"1\" rate=\"1000\" end=\"0.5\" dirt=\"0.05\">\n"
        "      <Load substance=\"water\" amount=\"1\"/>\n"
        "      <Load substance=\"moss\" amount=\"0\"/>\n"
        "    </BoxEmitter>\n"
        "  </Emitters>\n"
        "  <Collider>\n"
        "    <ProjectedMaps>\n"
        "      <Ortho cameraName=\"top\">\n"
        "        <View eye=\"0 3 0\" target=\"0 0 0\" up=\"0 0 -1\" width=\"2.4\" "
        "height=\"2.4\" resolution=\"64\"/>\n"
        "      </Ortho>\n"
        "      <Ortho cameraName=\"shot\" out=\"true\">\n"
        "        <View eye=\"0 3 0\" target=\"0 0 0\" up=\"0 0 -1\" width=\"2.4\" "
        "height=\"2.4\" resolution=\"32\"/>\n"
        "        <OutputMap file=\"mask.exr\" width=\"32\" height=\"32\" every=\"2\"/>\n"
        "      </Ortho>\n"
        "    </ProjectedMaps>\n"
        "  </Collider>\n"
        "  <Ageing>\n"
        "    <Decay substance=\"water\" rate=\"0.5\"/>\n"
        "    <Grow substance=\"moss\" amount=\"2\"/>\n"
        "  </Ageing>\n"
        "  <Geometry>\n"
        "    <Mesh file=\"plane.obj\">\n"
        "      <Surface material=\"iron\" absorption=\"0.1\" bounce=\"0.2\" dirt=\"0\" "
        "deposit=\"0.5\" erosion=\"0.1\">\n"
        "        <Exchange substance=\"water\" deposit=\"0.8\" erosion=\"0.1\"/>\n"
        "        <Transfer from=\"water\" to=\"rust\" rate=\"0.2\"/>\n"
        "        <Decay substance=\"water\" rate=\"0.25\"/>\n"
        "      </Surface>\n"
        "      <Surface material=\"stone\" absorption=\"0.6\" bounce=\"0.1\" dirt=\"0\" "
        "deposit=\"0\" erosion=\"0\">\n"
        "        <Exchange substance=\"water\" initial=\"0.5\" deposit=\"0.3\"/>\n"
        "        <Decay substance=\"rust\" rate=\"1\"/>\n"
        "      </Surface>\n"
        "    </Mesh>\n"
        "  </Geometry>\n"
        "</Weathering>\n");
    ENSURE(path != NULL);
    char args[4400];
    snprintf(args, sizeof args, "info '%s'", path);
    int status = weathering(args);
    if (status != 0) {
        fprintf(stderr, "        status %d: %s", status, out);
    }
    ENSURE(status == 0);
    ENSURE(ensure_contains(out, "substances (4): water, dirt, rust, moss\n"));
    ENSURE(ensure_contains(out, "50 steps of 0.01 s (0.5 s simulated) in each of 4 iterations "
                                "(200 steps, 2 s in all);"));
    // 1000/s for 0.5 s in each of the 4 iterations; the loads that are not 0.
    ENSURE(ensure_contains(out, "(500 particles per iteration, 2000 in all)"));
    ENSURE(ensure_contains(out, "mass 1, loads water 1, dirt 0.05, max collisions"));
    ENSURE(!ensure_contains(out, "moss 0"));
    // The global rules, then each surface's exchanges and rules, in document order.
    ENSURE(ensure_contains(out, "ageing: 2 global rules after each of the 4 iterations: "
                                "Decay water 0.5, Grow moss 2 per m^2\n"));
    ENSURE(ensure_contains(out, "    material 'iron' absorption 0.1 bounce 0.2; exchanges water "
                                "initial 0 deposit 0.8 erosion 0.1, dirt initial 0 deposit 0.5 "
                                "erosion 0.1; rules Transfer water -> rust 0.2, Decay water "
                                "0.25\n"));
    ENSURE(ensure_contains(out, "    material 'stone' absorption 0.6 bounce 0.1; exchanges water "
                                "initial 0.5 deposit 0.3 erosion 0; rules Decay rust 1\n"));
    // The mask's channel per substance and its frames after iterations 2 and 4.
    ENSURE(ensure_contains(out, "channels water.Y, dirt.Y, rust.Y, moss.Y; frames "
                                "'mask.0002.exr' to 'mask.0004.exr', one after every 2 "
                                "iterations\n"));
    // The memory estimate counts the particles of every iteration and the frames.
    ENSURE(ensure_contains(out, "for at most 2000 particles alive at once of 2000 emitted and "));
    ENSURE(ensure_contains(out, "for a frame of the mask's sequence"));
    // What the sequence costs: 2 frames of 4 channels of 32 x 32 floats; a
    // gather of 1024 texels, 1 input camera and 4 substances at 400 ns each.
    ENSURE(ensure_contains(out, "2 frames of 4 channels: 0.0312 MiB of floats (0.0016-0.0063 "
                                "after ZIP) on disk, about 0.0033 s of gathering (0.0016 s a "
                                "frame)\n"));
}

// Issue 24: a sequence of 100 000 frames took info 23 s (the output names
// compared pair by pair) and info said nothing of its 1.5 h and gigabytes.
TEST(info_estimates_a_sequence_of_100000_frames)
{
    char dir[4200], maps[PATH_MAX + 16], tests_dir[PATH_MAX];
    snprintf(dir, sizeof dir, "%s/frames", ensure_tmpdir());
    ENSURE(ensure_shell(NULL, 0, "mkdir -p '%s'", dir) == 0);
    ENSURE(realpath(ensure_tests_dir(), tests_dir) != NULL);
    snprintf(maps, sizeof maps, "%s/../maps", tests_dir);
    char sed[16384];
    snprintf(sed, sizeof sed,
             "sed -e 's#\\.\\./maps/#%s/#' -e 's#<BoundingBox#<Simulation timeStep=\"0.01\" "
             "steps=\"10\" iterations=\"100000\"/><BoundingBox#' -e 's#rate=\"20000\"#"
             "rate=\"100\"#' -e 's#end=\"2\"#end=\"0.05\"#' -e 's#height=\"256\"/>#"
             "height=\"256\" every=\"1\"/>#' '%s/../xml_scenes/thesis_box.xml' > '%s/f.xml'",
             maps, tests_dir, dir);
    ENSURE(ensure_shell(NULL, 0, "%s", sed) == 0);
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    char args[4400];
    snprintf(args, sizeof args, "info '%s/f.xml'", dir);
    int status = weathering(args);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    double seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    printf("        info took %.2f s\n", seconds);
    if (status != 0) {
        fprintf(stderr, "        status %d: %s", status, out);
    }
    ENSURE(status == 0);
    ENSURE(ensure_contains(out, "frames 'thesis_box_mask.0001.exr' to "
                                "'thesis_box_mask.100000.exr', one after every iteration\n"));
    // 100000 x 256 x 256 floats; 65536 texels x 2 input cameras x 400 ns a frame.
    ENSURE(ensure_contains(out, "100000 frames of 1 channel: 24.4 GiB of floats (1.2-4.9 after "
                                "ZIP) on disk, about 1.5 h of gathering (0.052 s a frame); a "
                                "long sequence: a larger every= writes fewer frames\n"));
    ENSURE(seconds < 5.0); // 0.3 s; 23 s when the output names were compared pair by pair
}

TEST(info_on_a_bad_scene_gives_file_line_and_status_2)
{
    const char *dir = ensure_tmpdir();
    const char *path = ensure_write_file(dir, "bad.xml",
                                         "<Weathering>\n"
                                         "  <Collider>\n"
                                         "    <Frobnicate/>\n"
                                         "  </Collider>\n"
                                         "</Weathering>\n");
    char args[4200];
    snprintf(args, sizeof args, "info %s", path);
    ENSURE(weathering(args) == 2);
    char expected[4200];
    snprintf(expected, sizeof expected, "%s:3:", path);
    ENSURE(ensure_contains(out, expected));
}

// An emitter of rate="1e300": its count overflowed the cast to int64_t (to a
// negative number, which the memory check let through), and once that was
// clamped, info's pilot thinned it too little and its particle arrays' size
// wrapped: info crashed. Now info reports it too large, and run refuses it
// before any work.
TEST(an_absurd_emission_rate_is_refused_not_a_crash)
{
    const char *dir = ensure_tmpdir();
    char args[4200], *scene = ensure_read_file("xml_scenes/thesis_box.xml");
    ENSURE(scene != NULL);
    char *rate = strstr(scene, "rate=\"");
    ENSURE(rate != NULL);
    char *end = strchr(rate + 6, '"');
    static char text[65536];
    snprintf(text, sizeof text, "%.*srate=\"1e300%s", (int)(rate - scene), scene, end);
    free(scene);
    // The thesis box's maps are ../maps/ of its scene.
    char sub[4200];
    snprintf(sub, sizeof sub, "%s/flood", dir);
    ENSURE(ensure_shell(out, sizeof out, "mkdir -p '%s' && cp -r maps '%s/'", sub, dir) == 0);
    const char *path = ensure_write_file(sub, "flood.xml", text);
    // The amounts' check (docs/reliability.md, "Amounts") refuses it first: the
    // dirt of 2e300 particles cannot be held in single precision.
    snprintf(args, sizeof args, "info %s", path);
    ENSURE(weathering(args) == 2);
    ENSURE(ensure_contains(out, "2e+300 particles over 1 iteration"));
    snprintf(args, sizeof args, "run %s --out %s/flood -q", path, dir);
    ENSURE(weathering(args) == 2);
    ENSURE(ensure_contains(out, "2e+300 particles over 1 iteration"));
}

// The build folder as an absolute path (the tests below change folders).
static const char *build_dir(void)
{
    static char dir[PATH_MAX];
    if (dir[0] == '\0' && realpath(ensure_build_dir(), dir) == NULL) {
        snprintf(dir, sizeof dir, "%s", ensure_build_dir());
    }
    return dir;
}

// A scratch copy of the teapot scene and its mesh (issue 13's repro folder).
static const char *teapot_copy(const char *name)
{
    static char dir[4200];
    snprintf(dir, sizeof dir, "%s/%s", ensure_tmpdir(), name);
    if (ensure_shell(NULL, 0,
                     "mkdir -p '%s/meshes' && cp xml_scenes/teapot.xml '%s/s.xml' && "
                     "cp xml_scenes/meshes/teapot.obj '%s/meshes/'",
                     dir, dir, dir) != 0) {
        return NULL;
    }
    return dir;
}

// --stats never replaces an input, an output of the run or a non-regular file,
// and is refused before any work (issue 13).
TEST(stats_never_overwrites_anything)
{
    const char *d = teapot_copy("stats");
    ENSURE(d != NULL);
    ENSURE(ensure_shell(NULL, 0, "cd '%s' && cksum s.xml meshes/teapot.obj > ../stats.sum && "
                                 "ln -s /dev/null link.json && mkfifo fifo.json && mkdir o && "
                                 "echo keep > o/mask.exr", d) == 0);
    struct {
        const char *stats, *message;
    } cases[] = {
        { "s.xml", "--stats s.xml: is an input of scene s.xml" },
        { "meshes/teapot.obj", "--stats meshes/teapot.obj: is an input of scene" },
        { "o/mask.exr", "--stats o/mask.exr: is the run's output mask.exr" },
        { "o/../o/front_dirt.exr", "is the run's output front_dirt.exr" },
        { "link.json", "--stats link.json: exists and is a symbolic link" },
        { "fifo.json", "--stats fifo.json: exists and is a FIFO" },
        { "nowhere/s.json", "folder" },
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        int status = ensure_shell(out, sizeof out,
                                  "cd '%s' && timeout 20 '%s/weathering' run s.xml "
                                  "--out o --stats '%s'",
                                  d, build_dir(), cases[k].stats);
        if (status != 2 || !ensure_contains(out, cases[k].message)) {
            fprintf(stderr, "        --stats %s: status %d: %s", cases[k].stats, status, out);
        }
        ENSURE(status == 2);
        ENSURE(ensure_contains(out, cases[k].message));
        // info refuses what a run would.
        status = ensure_shell(out, sizeof out, "cd '%s' && '%s/weathering' info s.xml --out o "
                              "--stats '%s'", d, build_dir(), cases[k].stats);
        ENSURE(status == 2);
        ENSURE(ensure_contains(out, cases[k].message));
    }
    // Nothing was written: the inputs are unchanged, the folder holds only the
    // user's file, the link still points at /dev/null.
    ENSURE(ensure_shell(NULL, 0,
                        "cd '%s' && cksum s.xml meshes/teapot.obj | cmp - ../stats.sum && "
                        "[ \"$(ls -A o)\" = mask.exr ] && [ \"$(cat o/mask.exr)\" = keep ] && "
                        "[ \"$(readlink link.json)\" = /dev/null ]",
                        d) == 0);
    // A new file in the output folder (made by the run) is fine.
    ENSURE(ensure_shell(out, sizeof out, "cd '%s' && '%s/weathering' info s.xml --out new "
                        "--stats new/stats.json", d, build_dir()) == 0);
    ENSURE(ensure_contains(out, "statistics: new/stats.json (written by bake, simulate, gather "
                                "and run; info writes nothing)\n"));
}

// The cleanup of killed runs' temporaries touches only this program's own
// output names, and a scene called "...xml" still writes inside out/.
TEST(stale_cleanup_and_default_folder_stay_in_their_place)
{
    SLOW();
    const char *d = teapot_copy("stale");
    ENSURE(d != NULL);
    ENSURE(ensure_shell(NULL, 0,
                        "cd '%s' && mkdir -p out/s && "
                        "echo draft > out/s/.draft.txt.tmp999999998 && "
                        "echo dead > out/s/.mask.exr.tmp999999997 && "
                        "sed -e 's/teapot.obj/..\\/meshes\\/teapot.obj/' s.xml > ...xml",
                        d) == 0);
    ENSURE(ensure_shell(out, sizeof out, "cd '%s' && '%s/weathering' bake s.xml -q", d,
                        build_dir()) == 0);
    ENSURE(ensure_shell(NULL, 0, "cd '%s/out/s' && [ -e .draft.txt.tmp999999998 ] && "
                                 "[ ! -e .mask.exr.tmp999999997 ]", d) == 0);
    ENSURE(ensure_shell(out, sizeof out, "cd '%s' && '%s/weathering' info ...xml", d,
                        build_dir()) == 0);
    ENSURE(ensure_contains(out, "output folder: out/__\n"));
    // The --stats file's temporary is ours too when --stats names a file in the
    // output folder, relative or absolute, through a different spelling.
    ENSURE(ensure_shell(NULL, 0, "cd '%s' && echo dead > out/s/.notes.json.tmp999999996 && "
                                 "echo dead > out/s/.abs.json.tmp999999995", d) == 0);
    ENSURE(ensure_shell(out, sizeof out, "cd '%s' && '%s/weathering' bake s.xml -q "
                        "--stats out/s/notes.json && '%s/weathering' bake s.xml -q --out out/s "
                        "--stats \"$PWD/out/./s/abs.json\"", d, build_dir(), build_dir()) == 0);
    ENSURE(ensure_shell(NULL, 0, "cd '%s/out/s' && [ ! -e .notes.json.tmp999999996 ] && "
                                 "[ ! -e .abs.json.tmp999999995 ] && [ -e notes.json ] && "
                                 "[ -e .draft.txt.tmp999999998 ]", d) == 0);
}

// --out and --stats longer than a path may be are refused, not cut (issue 13).
TEST(overlong_paths_are_refused)
{
    char *args = malloc(10000);
    ENSURE(args != NULL);
    int n = snprintf(args, 10000, "info xml_scenes/thesis_box.xml --out ");
    memset(args + n, 'a', 5000);
    args[n + 5000] = '\0';
    int status = weathering(args);
    snprintf(args, 10000, "info xml_scenes/thesis_box.xml --stats ");
    n = (int)strlen(args);
    memset(args + n, 'b', 4200);
    args[n + 4200] = '\0';
    int stats_status = weathering(args);
    free(args);
    ENSURE(status == 2);
    ENSURE(stats_status == 2);
    ENSURE(ensure_contains(out, "--stats: a file name of at most 4095 characters"));
}

// Text from files is echoed escaped: a mesh's material name with ESC and BEL
// cannot colour the terminal or fake a line (issue 13).
TEST(control_characters_from_files_are_escaped)
{
    const char *d = teapot_copy("escape");
    ENSURE(d != NULL);
    ENSURE(ensure_shell(NULL, 0,
                        "cd '%s' && printf 'newmtl red\\033[31m\\a\\n' > meshes/m.mtl && "
                        "(printf 'mtllib m.mtl\\nusemtl red\\033[31m\\a\\n'; "
                        "cat meshes/teapot.obj) > meshes/t.obj && "
                        "sed -e 's|teapot.obj|t.obj|' -e 's|material=\"\\*\"|material=\"x\"|' "
                        "s.xml > esc.xml",
                        d) == 0);
    int status = ensure_shell(out, sizeof out, "cd '%s' && '%s/weathering' info esc.xml", d,
                              build_dir());
    ENSURE(status == 2);
    ENSURE(ensure_contains(out, "material 'red\\x1b[31m\\x07' that no <Surface> matches"));
    ENSURE(strchr(out, '\033') == NULL && strchr(out, '\a') == NULL);
    ENSURE(strchr(out, '\n') == out + strlen(out) - 1);
}

// info's pilot says what share of the particles a run wastes: a sky dome of
// radius 12 over the teapot (as the scene had before its box emitter) misses the
// pot with about 90% of them; the run's --stats agree within two points (the
// pilot's 20000 particles give a standard error of 0.2).
TEST(info_pilot_predicts_the_particles_that_miss)
{
    SLOW();
    const char *d = teapot_copy("pilot");
    ENSURE(d != NULL);
    char scene[4300];
    snprintf(scene, sizeof scene, "%s/s.xml", d);
    char *xml = ensure_read_file(scene);
    ENSURE(xml != NULL);
    char *box = strstr(xml, "<BoxEmitter"), *end = box != NULL ? strstr(box, "/>") : NULL;
    bool replaced = end != NULL;
    if (replaced) {
        char *dome = malloc(strlen(xml) + 512);
        snprintf(dome, strlen(xml) + 512, "%.*s<HemisphereEmitter name=\"sky\" radius=\"12\" "
                 "rate=\"150000\" end=\"2\" speed=\"4\" maxCollisions=\"150\"/>%s",
                 (int)(box - xml), xml, end + 2);
        ensure_write_file(d, "s.xml", dome);
        free(dome);
    }
    free(xml);
    ENSURE(replaced);
    ENSURE(ensure_shell(out, sizeof out, "cd '%s' && '%s/weathering' info s.xml", d,
                        build_dir()) == 0);
    const char *line = strstr(out, "pilot: 20000 particles");
    ENSURE(line != NULL);
    const char *pct = strstr(line, "a side: ");
    ENSURE(pct != NULL);
    double predicted = atof(pct + strlen("a side: "));
    ENSURE(ensure_contains(line, "over half: aim the emitters at the model"));
    int status = ensure_shell(out, sizeof out, "cd '%s' && '%s/weathering' run s.xml --stats "
                              "s.json", d, build_dir());
    ENSURE(status == 0);
    ENSURE(ensure_contains(out, "left the bounding box without hitting anything"));
    char path[4300];
    snprintf(path, sizeof path, "%s/s.json", d);
    char *json = ensure_read_file(path);
    ENSURE(json != NULL);
    static const char emitted_key[] = "\"particles_emitted\": ";
    static const char missed_key[] = "\"escaped_without_hit\": ";
    const char *emitted = strstr(json, emitted_key), *missed = strstr(json, missed_key);
    bool found = emitted != NULL && missed != NULL;
    double actual = found ? 100.0 * atof(missed + sizeof missed_key - 1) /
                                atof(emitted + sizeof emitted_key - 1)
                          : -1.0;
    free(json);
    ENSURE(found);
    printf("        pilot %.1f%%, run %.1f%% of the particles escaped without a hit\n",
           predicted, actual);
    ENSURE(predicted > 50.0);
    ENSURE_NEAR(predicted, actual, 2.0);
}

// A --stats share, in percent of the particles emitted.
static double stats_share(const char *json, const char *key)
{
    static const char emitted_key[] = "\"particles_emitted\": ";
    const char *emitted = strstr(json, emitted_key), *at = strstr(json, key);
    return emitted != NULL && at != NULL
               ? 100.0 * atof(at + strlen(key)) / atof(emitted + sizeof emitted_key - 1)
               : -1.0;
}

// The pilot flies every iteration, as the run does: particles still flying at
// the end of one fly on into the next. After the first of four iterations of
// 1.5 s no drop has yet fallen out of the teapot's box and most of those that
// hit still slide on the pot: a pilot of the first iteration alone said 0%
// wasted and 100% still flying, where the run ends with 37% and 33%.
TEST(info_pilot_flies_every_iteration)
{
    SLOW();
    const char *d = teapot_copy("pilot_iterations");
    ENSURE(d != NULL);
    ENSURE(ensure_shell(NULL, 0,
                        "cd '%s' && sed -i 's/steps=\"[0-9]*\" seed=\"1\"/steps=\"150\" seed=\"1\" "
                        "iterations=\"4\"/; s/rate=\"150000\"/rate=\"10000\"/' s.xml && "
                        "grep -q 'iterations=\"4\"' s.xml && grep -q 'rate=\"10000\"' s.xml",
                        d) == 0);
    ENSURE(ensure_shell(out, sizeof out, "cd '%s' && '%s/weathering' info s.xml", d, build_dir()) ==
           0);
    const char *line = strstr(out, "pilot: ");
    ENSURE(line != NULL);
    const char *missed = strstr(line, "a side: "), *flying = strstr(line, "hit, ");
    ENSURE(missed != NULL && flying != NULL);
    double predicted_missed = atof(missed + strlen("a side: "));
    double predicted_flying = atof(flying + strlen("hit, "));
    ENSURE(ensure_shell(out, sizeof out, "cd '%s' && '%s/weathering' run s.xml -q --stats s.json",
                        d, build_dir()) == 0);
    char path[4300];
    snprintf(path, sizeof path, "%s/s.json", d);
    char *json = ensure_read_file(path);
    ENSURE(json != NULL);
    double missed_share = stats_share(json, "\"escaped_without_hit\": ");
    double flying_share = stats_share(json, "\"alive\": ");
    free(json);
    printf("        pilot %.1f%% wasted, %.1f%% still flying; run %.1f%%, %.1f%%\n",
           predicted_missed, predicted_flying, missed_share, flying_share);
    ENSURE(missed_share >= 0.0 && flying_share >= 0.0);
    ENSURE_NEAR(predicted_missed, missed_share, 2.0);
    ENSURE_NEAR(predicted_flying, flying_share, 2.0);
}

// The summary (on stdout, issue 24) tells the particles that hit from those
// that left or are still flying: the thesis box simulated for 0.2 s, its cloud
// 4 m above the cube, hits nothing and ends with every particle in the air.
// Diagnostics (the warning) go to stderr, the summary to stdout.
TEST(summary_tells_hits_from_particles_still_flying)
{
    char maps[4200];
    ENSURE(realpath(ensure_tests_dir(), maps) != NULL);
    strcat(maps, "/../maps/");
    char path[4300];
    snprintf(path, sizeof path, "%s/../xml_scenes/thesis_box.xml", ensure_tests_dir());
    char *xml = ensure_read_file(path);
    ENSURE(xml != NULL);
    char *solver = strstr(xml, "  </Solver>");
    ENSURE(solver != NULL);
    size_t cap = strlen(xml) * 2 + 8192;
    char *scene = malloc(cap);
    size_t n = (size_t)snprintf(scene, cap, "%.*s    <Simulation steps=\"20\"/>\n",
                                (int)(solver - xml), xml);
    for (const char *c = solver; *c != '\0' && n + 4200 < cap;) {
        if (strncmp(c, "../maps/", 8) == 0) {
            n += (size_t)snprintf(scene + n, cap - n, "%s", maps);
            c += 8;
        } else {
            scene[n++] = *c++;
        }
    }
    scene[n] = '\0';
    free(xml);
    const char *d = ensure_tmpdir();
    ensure_write_file(d, "flying.xml", scene);
    free(scene);
    ENSURE(ensure_shell(out, sizeof out, "cd '%s' && '%s/weathering' run flying.xml --out fly "
                        "2>/dev/null", d, build_dir()) == 0);
    ENSURE(ensure_contains(out, "run done in"));
    ENSURE(ensure_contains(out, "4000 emitted: 0.0% hit the model, 0.0% left without a hit, "
                                "100.0% still flying without a hit; 0 hits; 4000 (100.0%) still "
                                "flying at the end"));
    ENSURE(strstr(out, "warning") == NULL);
    ENSURE(ensure_shell(out, sizeof out, "cd '%s' && '%s/weathering' run flying.xml --out fly "
                        ">/dev/null", d, build_dir()) == 0);
    ENSURE(strstr(out, "done in") == NULL);
    ENSURE(ensure_contains(out, "100% of the particles (4000 of 4000) are still flying when the "
                                "simulation ends, 4000 of them before any hit"));
}

// Whether the entry of the "noise" object of --stats file NAME (in the tests'
// folder) that begins with `anchor` holds a note's figures (percent, as the
// note rounds them) unrounded: its capped_noise_median and capped_share.
static bool noise_entry_matches_note(const char *name, const char *anchor, double noise,
                                     double share)
{
    char path[4300];
    snprintf(path, sizeof path, "%s/%s", ensure_tmpdir(), name);
    char *json = ensure_read_file(path);
    const char *entry = json != NULL ? strstr(json, anchor) : NULL;
    const char *median = entry != NULL ? strstr(entry, "\"capped_noise_median\": ") : NULL;
    const char *capped = entry != NULL ? strstr(entry, "\"capped_share\": ") : NULL;
    double stats_noise = median != NULL ? atof(median + 23) : -1.0;
    double stats_share = capped != NULL ? atof(capped + 16) : -1.0;
    free(json);
    printf("        --stats: capped_share %.4f, capped_noise_median %.5f\n", stats_share,
           stats_noise);
    return entry != NULL && fabs(100.0 * stats_noise - noise) <= 0.051 &&
           fabs(100.0 * stats_share - share) <= 0.51;
}

// The gather's note on a mask the smoothing could not make as quiet as asked
// says how noisy it stays there (docs/mask.md, "Notes it prints"): on the
// thesis box 77% of the mask holds fewer impacts than 4% needs, and keeps
// about 6.2% (the median over those texels).
TEST(the_capped_note_says_how_noisy_the_mask_stays)
{
    ENSURE(ensure_shell(out, sizeof out,
                        "cd '%s/..' && '%s/weathering' run xml_scenes/thesis_box.xml --out "
                        "'%s/capped' --stats '%s/capped.json' 2>&1 >/dev/null",
                        ensure_tests_dir(), build_dir(), ensure_tmpdir(), ensure_tmpdir()) == 0);
    static const char lead[] = "that 4% noise needs: its noise there is about ";
    const char *at = strstr(out, lead);
    ENSURE(at != NULL);
    double noise = at != NULL ? atof(at + strlen(lead)) : 0.0;
    printf("        the note: ...%s", at != NULL ? at : "(none)\n");
    ENSURE(noise > 4.0 && noise < 20.0);
    ENSURE(ensure_contains(out, "% (the median); where that shows, fly more particles or "
                                "raise maxRadius\n"));
    static const char share_lead[] = "weathering: note: gather: ";
    const char *share_at = strstr(out, share_lead);
    ENSURE(share_at != NULL);
    double share = atof(share_at + strlen(share_lead));
    // --stats holds the same figures, unrounded, under "noise" and the mask's
    // file name.
    ENSURE(noise_entry_matches_note("capped.json",
                                    "\"noise\": {\n    \"thesis_box_mask.exr\": { \"aim\": 0.04, "
                                    "\"impacts_aimed_at\": 937.5, ",
                                    noise, share));
}

// A TextureMap says the same of its own smoothing, which runs on the input
// cameras' texels with their own largest radius: Spot's dust texture, over the
// first substance's capped texels of all five cameras (their noise merged in
// bins of a 32nd of an octave).
TEST(the_capped_note_says_how_noisy_the_texture_stays)
{
    SLOW();
    ENSURE(ensure_shell(out, sizeof out,
                        "cd '%s/..' && '%s/weathering' run xml_scenes/spot.xml --out "
                        "'%s/capped_texture' --stats '%s/capped_texture.json' 2>&1 >/dev/null",
                        ensure_tests_dir(), build_dir(), ensure_tmpdir(), ensure_tmpdir()) == 0);
    // The texture's capped note (its coverage note comes first).
    static const char lead[] = "note: texture spot_texture.exr: ";
    const char *at = strstr(out, lead);
    while (at != NULL) {
        const char *rest = at + strlen(lead), *pct = strchr(rest, '%');
        if (pct != NULL && pct - rest < 8 && strncmp(pct, "% of the surface", 16) == 0) {
            break;
        }
        at = strstr(rest, lead);
    }
    ENSURE(at != NULL);
    printf("        the note: ...%s", at != NULL ? at : "(none)\n");
    double share = at != NULL ? atof(at + strlen(lead)) : 0.0;
    ENSURE(share > 10.0 && share < 100.0);
    ENSURE(ensure_contains(at, "% of the surface its input cameras see holds fewer than the 938 "
                               "impacts within maxRadius (16 texels of each input camera) that "
                               "4% noise needs: its noise there is about "));
    static const char about[] = "its noise there is about ";
    const char *n = at != NULL ? strstr(at, about) : NULL;
    double noise = n != NULL ? atof(n + strlen(about)) : 0.0;
    ENSURE(noise > 4.0 && noise < 30.0);
    ENSURE(ensure_contains(at, "% (the median); where that shows, fly more particles or raise "
                               "the TextureMap's maxRadius\n"));
    // --stats: the texture's entry, after the mask's, with the note's figures.
    ENSURE(noise_entry_matches_note("capped_texture.json",
                                    " },\n    \"spot_texture.exr\": { \"aim\": 0.04, "
                                    "\"impacts_aimed_at\": 937.5, ",
                                    noise, share));
}

// Spot (closed) with every face wound the other way, in the teapot's scene:
// its OBJ has no normals, so the generated ones point in. info says the
// import turned it outwards, naming the scene line and the mesh; -q keeps
// quiet; the teapot (open: no inside to speak of) is left as it is.
TEST(a_mesh_wound_inwards_is_turned_with_a_note)
{
    const char *d = teapot_copy("inward");
    ENSURE(d != NULL);
    ENSURE(ensure_shell(NULL, 0,
                        "awk '/^f /{printf \"f\"; for (i = NF; i >= 2; i--) "
                        "printf \" %%s\", $i; print \"\"; next} {print}' "
                        "xml_scenes/meshes/spot.obj > '%s/meshes/inward.obj' && "
                        "sed -e 's|teapot.obj|inward.obj|' '%s/s.xml' > '%s/in.xml'",
                        d, d, d) == 0);
    int status = ensure_shell(out, sizeof out, "cd '%s' && '%s/weathering' info in.xml", d,
                              build_dir());
    ENSURE(status == 0);
    ENSURE(ensure_contains(out, "in.xml:"));
    ENSURE(ensure_contains(out, ": 1 closed part with normals"));
    ENSURE(ensure_contains(out, "with normals pointing inwards (flipped on export?) turned "
                                "outwards, as renderers show it"));
    status = ensure_shell(out, sizeof out, "cd '%s' && '%s/weathering' info in.xml -q", d,
                          build_dir());
    ENSURE(status == 0);
    ENSURE(strstr(out, "inwards") == NULL);
    // The teapot as shipped is left as it is.
    status = ensure_shell(out, sizeof out, "cd '%s' && '%s/weathering' info s.xml", d,
                          build_dir());
    ENSURE(status == 0);
    ENSURE(strstr(out, "inwards") == NULL);
}

int main(void)
{
    RUN(help_lists_commands_and_options);
    RUN(version);
    RUN(no_command_is_a_usage_error);
    RUN(unknown_command_and_option);
    RUN(option_values_are_checked);
    RUN(missing_scene_names_the_file);
    RUN(info_summarises_the_default_scene);
    RUN(info_lists_substances_loads_exchanges_and_rules);
    RUN(info_estimates_a_sequence_of_100000_frames);
    RUN(info_on_a_bad_scene_gives_file_line_and_status_2);
    RUN(an_absurd_emission_rate_is_refused_not_a_crash);
    RUN(stats_never_overwrites_anything);
    RUN(stale_cleanup_and_default_folder_stay_in_their_place);
    RUN(overlong_paths_are_refused);
    RUN(control_characters_from_files_are_escaped);
    RUN(info_pilot_predicts_the_particles_that_miss);
    RUN(info_pilot_flies_every_iteration);
    RUN(summary_tells_hits_from_particles_still_flying);
    RUN(a_mesh_wound_inwards_is_turned_with_a_note);
    RUN(the_capped_note_says_how_noisy_the_mask_stays);
    RUN(the_capped_note_says_how_noisy_the_texture_stays);
    return ensure_summary();
}
