// atomic_file.c: temporary names, fsync and rename.
#include "atomic_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

void wx_temp_path(const char *path, char tmp[WX_PATH_MAX])
{
    const char *slash = strrchr(path, '/');
    int folder_len = slash != NULL ? (int)(slash - path) + 1 : 0;
    const char *base = path + folder_len;
    snprintf(tmp, WX_PATH_MAX, "%.*s.%s.tmp%ld", folder_len, path, base, (long)getpid());
}

wx_result wx_atomic_commit(const char *tmp, const char *path, wx_error *err)
{
    int fd = open(tmp, O_RDONLY);
    if (fd < 0 || fsync(fd) != 0) {
        int saved = errno;
        if (fd >= 0) {
            close(fd);
        }
        unlink(tmp);
        return wx_error_set(err, WX_FAIL, "%s: cannot write (%s)", path, strerror(saved));
    }
    close(fd);
    if (rename(tmp, path) != 0) {
        int saved = errno;
        unlink(tmp);
        return wx_error_set(err, WX_FAIL, "%s: cannot write (%s)", path, strerror(saved));
    }
    return WX_OK;
}

wx_result wx_write_file_atomic(const char *path, const void *data, size_t size, wx_error *err)
{
    char tmp[WX_PATH_MAX];
    wx_temp_path(path, tmp);
    FILE *f = fopen(tmp, "wb");
    if (f == NULL) {
        return wx_error_set(err, WX_FAIL, "%s: cannot write (%s)", path, strerror(errno));
    }
    size_t written = fwrite(data, 1, size, f);
    int closed = fclose(f);
    if (written != size || closed != 0) {
        int saved = errno;
        unlink(tmp);
        return wx_error_set(err, WX_FAIL, "%s: cannot write (%s)", path, strerror(saved));
    }
    return wx_atomic_commit(tmp, path, err);
}
