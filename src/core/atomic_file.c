// atomic_file.c: temporary names, fsync and rename, and the registry of
// temporaries that an interrupt removes.
#include "core/atomic_file.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

// The registry: a slot is in use when its flag is set; the path is complete
// before the flag is set, so a signal handler reading the flags never sees half
// a name. Slots are claimed and released under a mutex (several threads may
// write outputs); the handler takes no lock.
enum { TEMP_SLOTS = 64 };
static char temp_names[TEMP_SLOTS][WX_PATH_MAX];
static atomic_int temp_used[TEMP_SLOTS];
static pthread_mutex_t temp_lock = PTHREAD_MUTEX_INITIALIZER;

static void temp_remember(const char *tmp)
{
    pthread_mutex_lock(&temp_lock);
    int free_slot = -1;
    for (int i = 0; i < TEMP_SLOTS; ++i) {
        if (atomic_load(&temp_used[i])) {
            if (strcmp(temp_names[i], tmp) == 0) {
                pthread_mutex_unlock(&temp_lock);
                return; // already remembered
            }
        } else if (free_slot < 0) {
            free_slot = i;
        }
    }
    if (free_slot < 0) {
        // Full: release the slots of temporaries that no longer exist (a writer
        // that failed removes its temporary without wx_temp_forget).
        for (int i = 0; i < TEMP_SLOTS; ++i) {
            if (access(temp_names[i], F_OK) != 0) {
                atomic_store(&temp_used[i], 0);
                if (free_slot < 0) {
                    free_slot = i;
                }
            }
        }
    }
    if (free_slot >= 0) {
        snprintf(temp_names[free_slot], WX_PATH_MAX, "%s", tmp);
        atomic_store(&temp_used[free_slot], 1);
    }
    pthread_mutex_unlock(&temp_lock);
}

void wx_temp_forget(const char *tmp)
{
    pthread_mutex_lock(&temp_lock);
    for (int i = 0; i < TEMP_SLOTS; ++i) {
        if (atomic_load(&temp_used[i]) && strcmp(temp_names[i], tmp) == 0) {
            atomic_store(&temp_used[i], 0);
        }
    }
    pthread_mutex_unlock(&temp_lock);
}

void wx_temp_remove_all(void)
{
    for (int i = 0; i < TEMP_SLOTS; ++i) {
        if (atomic_load(&temp_used[i])) {
            unlink(temp_names[i]);
        }
    }
}

// Set by wx_temp_interrupt before its sweep. A writer checks it after creating
// its temporary: either the check comes first in the flag's order, and then
// the file already exists when the sweep runs, or it sees the flag and removes
// its own file.
static atomic_int temp_interrupted;

void wx_temp_interrupt(void)
{
    atomic_store(&temp_interrupted, 1);
    wx_temp_remove_all();
}

void wx_temp_created(const char *tmp)
{
    if (atomic_load(&temp_interrupted)) {
        unlink(tmp);
        for (;;) {
            pause(); // the handler's _exit ends the process
        }
    }
}

// True when `name` is ".<something>.tmp<digits>"; stores the digits as a pid and
// <something> in `base`.
static int temp_name_pid(const char *name, long *pid, char base[WX_PATH_MAX])
{
    if (name[0] != '.') {
        return 0;
    }
    const char *tag = NULL;
    for (const char *p = strstr(name, ".tmp"); p != NULL; p = strstr(p + 1, ".tmp")) {
        tag = p; // the last ".tmp"
    }
    if (tag == NULL || tag == name || tag[4] == '\0') {
        return 0;
    }
    char *end = NULL;
    errno = 0;
    long value = strtol(tag + 4, &end, 10);
    if (errno != 0 || *end != '\0' || value <= 0 || tag[4] < '0' || tag[4] > '9') {
        return 0;
    }
    *pid = value;
    snprintf(base, WX_PATH_MAX, "%.*s", (int)(tag - name - 1), name + 1);
    return 1;
}

int wx_temp_remove_stale(const char *folder, bool (*is_ours)(const char *name, void *context),
                         void *context)
{
    DIR *dir = opendir(folder);
    if (dir == NULL) {
        return 0;
    }
    int removed = 0;
    struct dirent *entry;
    while ((entry = readdir(dir)) != NULL) {
        long pid = 0;
        char base[WX_PATH_MAX];
        if (!temp_name_pid(entry->d_name, &pid, base) || !is_ours(base, context)) {
            continue;
        }
        // kill(pid, 0) fails with ESRCH when no such process runs; our own pid
        // is alive, so our own temporaries are never touched.
        if (kill((pid_t)pid, 0) == 0 || errno != ESRCH) {
            continue;
        }
        char path[WX_PATH_MAX];
        int n = snprintf(path, sizeof path, "%s/%s", folder, entry->d_name);
        if (n > 0 && n < (int)sizeof path && unlink(path) == 0) {
            removed++;
        }
    }
    closedir(dir);
    return removed;
}

void wx_temp_path(const char *path, char tmp[WX_PATH_MAX])
{
    const char *slash = strrchr(path, '/');
    int folder_len = slash != NULL ? (int)(slash - path) + 1 : 0;
    const char *base = path + folder_len;
    snprintf(tmp, WX_PATH_MAX, "%.*s.%s.tmp%ld", folder_len, path, base, (long)getpid());
    temp_remember(tmp);
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
        wx_temp_forget(tmp);
        return wx_fail(err, WX_CAUSE_IO, "%s: cannot write (%s)", path, strerror(saved));
    }
    close(fd);
    if (rename(tmp, path) != 0) {
        int saved = errno;
        unlink(tmp);
        wx_temp_forget(tmp);
        return wx_fail(err, WX_CAUSE_IO, "%s: cannot write (%s)", path, strerror(saved));
    }
    wx_temp_forget(tmp);
    return WX_OK;
}

wx_result wx_write_file_atomic(const char *path, const void *data, size_t size, wx_error *err)
{
    char tmp[WX_PATH_MAX];
    wx_temp_path(path, tmp);
    FILE *f = fopen(tmp, "wb");
    if (f == NULL) {
        wx_temp_forget(tmp);
        return wx_fail(err, WX_CAUSE_IO, "%s: cannot write (%s)", path, strerror(errno));
    }
    wx_temp_created(tmp);
    size_t written = fwrite(data, 1, size, f);
    int closed = fclose(f);
    if (written != size || closed != 0) {
        int saved = errno;
        unlink(tmp);
        wx_temp_forget(tmp);
        return wx_fail(err, WX_CAUSE_IO, "%s: cannot write (%s)", path, strerror(saved));
    }
    return wx_atomic_commit(tmp, path, err);
}
