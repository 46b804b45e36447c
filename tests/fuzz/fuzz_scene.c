// fuzz_scene.c: libFuzzer target for scene files: parse and validate
// (wx_scene_load), then the memory estimate. Every input must either load or
// give WX_BAD_INPUT with one message that names the scene file; anything else
// (a crash, a sanitizer report, another result) is a finding.
#define _XOPEN_SOURCE 700 // realpath, mkdtemp
#include <stdint.h>
#include <string.h>

#include "core/error.h"
#include "fuzz_workspace.h"
#include "pipeline/pipeline.h"
#include "model/scene.h"
#include "io/scene_xml.h"
#include "pipeline/memory.h"

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    fuzz_workspace("scene.xml");
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_write_input(data, size);
    wx_scene scene;
    wx_error err;
    memset(&err, 0, sizeof err);
    wx_result r = wx_scene_load(fuzz_input, &scene, &err);
    if (r == WX_OK) {
        wx_memory_need need;
        wx_memory_estimate(&scene, WX_PHASE_ALL, &need);
        if (scene.camera_count < 1 || !(need.total_bytes >= 0.0)) {
            __builtin_trap();
        }
    } else if (r != WX_BAD_INPUT || strstr(err.message, fuzz_input) == NULL ||
               strchr(err.message, '\n') != NULL) {
        fprintf(stderr, "result %d, message: %s\n", (int)r, err.message);
        __builtin_trap();
    }
    wx_scene_free(&scene);
    return 0;
}
