// test_cli.c: the `weathering` command line: options, exit statuses, messages.
#include <stdlib.h>
#include <string.h>

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
    // 200000 particles/s for 4 s.
    ENSURE(ensure_contains(out, "800000 particles"));
    ENSURE(ensure_contains(out, "seed 7"));
    ENSURE(ensure_contains(out, "output folder: /tmp/x"));
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

int main(void)
{
    RUN(help_lists_commands_and_options);
    RUN(version);
    RUN(no_command_is_a_usage_error);
    RUN(unknown_command_and_option);
    RUN(option_values_are_checked);
    RUN(missing_scene_names_the_file);
    RUN(info_summarises_the_default_scene);
    RUN(info_on_a_bad_scene_gives_file_line_and_status_2);
    return ensure_summary();
}
