// exr_internal.h: what the two files of the EXR io share (exr.c reads, and
// holds the stream both use; exr_write.c writes): the stream over our own file
// descriptor, where the library's messages are collected. Private to src/io/.
#ifndef WX_EXR_INTERNAL_H
#define WX_EXR_INTERNAL_H

#include <stdbool.h>
#include <stdint.h>

#include <openexr.h>

// Stream: our file descriptor, plus what went wrong (errno, library message).
typedef struct exr_stream {
    int fd;
    int io_errno;      // errno of the first failed read or write, 0 if none
    char message[512]; // first library message since the last stream_reset
    // While chunks are decoded on several threads nothing is recorded (a
    // failure is decoded again on one thread, which records it).
    bool quiet;
} exr_stream;

// Forgets what went wrong (before the next call into the library).
void wx_exr_stream_reset(exr_stream *s);

// Binds `s` to the calling thread (the error handler records its messages
// there); returns the stream bound before, for wx_exr_stream_unbind.
exr_stream *wx_exr_stream_bind(exr_stream *s);
void wx_exr_stream_unbind(exr_stream *outer);

// The library's error handler (records into the bound stream).
void wx_exr_stream_on_error(exr_const_context_t ctxt, exr_result_t code, const char *msg);

// The library's write callback on the stream's file.
int64_t wx_exr_stream_write(exr_const_context_t ctxt, void *user, const void *buffer, uint64_t size,
                            uint64_t offset, exr_stream_error_func_ptr_t error_cb);

// What went wrong: errno's text, the library's message or its default for rv.
const char *wx_exr_stream_detail(const exr_stream *s, exr_result_t rv);

#endif
