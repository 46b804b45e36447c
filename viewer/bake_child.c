// bake_child.c: `weathering bake` in a child process (bake_child.h).
#include "bake_child.h"
#include "core/limits.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <stdio.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

bool vw_executable_dir(const char *argv0, char dir[WX_PATH_MAX])
{
    ssize_t n = readlink("/proc/self/exe", dir, WX_PATH_MAX - 1);
    if (n > 0) {
        dir[n] = '\0';
    } else if (argv0 != NULL && strchr(argv0, '/') != NULL && strlen(argv0) < WX_PATH_MAX) {
        snprintf(dir, WX_PATH_MAX, "%s", argv0);
    } else {
        return false;
    }
    char *slash = strrchr(dir, '/');
    if (slash == NULL) {
        return false;
    }
    if (slash == dir) {
        slash[1] = '\0';
    } else {
        *slash = '\0';
    }
    return true;
}

wx_result vw_bake_start(vw_bake_child *child, const char *exe_dir, const char *scene_path,
                        const char *out_dir, wx_error *err)
{
    memset(child, 0, sizeof *child);
    child->stderr_fd = -1;
    char program[WX_PATH_MAX + 16];
    int n = snprintf(program, sizeof program, "%s/weathering", exe_dir);
    if (n < 0 || n >= (int)sizeof program || access(program, X_OK) != 0) {
        return wx_fail(err, WX_CAUSE_IO,
                       "%s: the scene has maps to bake, and %s is missing; run `weathering "
                       "bake %s --out %s` first",
                       scene_path, program, scene_path, out_dir);
    }
    int fds[2];
    if (pipe(fds) != 0) {
        return wx_fail(err, WX_CAUSE_IO, "cannot start the bake: %s", strerror(errno));
    }
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[1], STDERR_FILENO);
    posix_spawn_file_actions_addclose(&actions, fds[0]);
    posix_spawn_file_actions_addclose(&actions, fds[1]);
    char *argv[] = { program, "bake", (char *)scene_path, "--out", (char *)out_dir, "-q", NULL };
    pid_t pid = 0;
    int rc = posix_spawn(&pid, program, &actions, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&actions);
    close(fds[1]);
    if (rc != 0) {
        close(fds[0]);
        return wx_fail(err, WX_CAUSE_IO, "cannot run %s: %s", program, strerror(rc));
    }
    fcntl(fds[0], F_SETFL, fcntl(fds[0], F_GETFL) | O_NONBLOCK);
    fcntl(fds[0], F_SETFD, FD_CLOEXEC);
    child->pid = pid;
    child->stderr_fd = fds[0];
    return WX_OK;
}

// Passes the child's bytes on to our stderr and remembers its last line.
static void take_output(vw_bake_child *child, const char *bytes, size_t count)
{
    fwrite(bytes, 1, count, stderr);
    for (size_t k = 0; k < count; ++k) {
        char ch = bytes[k];
        if (ch == '\n' || ch == '\r') {
            if (child->partial_len > 0) {
                memcpy(child->last_line, child->partial, child->partial_len);
                child->last_line[child->partial_len] = '\0';
                child->partial_len = 0;
            }
        } else if (child->partial_len + 1 < sizeof child->partial) {
            child->partial[child->partial_len++] = ch;
        }
    }
}

// Reads until the pipe is empty (or, with `wait`, closed). True at end of file.
static bool drain(vw_bake_child *child, bool wait)
{
    char buf[4096];
    while (child->stderr_fd >= 0) {
        ssize_t n = read(child->stderr_fd, buf, sizeof buf);
        if (n > 0) {
            take_output(child, buf, (size_t)n);
            continue;
        }
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n < 0 && errno == EAGAIN && wait) {
            struct pollfd p = { .fd = child->stderr_fd, .events = POLLIN };
            poll(&p, 1, 100);
            continue;
        }
        if (n < 0 && errno == EAGAIN) {
            return false;
        }
        close(child->stderr_fd); // end of file or error
        child->stderr_fd = -1;
        if (child->partial_len > 0) {
            memcpy(child->last_line, child->partial, child->partial_len);
            child->last_line[child->partial_len] = '\0';
            child->partial_len = 0;
        }
    }
    return true;
}

bool vw_bake_poll(vw_bake_child *child, bool wait, int *status)
{
    if (child->pid <= 0) {
        *status = 1;
        return true;
    }
    drain(child, wait);
    int ws = 0;
    pid_t r;
    do {
        r = waitpid(child->pid, &ws, wait ? 0 : WNOHANG);
    } while (r < 0 && errno == EINTR);
    if (r == 0) {
        return false;
    }
    drain(child, true); // whatever it wrote last (grandchildren aside, the pipe closes)
    child->pid = 0;
    *status = r > 0 && WIFEXITED(ws) ? WEXITSTATUS(ws) : 1;
    return true;
}

void vw_bake_cancel(vw_bake_child *child)
{
    if (child->pid > 0) {
        kill(child->pid, SIGTERM);
        int ws;
        while (waitpid(child->pid, &ws, 0) < 0 && errno == EINTR) {
        }
        child->pid = 0;
    }
    if (child->stderr_fd >= 0) {
        close(child->stderr_fd);
        child->stderr_fd = -1;
    }
}
