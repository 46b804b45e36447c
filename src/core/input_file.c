// input_file.c: regular files only, opened without blocking (see input_file.h).
#include "core/input_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *kind_of(mode_t mode)
{
    if (S_ISDIR(mode)) {
        return "a folder";
    }
    if (S_ISFIFO(mode)) {
        return "a FIFO";
    }
    if (S_ISCHR(mode) || S_ISBLK(mode)) {
        return "a device";
    }
    if (S_ISSOCK(mode)) {
        return "a socket";
    }
    return "not a file";
}

// The reason for an errno of open() or stat().
static void set_cause(wx_cause *cause, wx_cause value)
{
    if (cause != NULL) {
        *cause = value;
    }
}

static void explain_errno(int e, char why[WX_INPUT_WHY_MAX], wx_cause *cause)
{
    set_cause(cause, e == ENOENT || e == ENOTDIR ? WX_CAUSE_FILE_MISSING
                     : e == ELOOP                ? WX_CAUSE_NOT_REGULAR_FILE
                                                 : WX_CAUSE_UNREADABLE);
    if (e == ELOOP) {
        snprintf(why, WX_INPUT_WHY_MAX, "is not a regular file (a loop of symbolic links)");
    } else {
        snprintf(why, WX_INPUT_WHY_MAX, "cannot open (%s)", strerror(e));
    }
}

static void explain_mode(mode_t mode, char why[WX_INPUT_WHY_MAX], wx_cause *cause)
{
    set_cause(cause, WX_CAUSE_NOT_REGULAR_FILE);
    snprintf(why, WX_INPUT_WHY_MAX, "is not a regular file (%s)", kind_of(mode));
}

int wx_open_regular(const char *path, char why[WX_INPUT_WHY_MAX], wx_cause *cause)
{
    // O_NONBLOCK: opening a FIFO without a writer, or a device, must not wait.
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
    if (fd < 0) {
        explain_errno(errno, why, cause);
        return -1;
    }
    struct stat st;
    if (fstat(fd, &st) != 0) {
        explain_errno(errno, why, cause);
        close(fd);
        return -1;
    }
    if (!S_ISREG(st.st_mode)) {
        explain_mode(st.st_mode, why, cause);
        close(fd);
        return -1;
    }
    int flags = fcntl(fd, F_GETFL);
    if (flags < 0 || fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) != 0) {
        explain_errno(errno, why, cause);
        close(fd);
        return -1;
    }
    set_cause(cause, WX_CAUSE_NONE);
    why[0] = '\0';
    return fd;
}

bool wx_is_regular_file(const char *path, char why[WX_INPUT_WHY_MAX], wx_cause *cause)
{
    struct stat st;
    if (stat(path, &st) != 0) {
        explain_errno(errno, why, cause);
        return false;
    }
    if (!S_ISREG(st.st_mode)) {
        explain_mode(st.st_mode, why, cause);
        return false;
    }
    set_cause(cause, WX_CAUSE_NONE);
    why[0] = '\0';
    return true;
}
