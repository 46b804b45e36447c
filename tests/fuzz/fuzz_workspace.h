// fuzz_workspace.h: a temporary folder for the fuzz targets, laid out so that the
// relative paths of the seed scenes resolve (docs/reliability.md):
//
//   T/maps   -> maps/            (xml_scenes/*.xml name ../maps/...)
//   T/data   -> tests/data/      (tests/bad/*.xml name ../data/...)
//   T/s/maps -> tests/bad/maps/  (tests/bad/*.xml name maps/...)
//   T/s/meshes -> xml_scenes/meshes/, T/s/<each file of tests/data/>
//
// and the input is written to T/s/<name>. Run from the repository's root.
#ifndef WX_FUZZ_WORKSPACE_H
#define WX_FUZZ_WORKSPACE_H

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char fuzz_root[4096];
static char fuzz_input[4200];

static void fuzz_link(const char *target, const char *link_path)
{
    char full[4096];
    if (realpath(target, full) != NULL) {
        if (symlink(full, link_path) != 0) {
            perror(link_path);
        }
    }
}

static void fuzz_cleanup(void)
{
    char command[4200];
    snprintf(command, sizeof command, "rm -rf '%s'", fuzz_root);
    if (fuzz_root[0] != '\0' && system(command) != 0) {
        fprintf(stderr, "cannot remove %s\n", fuzz_root);
    }
}

// Makes the workspace; the input file is T/s/`name`.
static void fuzz_workspace(const char *name)
{
    snprintf(fuzz_root, sizeof fuzz_root, "/tmp/wx_fuzz_XXXXXX");
    if (mkdtemp(fuzz_root) == NULL) {
        perror("mkdtemp");
        exit(1);
    }
    atexit(fuzz_cleanup);
    char path[4200];
    snprintf(path, sizeof path, "%s/s", fuzz_root);
    mkdir(path, 0777);
    snprintf(path, sizeof path, "%s/maps", fuzz_root);
    fuzz_link("maps", path);
    snprintf(path, sizeof path, "%s/data", fuzz_root);
    fuzz_link("tests/data", path);
    snprintf(path, sizeof path, "%s/s/maps", fuzz_root);
    fuzz_link("tests/bad/maps", path);
    snprintf(path, sizeof path, "%s/s/meshes", fuzz_root);
    fuzz_link("xml_scenes/meshes", path);
    DIR *dir = opendir("tests/data");
    struct dirent *entry;
    while (dir != NULL && (entry = readdir(dir)) != NULL) {
        if (entry->d_name[0] == '.') {
            continue;
        }
        char target[4200];
        snprintf(target, sizeof target, "tests/data/%s", entry->d_name);
        snprintf(path, sizeof path, "%s/s/%s", fuzz_root, entry->d_name);
        fuzz_link(target, path);
    }
    if (dir != NULL) {
        closedir(dir);
    }
    snprintf(fuzz_input, sizeof fuzz_input, "%s/s/%s", fuzz_root, name);
}

// Writes the fuzzer's input to the input file.
static void fuzz_write_input(const uint8_t *data, size_t size)
{
    FILE *f = fopen(fuzz_input, "wb");
    if (f == NULL || fwrite(data, 1, size, f) != size || fclose(f) != 0) {
        perror(fuzz_input);
        abort();
    }
}

#endif
