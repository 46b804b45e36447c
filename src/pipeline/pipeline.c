// pipeline.c: the run's options and their defaults (pipeline.h).
#include "pipeline/pipeline.h"

#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "core/parallel.h"

void wx_default_out_name(const char *scene_name, char *out, size_t cap)
{
    size_t n = 0;
    bool leading = true;
    for (const char *c = scene_name; *c != '\0' && n + 1 < cap; ++c) {
        bool plain = (*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') ||
                     (*c >= '0' && *c <= '9') || *c == '_' || *c == '-' || *c == '.';
        out[n++] = plain && !(leading && *c == '.') ? *c : '_';
        leading = leading && *c == '.';
    }
    out[n] = '\0';
    if (n == 0) {
        snprintf(out, cap, "scene");
    }
}

wx_run_def wx_default_run_def(const wx_scene *scene)
{
    wx_run_def def;
    memset(&def, 0, sizeof def);
    char name[sizeof scene->name];
    wx_default_out_name(scene->name, name, sizeof name);
    snprintf(def.out_dir, sizeof def.out_dir, "out/%s", name);
    def.seed = scene->seed;
    def.threads = wx_cpu_count();
    return def;
}

