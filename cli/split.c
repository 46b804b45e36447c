// split.c: `weathering split FILE.exr`: every channel of an EXR as a file of
// its own (pipeline/split.h); the written paths on stdout.
#include "cli.h"

#include <stdio.h>

#include "pipeline/split.h"

static void print_written(const char *path, void *context)
{
    (void)context;
    printf("%s\n", path);
}

// Every channel of an EXR as a single-channel file BASE_NAME.exr (split.h);
// prints the written paths on stdout.
int command_split(const cli_args *args)
{
    wx_split_def def = { .input = args->scene_path,
                         .out_dir = args->out_dir,
                         .on_written = print_written };
    wx_error err;
    wx_result r = wx_split_exr(&def, &err);
    return cli_report(r, &err);
}
